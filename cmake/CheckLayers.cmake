# cmake -DROOT=<source tree> -P cmake/CheckLayers.cmake: fails, listing every include of a
# higher layer by a lower one (cmake/LayerRules.cmake). Run by the test layers.include_graph.
cmake_minimum_required(VERSION 3.22)  # policies as in the build (IN_LIST)
if(NOT ROOT)
  message(FATAL_ERROR "CheckLayers.cmake: pass -DROOT=<source tree>")
endif()
include(${CMAKE_CURRENT_LIST_DIR}/LayerRules.cmake)
osgbtf_layer_violations(${ROOT} violations)
if(violations)
  list(LENGTH violations count)
  list(JOIN violations "\n" text)
  message(FATAL_ERROR "${count} include(s) of a higher layer:\n${text}")
endif()
message(STATUS "include graph follows the layers")
