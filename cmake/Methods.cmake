# osgbtf_method(RENDER <sources> FIT <sources> [OWN <sources>]): a method folder's one CMake entry
# (materials/<m>/CMakeLists.txt). RENDER sources build libosgBTF: the material, its shader-side
# state, its file formats and environment folding, all that rendering a fitted material needs.
# FIT sources build libosgBTFFit (with Ceres and TBB), which registers the fitter. OWN sources are
# built by a target the folder defines itself (neural's training module). A .cpp file of the
# folder that the entry does not name stops the configuration: the folder and its entry agree.
function(osgbtf_method)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "" "RENDER;FIT;OWN")
  get_filename_component(method ${CMAKE_CURRENT_SOURCE_DIR} NAME)
  file(GLOB sources CONFIGURE_DEPENDS RELATIVE ${CMAKE_CURRENT_SOURCE_DIR}
       ${CMAKE_CURRENT_SOURCE_DIR}/*.cpp)
  set(named ${arg_RENDER} ${arg_FIT} ${arg_OWN})
  foreach(source IN LISTS sources)
    if(NOT source IN_LIST named)
      message(FATAL_ERROR "materials/${method}/${source}: not named in "
                          "materials/${method}/CMakeLists.txt (RENDER, FIT or OWN)")
    endif()
  endforeach()
  foreach(source IN LISTS named)
    if(NOT source IN_LIST sources)
      message(FATAL_ERROR "materials/${method}/CMakeLists.txt names ${source}, which is not in "
                          "the folder")
    endif()
  endforeach()
  target_sources(osgBTF PRIVATE ${arg_RENDER})
  if(arg_FIT)
    target_sources(osgBTFFit PRIVATE ${arg_FIT})
  endif()
endfunction()
