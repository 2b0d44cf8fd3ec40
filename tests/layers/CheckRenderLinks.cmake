# ctest layers.render_links: rendering a fitted material loads no fitter, no HTTP client, no ray
# tracer and no OpenImageIO. The render library (libosgBTF) and the render plugin (osgdb_btfmat)
# must not need Ceres, glog, libtorch, libcurl, libembree or OpenImageIO, not even through another
# library (ldd: the whole closure), nor libosgBTFFit, libosgBTFStreaming or libosgBTFEnvironment
# (readelf: NEEDED, and ldd); OpenImageIO (whose closure brings ~260 libraries, libcurl through
# GDAL among them) is a module the library loads on first use, libosgBTFImageCodecs.
# libosgBTF must not use a symbol the upper libraries define (the fitting code lives there only),
# no curl_ or rtc* (Embree) function, and must not export Ceres code (Debian's CMake package links
# Ceres statically: its code would be inside, and only glog in NEEDED). So that the check can
# fail, the same probes must find glog or Ceres behind libosgBTFFit, Ceres code in it, libosgBTFFit
# in a plugin that fits on load (osgdb_btf), libcurl and curl_ functions in libosgBTFStreaming,
# libembree and its rtc* functions in libosgBTFEnvironment, and OpenImageIO in the module.
#   cmake -DRENDER_LIBRARY=<libosgBTF> -DRENDER_PLUGIN=<osgdb_btfmat>
#         -DFIT_LIBRARY=<libosgBTFFit> -DFIT_PLUGIN=<osgdb_btf>
#         -DSTREAMING_LIBRARY=<libosgBTFStreaming>
#         -DENVIRONMENT_LIBRARY=<libosgBTFEnvironment>
#         -DIMAGE_CODECS_MODULE=<libosgBTFImageCodecs.so> -P CheckRenderLinks.cmake
cmake_minimum_required(VERSION 3.22)
# libtorch, libc10: the neural method's training (materials/neural/NeuralTraining.cpp, a module).
set(fitting_pattern
    "ceres|glog|osgBTFFit|osgBTFStreaming|embree|osgBTFEnvironment|libtorch|libc10|curl|OpenImageIO")
set(RENDER ${RENDER_LIBRARY} ${RENDER_PLUGIN})

function(needed file out)  # the DT_NEEDED entries of `file`
  execute_process(COMMAND readelf -d ${file} OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "readelf -d ${file} failed (${rc})")
  endif()
  string(REGEX MATCHALL "\\(NEEDED\\)[^[]*\\[[^]]+\\]" entries "${text}")
  list(TRANSFORM entries REPLACE ".*\\[([^]]+)\\]" "\\1")
  set(${out} "${entries}" PARENT_SCOPE)
endfunction()

function(closure file out)  # every library the loader brings in for `file` (ldd)
  execute_process(COMMAND ldd ${file} OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "ldd ${file} failed (${rc})")
  endif()
  string(REGEX MATCHALL "[^ \t\n]+\\.so[^ \t\n]*" entries "${text}")
  set(${out} "${entries}" PARENT_SCOPE)
endfunction()

function(dynamic_symbols file mode out)  # mode: --defined-only or --undefined-only
  execute_process(COMMAND nm -D ${mode} ${file} OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "nm -D ${mode} ${file} failed (${rc})")
  endif()
  string(REGEX MATCHALL "[^ \t\n]+\n" symbols "${text}")
  list(TRANSFORM symbols STRIP)
  set(${out} "${symbols}" PARENT_SCOPE)
endfunction()

set(problems)
foreach(file IN LISTS RENDER)
  get_filename_component(name ${file} NAME)
  needed(${file} direct)
  closure(${file} all)
  foreach(library IN LISTS direct)
    if(library MATCHES "${fitting_pattern}")
      list(APPEND problems "${name} needs ${library}: rendering must not load a fitter, an "
                           "HTTP client, a ray tracer or OpenImageIO")
    endif()
  endforeach()
  foreach(library IN LISTS all)
    if(library MATCHES "${fitting_pattern}")
      list(APPEND problems "${name} loads ${library}: rendering must not load a fitter, an "
                           "HTTP client, a ray tracer or OpenImageIO")
    endif()
  endforeach()
endforeach()

# No symbol of the render library is left for libosgBTFFit, libosgBTFStreaming or
# libosgBTFEnvironment to define.
set(render_library ${RENDER_LIBRARY})
dynamic_symbols(${render_library} --undefined-only render_undefined)
foreach(symbol IN LISTS render_undefined)
  if(symbol MATCHES "^curl_")
    list(APPEND problems "${render_library} uses ${symbol} (libcurl)")
  endif()
  if(symbol MATCHES "^rtc[A-Z]")
    list(APPEND problems "${render_library} uses ${symbol} (Embree)")
  endif()
