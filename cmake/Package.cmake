# `cpack -G DEB` in a build configured with -DCMAKE_INSTALL_PREFIX=/usr: the package osgbtf
# (osgbtf_<version>_<arch>.deb) with everything `cmake --install` puts in place, under /usr:
# libosgBTF, libosgBTFFit, libosgBTFStreaming and libosgBTFEnvironment in /usr/lib/<multiarch>,
# the plugins in /usr/lib/<multiarch>/osgPlugins-<OSG version> (where Debian's OSG looks first,
# so stock osgviewer needs no OSG_LIBRARY_PATH), the tools in /usr/bin, the SDK (headers, CMake
# package, pkg-config files), and the Python module osgbtf in /usr/lib/python3/dist-packages when
# it is built. Library dependencies come from dpkg-shlibdeps (package dpkg-dev);
# the -dev packages the SDK's headers need are recommended.
# cpack installs from this build: it builds nothing that is not built already.
set(CPACK_PACKAGE_NAME osgbtf)
set(CPACK_PACKAGE_VENDOR osgBTF)
set(CPACK_PACKAGE_VERSION ${PROJECT_VERSION})
set(CPACK_PACKAGE_DESCRIPTION_SUMMARY
    "measured BTF materials for OpenSceneGraph: plugins, library, SDK and the btf tool")
set(CPACK_PACKAGE_DESCRIPTION
    "osgBTF renders measured Bidirectional Texture Functions in OpenSceneGraph: osgDB plugins for
fitted and measured BTFs (stock osgviewer and osgconv read them), libosgBTF with
osgBTF::MaterialNode, libosgBTFFit with the fitters and the fit cache, libosgBTFStreaming
with BSVTF streaming, libosgBTFEnvironment with environment lighting, their headers, CMake
package and pkg-config files, and the btf, btfviewer and btf-examples tools.")
set(CPACK_PACKAGE_CONTACT "osgBTF maintainers <osgbtf@localhost>")
set(CPACK_PACKAGING_INSTALL_PREFIX /usr)
set(CPACK_DEBIAN_FILE_NAME DEB-DEFAULT)
set(CPACK_DEBIAN_PACKAGE_SECTION graphics)
set(CPACK_STRIP_FILES ON)  # as Debian packages are (debug info would triple the size)
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS ON)
# libosgBTF, libosgBTFFit, libosgBTFStreaming and libosgBTFEnvironment are in the package itself:
# dpkg-shlibdeps finds them there for the tools and plugins.
set(CPACK_DEBIAN_PACKAGE_SHLIBDEPS_PRIVATE_DIRS ${CMAKE_INSTALL_LIBDIR})
set(CPACK_DEBIAN_PACKAGE_RECOMMENDS
    "libopenscenegraph-dev, libglm-dev, libimath-dev, libeigen3-dev, openscenegraph")
if(OSGBTF_PYTHON)
  # The Python module (python/, in /usr/lib/python3/dist-packages) returns numpy arrays.
  string(APPEND CPACK_DEBIAN_PACKAGE_RECOMMENDS ", python3, python3-numpy")
endif()
set(CPACK_GENERATOR DEB)
set(CPACK_SOURCE_GENERATOR TGZ)
# The .deb must follow Debian's layout; a build for another prefix would put the library in
# /usr/lib, outside the multiarch folder (GNUInstallDirs picks the libdir from the prefix).
set(OSGBTF_PACKAGE_LIBDIR ${CMAKE_INSTALL_LIBDIR})
configure_file(${CMAKE_SOURCE_DIR}/cmake/CPackProjectConfig.cmake.in
               ${CMAKE_BINARY_DIR}/CPackProjectConfig.cmake @ONLY)
# Maintainer scripts (cmake/debian/): OSG's plugin names osgdb_zip.so and osgdb_exr.so become
# update-alternatives links to osgdb_btfzip.so and osgdb_btfexr.so where no real file has them
# (plugins/README.md, "Names"; tests/plugin_names_test.cpp runs the scripts in a scratch root).
set(OSGBTF_PACKAGE_PLUGIN_DIR
    ${CMAKE_INSTALL_PREFIX}/${CMAKE_INSTALL_LIBDIR}/osgPlugins-${OPENSCENEGRAPH_VERSION})
foreach(script postinst prerm)
  configure_file(${CMAKE_SOURCE_DIR}/cmake/debian/${script}.in ${CMAKE_BINARY_DIR}/debian/${script}
                 @ONLY FILE_PERMISSIONS OWNER_READ OWNER_WRITE OWNER_EXECUTE GROUP_READ
                 GROUP_EXECUTE WORLD_READ WORLD_EXECUTE)
endforeach()
# A postinst of our own replaces the one CPack writes, which only ran ldconfig: the trigger file
# has dpkg run it (libc-bin's ldconfig trigger) instead.
set(CPACK_DEBIAN_PACKAGE_CONTROL_EXTRA ${CMAKE_BINARY_DIR}/debian/postinst
    ${CMAKE_BINARY_DIR}/debian/prerm ${CMAKE_SOURCE_DIR}/cmake/debian/triggers)
set(CPACK_DEBIAN_PACKAGE_CONTROL_STRICT_PERMISSION ON)
set(CPACK_PROJECT_CONFIG_FILE ${CMAKE_BINARY_DIR}/CPackProjectConfig.cmake)
include(CPack)
