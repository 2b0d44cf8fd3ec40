# The layers of the source tree and what each may include (README "Layout", docs/architecture.md).
# Every library is a folder (or a few), and a library includes only its own folders and those of
# the libraries it links:
#   libosgBTF          core/ loaders/ materials/ (every method's RENDER sources) synthesis/ scene/
#   libosgBTFFit       fit/ (and every method's FIT sources, materials/<m>/CMakeLists.txt)
#   libosgBTFStreaming streaming/        libosgBTFEnvironment environment/
#   libosgBTFHarness   harness/ (static: the tools, examples, tests and benchmarks)
# A header belongs to its folder's layer; a source to its folder's layer and to the library that
# compiles it, checked when CMake configures (osgbtf_layer_violations and
# osgbtf_library_include_violations, top CMakeLists.txt): a method's FIT sources in
# materials/<m>/ are libosgBTFFit's and may include fit/, its render and OWN sources may not. tests/, fuzz/ and bench/ may include everything below them (fuzz/ holds the fuzz
# targets' bodies, which the regression test in tests/ calls, and their seed generator). Used by
# the configure step and cmake/CheckLayers.cmake (the layers.include_graph test), and tested on
# fake trees by tests/layers/CheckLayersTest.cmake.

set(osgbtf_runtime core loaders materials synthesis scene)
set(osgbtf_libraries ${osgbtf_runtime} fit streaming environment)
set(OSGBTF_LAYER_ALLOWED_core core)
set(OSGBTF_LAYER_ALLOWED_loaders core loaders)
set(OSGBTF_LAYER_ALLOWED_materials core materials)
set(OSGBTF_LAYER_ALLOWED_synthesis core synthesis)
set(OSGBTF_LAYER_ALLOWED_scene core loaders materials synthesis scene)
set(OSGBTF_LAYER_ALLOWED_fit ${osgbtf_runtime} fit)
set(OSGBTF_LAYER_ALLOWED_streaming core materials streaming)
set(OSGBTF_LAYER_ALLOWED_environment ${osgbtf_runtime} environment)
set(OSGBTF_LAYER_ALLOWED_harness ${osgbtf_libraries} harness)
set(OSGBTF_LAYER_ALLOWED_tools ${osgbtf_libraries} harness tools)
set(OSGBTF_LAYER_ALLOWED_python ${osgbtf_libraries} harness python)
set(OSGBTF_LAYER_ALLOWED_examples ${osgbtf_libraries} harness examples)
set(OSGBTF_LAYER_ALLOWED_plugins ${osgbtf_libraries} plugins)
set(OSGBTF_LAYER_ALLOWED_fuzz ${osgbtf_libraries} harness plugins fuzz)
set(OSGBTF_LAYER_ALLOWED_tests ${osgbtf_libraries} harness plugins fuzz tests)
set(OSGBTF_LAYER_ALLOWED_bench ${osgbtf_libraries} harness bench)
set(OSGBTF_LAYERS core loaders materials synthesis scene fit streaming environment harness tools
                  python examples plugins fuzz tests bench)
# What each library's sources may include: its own folders and its links'.
set(OSGBTF_LIBRARY_ALLOWED_osgBTF ${osgbtf_runtime})
set(OSGBTF_LIBRARY_ALLOWED_osgBTFFit ${osgbtf_runtime} fit)
set(OSGBTF_LIBRARY_ALLOWED_osgBTFStreaming ${OSGBTF_LAYER_ALLOWED_streaming})
set(OSGBTF_LIBRARY_ALLOWED_osgBTFEnvironment ${OSGBTF_LAYER_ALLOWED_environment})
set(OSGBTF_LIBRARY_ALLOWED_osgBTFHarness ${OSGBTF_LAYER_ALLOWED_harness})

