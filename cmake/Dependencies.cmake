# Every dependency comes from Debian 12 packages (see .ci/run for the package list).
find_package(OpenSceneGraph 3.6 REQUIRED COMPONENTS osgDB osgUtil osgGA osgViewer osgText osgShadow)
# osgbtf::osg: what libosgBTF's headers and code use (osg, osgDB, osgUtil, OpenThreads); the
# installed osgBTFConfig.cmake defines the same target. osgbtf::osgviewer adds the rest for the
# tools, examples and tests.
add_library(osgbtf::osg INTERFACE IMPORTED)
set_target_properties(osgbtf::osg PROPERTIES
  INTERFACE_INCLUDE_DIRECTORIES "${OPENSCENEGRAPH_INCLUDE_DIRS}"
  INTERFACE_LINK_LIBRARIES "${OSGUTIL_LIBRARY};${OSGDB_LIBRARY};${OSG_LIBRARY};${OPENTHREADS_LIBRARY}")
add_library(osgbtf::osgviewer INTERFACE IMPORTED)
set_target_properties(osgbtf::osgviewer PROPERTIES
  INTERFACE_LINK_LIBRARIES "${OPENSCENEGRAPH_LIBRARIES};osgbtf::osg")

set(OpenGL_GL_PREFERENCE GLVND)
find_package(OpenGL REQUIRED COMPONENTS OpenGL EGL)
find_package(PkgConfig REQUIRED)
pkg_check_modules(OSMesa REQUIRED IMPORTED_TARGET osmesa)
# libzip's CMake config names tools Debian packages separately; pkg-config works.
pkg_check_modules(LIBZIP REQUIRED IMPORTED_TARGET libzip>=1.7)
find_package(glm CONFIG REQUIRED)
find_package(Imath CONFIG REQUIRED)
find_package(OpenEXR CONFIG REQUIRED)
find_package(OpenImageIO CONFIG REQUIRED)
# OpenImageIO 2.4.7's target lists /usr/include/opencv4, absent without libopencv-dev.
foreach(prop INTERFACE_INCLUDE_DIRECTORIES INTERFACE_SYSTEM_INCLUDE_DIRECTORIES)
  get_target_property(dirs OpenImageIO::OpenImageIO ${prop})
  if(dirs)
    list(FILTER dirs EXCLUDE REGEX opencv)
    set_target_properties(OpenImageIO::OpenImageIO PROPERTIES ${prop} "${dirs}")
  endif()
endforeach()
find_package(Eigen3 3.4 CONFIG REQUIRED)
find_package(Ceres CONFIG REQUIRED)
# The neural method's training (materials/neural/NeuralFit.cpp, libosgBTFFit only): Debian's
# libtorch-dev 1.13. Optional: without it every other method builds and the neural fit says
# what is missing; rendering a fitted neural material never needs it.
option(OSGBTF_NEURAL_FIT "Train the neural method with libtorch when it is found" ON)
if(OSGBTF_NEURAL_FIT)
  find_package(Torch QUIET)
  if(Torch_FOUND)
    message(STATUS "libtorch found: the neural method can fit")
  else()
    message(STATUS "libtorch not found (apt-get install libtorch-dev): the neural method cannot fit")
  endif()
endif()
find_package(TBB CONFIG REQUIRED)
# Per-vertex environment visibility (environment/VertexEnvironment.h, libosgBTFEnvironment only):
# Debian's libembree-dev 3.13.
find_package(embree 3 CONFIG REQUIRED)
find_package(CLI11 CONFIG REQUIRED)
find_package(nlohmann_json 3 CONFIG REQUIRED)
find_package(GTest CONFIG REQUIRED)
