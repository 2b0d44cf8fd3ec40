# osgbtf_method(RENDER <sources> FIT <sources> [OWN <sources>] [TESTS <sources>]
#               [GL_TESTS <sources>]): a method folder's one CMake entry
# (materials/<m>/CMakeLists.txt). RENDER sources build libosgBTF: the material, its shader-side
# state, its file formats and environment folding, all that rendering a fitted material needs.
# FIT sources build libosgBTFFit (with Ceres and TBB), which registers the fitter. OWN sources are
# built by a target the folder defines itself (neural's training module). TESTS and GL_TESTS name
# the method's tests in its test/ folder (names relative to test/): TESTS are compiled into the
# unit-test programs (osgBTF_tests, osgBTF_accuracy_tests), GL_TESTS into the OpenGL test programs
# (tests/gl/), collected in the global properties OSGBTF_METHOD_TESTS and OSGBTF_METHOD_GL_TESTS,
# which tests/ reads. A .cpp file of the folder or of test/ that the entry does not name stops the
# configuration: the folder and its entry agree.
function(osgbtf_method)
  cmake_parse_arguments(PARSE_ARGV 0 arg "" "" "RENDER;FIT;OWN;TESTS;GL_TESTS")
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
  set(test_dir ${CMAKE_CURRENT_SOURCE_DIR}/test)
  file(GLOB tests CONFIGURE_DEPENDS RELATIVE ${test_dir} ${test_dir}/*.cpp)
  set(named_tests ${arg_TESTS} ${arg_GL_TESTS})
  foreach(source IN LISTS tests)
    if(NOT source IN_LIST named_tests)
      message(FATAL_ERROR "materials/${method}/test/${source}: not named in "
                          "materials/${method}/CMakeLists.txt (TESTS or GL_TESTS)")
    endif()
  endforeach()
  foreach(source IN LISTS named_tests)
    if(NOT source IN_LIST tests)
      message(FATAL_ERROR "materials/${method}/CMakeLists.txt names the test ${source}, which is "
                          "not in materials/${method}/test/")
    endif()
  endforeach()
  list(TRANSFORM arg_TESTS PREPEND ${test_dir}/)
  list(TRANSFORM arg_GL_TESTS PREPEND ${test_dir}/)
  set_property(GLOBAL APPEND PROPERTY OSGBTF_METHOD_TESTS ${arg_TESTS})
  set_property(GLOBAL APPEND PROPERTY OSGBTF_METHOD_GL_TESTS ${arg_GL_TESTS})
  target_sources(osgBTF PRIVATE ${arg_RENDER})
  if(arg_FIT)
    target_sources(osgBTFFit PRIVATE ${arg_FIT})
  endif()
endfunction()