# Appends to OUT_VAR one message per quoted include, in FILES (relative to ROOT, sorted here),
# whose first folder is a layer not in ALLOWED: "<file><WHO>: includes "<path>", but <RULE>
# may include only <allowed>/". Quoted includes whose first folder is not a layer (same-folder
# headers such as "Commands.h") are not part of the graph.
function(osgbtf_forbidden_includes ROOT FILES ALLOWED WHO RULE OUT_VAR)
  set(violations ${${OUT_VAR}})
  string(REPLACE ";" "/, " allowed_text "${ALLOWED}")
  set(files ${FILES})
  list(SORT files)
  foreach(file IN LISTS files)
    file(READ ${ROOT}/${file} text)
    string(REGEX MATCHALL "#[ \t]*include[ \t]*\"[^\"]+\"" includes "${text}")
    foreach(include IN LISTS includes)
      string(REGEX REPLACE ".*\"([^\"]+)\"" "\\1" path "${include}")
      string(REGEX MATCH "^[^/]+/" first "${path}")
      string(REPLACE "/" "" first "${first}")
      if(first AND first IN_LIST OSGBTF_LAYERS AND NOT first IN_LIST ALLOWED)
        list(APPEND violations
             "${file}${WHO}: includes \"${path}\", but ${RULE} may include only ${allowed_text}/")
      endif()
    endforeach()
  endforeach()
  set(${OUT_VAR} "${violations}" PARENT_SCOPE)
endfunction()

# Sets OUT_VAR to one message per include, in FILES (paths relative to ROOT) that LIBRARY
# compiles, of a layer that library may not use:
#   <file> (LIBRARY): includes "<path>", but LIBRARY may include only <allowed>/
function(osgbtf_library_include_violations ROOT LIBRARY FILES OUT_VAR)
  set(violations)
  osgbtf_forbidden_includes(${ROOT} "${FILES}" "${OSGBTF_LIBRARY_ALLOWED_${LIBRARY}}"
                            " (${LIBRARY})" ${LIBRARY} violations)
  set(${OUT_VAR} "${violations}" PARENT_SCOPE)
endfunction()