endforeach()
foreach(upper IN ITEMS ${FIT_LIBRARY} ${STREAMING_LIBRARY} ${ENVIRONMENT_LIBRARY})
  get_filename_component(upper_name ${upper} NAME)
  dynamic_symbols(${upper} --defined-only upper_defined)
  list(LENGTH upper_defined upper_defined_count)
  if(upper_defined_count EQUAL 0)
    list(APPEND problems "nm -D found no symbols in ${upper}: the probe is broken")
  endif()
  foreach(symbol IN LISTS render_undefined)
    if(symbol IN_LIST upper_defined)
      list(APPEND problems "${render_library} uses ${symbol}, which ${upper_name} defines")
    endif()
  endforeach()
endforeach()

function(exports_ceres file out)  # whether `file` exports symbols of namespace ceres
  execute_process(COMMAND nm -DC --defined-only ${file} OUTPUT_VARIABLE text RESULT_VARIABLE rc)
  if(NOT rc EQUAL 0)
    message(FATAL_ERROR "nm -DC --defined-only ${file} failed (${rc})")
  endif()
  string(FIND "${text}" "ceres::" at)
  if(at EQUAL -1)
    set(${out} FALSE PARENT_SCOPE)
  else()
    set(${out} TRUE PARENT_SCOPE)
  endif()
endfunction()
exports_ceres(${render_library} render_ceres)
if(render_ceres)
  list(APPEND problems "${render_library} exports symbols of Ceres (nm -DC | grep ceres::)")
endif()

# The probes can fail: the fitting side shows what the render side must not.
needed(${FIT_LIBRARY} fit_direct)
if(NOT fit_direct MATCHES "ceres|glog")
  list(APPEND problems "readelf finds neither Ceres nor glog in ${FIT_LIBRARY}'s NEEDED (${fit_direct})")
endif()
exports_ceres(${FIT_LIBRARY} fit_ceres)
if(NOT fit_ceres)
  list(APPEND problems "nm finds no Ceres code in ${FIT_LIBRARY}")
endif()
needed(${FIT_PLUGIN} plugin_direct)
if(NOT plugin_direct MATCHES "osgBTFFit")
  list(APPEND problems "readelf finds no libosgBTFFit in ${FIT_PLUGIN}'s NEEDED (${plugin_direct})")
endif()
closure(${FIT_PLUGIN} plugin_all)
if(NOT plugin_all MATCHES "ceres|glog")
  list(APPEND problems "ldd finds neither Ceres nor glog behind ${FIT_PLUGIN}")
endif()
dynamic_symbols(${STREAMING_LIBRARY} --undefined-only streaming_undefined)
if(NOT streaming_undefined MATCHES "(^|;)curl_")
  list(APPEND problems "nm finds no curl_ symbol used by ${STREAMING_LIBRARY}")
endif()
needed(${STREAMING_LIBRARY} streaming_direct)
if(NOT streaming_direct MATCHES "curl")
  list(APPEND problems "readelf finds no libcurl in ${STREAMING_LIBRARY}'s NEEDED (${streaming_direct})")
endif()
needed(${ENVIRONMENT_LIBRARY} environment_direct)
if(NOT environment_direct MATCHES "embree")
  list(APPEND problems "readelf finds no libembree in ${ENVIRONMENT_LIBRARY}'s NEEDED "
                       "(${environment_direct})")
endif()
dynamic_symbols(${ENVIRONMENT_LIBRARY} --undefined-only environment_undefined)
if(NOT environment_undefined MATCHES "(^|;)rtc[A-Z]")
  list(APPEND problems "nm finds no rtc* (Embree) symbol used by ${ENVIRONMENT_LIBRARY}")
endif()
needed(${IMAGE_CODECS_MODULE} codecs_direct)
if(NOT codecs_direct MATCHES "OpenImageIO")
  list(APPEND problems "readelf finds no OpenImageIO in ${IMAGE_CODECS_MODULE}'s NEEDED "
                       "(${codecs_direct})")
endif()

if(problems)
  list(REMOVE_DUPLICATES problems)
  list(JOIN problems "\n  " text)
  message(FATAL_ERROR "render link check failed:\n  ${text}")
endif()
message(STATUS "render library and render plugin load no fitter, no HTTP client, no ray tracer "
               "and no OpenImageIO")