# Sets OUT_VAR to the FIT sources of every method folder (materials/<m>/CMakeLists.txt's
# osgbtf_method(... FIT <sources> ...), cmake/Methods.cmake), relative to ROOT: libosgBTFFit's
# sources that live in materials/.
function(osgbtf_method_fit_sources ROOT OUT_VAR)
  set(fit_sources)
  file(GLOB entries RELATIVE ${ROOT} ${ROOT}/materials/*/CMakeLists.txt)
  foreach(entry IN LISTS entries)
    get_filename_component(folder ${entry} DIRECTORY)
    file(READ ${ROOT}/${entry} text)
    string(REGEX MATCH "osgbtf_method\\(([^)]*)\\)" call "${text}")
    string(REGEX REPLACE "[ \t\r\n]+" ";" words "${CMAKE_MATCH_1}")
    set(section)
    foreach(word IN LISTS words)
      if(word MATCHES "^[A-Z_]+$")  # a keyword: RENDER, FIT, OWN, ...
        set(section ${word})
      elseif(word AND section STREQUAL "FIT")
        list(APPEND fit_sources ${folder}/${word})
      endif()
    endforeach()
  endforeach()
  set(${OUT_VAR} "${fit_sources}" PARENT_SCOPE)
endfunction()

# Sets OUT_VAR to one message per include of a layer the including file's layer may not use:
#   <file>: includes "<path>", but <layer>/ may include only <allowed>/
# (files relative to ROOT, sorted). Every header and source is checked by its folder: inside
# libosgBTF a loaders/ source may not include materials/, although the library holds both, and a
# source no library compiles (neural's training module, an OWN source) is checked too. Except a
# method's FIT sources, which libosgBTFFit compiles: they are checked as that library's,
#   <file> (osgBTFFit): includes "<path>", but osgBTFFit may include only <allowed>/
# (at configure time also with the library's other sources, osgbtf_library_include_violations).
# And a method's tests (materials/<m>/test/, osgbtf_method's TESTS and GL_TESTS), which the test
# programs compile: checked as the tests layer,
#   <file>: includes "<path>", but a method's test/ (the tests layer) may include only <allowed>/
# Quoted includes whose first folder is not a layer (same-folder headers such as "Commands.h")
# are not part of the graph.
function(osgbtf_layer_violations ROOT OUT_VAR)
  set(violations)
  osgbtf_method_fit_sources(${ROOT} fit_sources)
  foreach(layer IN LISTS OSGBTF_LAYERS)
    file(GLOB_RECURSE files RELATIVE ${ROOT} ${ROOT}/${layer}/*.h ${ROOT}/${layer}/*.hpp
         ${ROOT}/${layer}/*.cpp ${ROOT}/${layer}/*.inc)
    if(fit_sources)
      list(REMOVE_ITEM files ${fit_sources})
    endif()
    # A method's tests (materials/<m>/test/) are the tests layer's, checked as such below.
    list(FILTER files EXCLUDE REGEX "^materials/[^/]+/test/")
    osgbtf_forbidden_includes(${ROOT} "${files}" "${OSGBTF_LAYER_ALLOWED_${layer}}" ""
                              ${layer}/ violations)
  endforeach()
  file(GLOB method_tests RELATIVE ${ROOT} ${ROOT}/materials/*/test/*.h
       ${ROOT}/materials/*/test/*.cpp)
  osgbtf_forbidden_includes(${ROOT} "${method_tests}" "${OSGBTF_LAYER_ALLOWED_tests}" ""
                            "a method's test/ (the tests layer)" violations)
  osgbtf_library_include_violations(${ROOT} osgBTFFit "${fit_sources}" fit_violations)
  list(APPEND violations ${fit_violations})
  set(${OUT_VAR} "${violations}" PARENT_SCOPE)
endfunction()

# Sets OUT_VAR to one message per include cycle among the headers of the layers:
#   include cycle: <a.h> -> <b.h> -> <a.h>
# each cycle once, starting at its alphabetically first header. Quoted includes are resolved as
# the compiler does: beside the including file first, then from ROOT. A cycle compiles (#pragma
# once) but makes the order of declarations depend on which header an includer names first.
function(osgbtf_include_cycles ROOT OUT_VAR)
  set(headers)
  foreach(layer IN LISTS OSGBTF_LAYERS)
    file(GLOB_RECURSE found RELATIVE ${ROOT} ${ROOT}/${layer}/*.h ${ROOT}/${layer}/*.hpp)
    list(APPEND headers ${found})
  endforeach()
  list(SORT headers)
  foreach(header IN LISTS headers)
    file(READ ${ROOT}/${header} text)
    string(REGEX MATCHALL "#[ \t]*include[ \t]*\"[^\"]+\"" includes "${text}")
    get_filename_component(dir ${header} DIRECTORY)
    set(edges)
    foreach(include IN LISTS includes)
      string(REGEX REPLACE ".*\"([^\"]+)\"" "\\1" path "${include}")
      if(dir AND EXISTS ${ROOT}/${dir}/${path})
        set(path ${dir}/${path})
      endif()
      if(path IN_LIST headers)
        list(APPEND edges ${path})
      endif()
    endforeach()
    set(edges_${header} ${edges})
  endforeach()
  set(cycles)
  foreach(start IN LISTS headers)
    # Breadth-first from start's includes, each header's predecessor kept to print the path.
    set(queue ${edges_${start}})
    set(seen ${queue})
    foreach(next IN LISTS queue)
      set(from_${next} ${start})
    endforeach()
    set(found FALSE)
    while(queue AND NOT found)
      list(POP_FRONT queue current)
      if(current STREQUAL start)
        set(found TRUE)
        break()
      endif()
      foreach(next IN LISTS edges_${current})
        if(NOT next IN_LIST seen)
          list(APPEND seen ${next})
          list(APPEND queue ${next})
          set(from_${next} ${current})
        elseif(next STREQUAL start AND NOT found)
          set(from_start_again ${current})
          set(found TRUE)
        endif()
      endforeach()
    endwhile()
    if(found)
      # Walk back from start's predecessor on the cycle to start.
      if(DEFINED from_start_again)
        set(node ${from_start_again})
      else()
        set(node ${from_${start}})
      endif()
      set(path ${start})
      set(smallest TRUE)
      while(NOT node STREQUAL start)
        list(PREPEND path ${node})
        string(COMPARE LESS "${node}" "${start}" earlier)
        if(earlier)
          set(smallest FALSE)
        endif()
        set(node ${from_${node}})
      endwhile()
      list(PREPEND path ${start})
      if(smallest)
        list(JOIN path " -> " text)
        list(APPEND cycles "include cycle: ${text}")
      endif()
    endif()
    foreach(node IN LISTS seen)
      unset(from_${node})
    endforeach()
    unset(from_start_again)
  endforeach()
  set(${OUT_VAR} "${cycles}" PARENT_SCOPE)
endfunction()
