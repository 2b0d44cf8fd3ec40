# The layers of the source tree and what each may include (README "Layout"). A lower layer never
# includes a higher one: the runtime libosgBTF (core, loaders, materials, scene) must build and
# ship without harness/ (libosgBTFHarness), and the plugins load only the runtime.
#   core <- loaders, materials, synthesis; materials <- streaming (BSVTF);
#   all of those <- scene <- harness <- tools, examples, python (the Python module); scene <- plugins
# tests/, fuzz/ and bench/ may include everything below them (fuzz/ holds the fuzz targets'
# bodies, which the regression test in tests/ calls, and their seed generator). Used by
# cmake/CheckLayers.cmake (the layers.include_graph test) and tested on fake trees by
# tests/layers/CheckLayersTest.cmake.

set(OSGBTF_LAYER_ALLOWED_core core)
set(OSGBTF_LAYER_ALLOWED_loaders core loaders)
set(OSGBTF_LAYER_ALLOWED_materials core materials)
set(OSGBTF_LAYER_ALLOWED_synthesis core synthesis)
set(OSGBTF_LAYER_ALLOWED_streaming core materials streaming)
set(OSGBTF_LAYER_ALLOWED_scene core loaders materials synthesis streaming scene)
set(OSGBTF_LAYER_ALLOWED_harness core loaders materials synthesis streaming scene harness)
set(OSGBTF_LAYER_ALLOWED_tools core loaders materials synthesis streaming scene harness tools)
set(OSGBTF_LAYER_ALLOWED_python core loaders materials synthesis streaming scene harness python)
set(OSGBTF_LAYER_ALLOWED_examples core loaders materials synthesis streaming scene harness examples)
set(OSGBTF_LAYER_ALLOWED_plugins core loaders materials synthesis streaming scene plugins)
set(OSGBTF_LAYER_ALLOWED_fuzz core loaders materials synthesis streaming scene harness plugins fuzz)
set(OSGBTF_LAYER_ALLOWED_tests core loaders materials synthesis streaming scene harness plugins fuzz tests)
set(OSGBTF_LAYER_ALLOWED_bench core loaders materials synthesis streaming scene harness bench)
set(OSGBTF_LAYERS core loaders materials synthesis streaming scene harness tools python examples plugins
                  fuzz tests bench)

# Sets OUT_VAR to one message per include of a layer the including file's layer may not use:
#   <file>: includes "<path>", but <layer>/ may include only <allowed>/
# (files relative to ROOT, sorted). Quoted includes whose first folder is not a layer (same-folder
# headers such as "Commands.h") are not part of the graph.
function(osgbtf_layer_violations ROOT OUT_VAR)
  set(violations)
  foreach(layer IN LISTS OSGBTF_LAYERS)
    file(GLOB_RECURSE files RELATIVE ${ROOT} ${ROOT}/${layer}/*.h ${ROOT}/${layer}/*.hpp
         ${ROOT}/${layer}/*.cpp ${ROOT}/${layer}/*.inc)
    list(SORT files)
    set(allowed ${OSGBTF_LAYER_ALLOWED_${layer}})
    string(REPLACE ";" "/, " allowed_text "${allowed}")
    foreach(file IN LISTS files)
      file(READ ${ROOT}/${file} text)
      string(REGEX MATCHALL "#[ \t]*include[ \t]*\"[^\"]+\"" includes "${text}")
      foreach(include IN LISTS includes)
        string(REGEX REPLACE ".*\"([^\"]+)\"" "\\1" path "${include}")
        string(REGEX MATCH "^[^/]+/" first "${path}")
        string(REPLACE "/" "" first "${first}")
        if(first AND first IN_LIST OSGBTF_LAYERS AND NOT first IN_LIST allowed)
          list(APPEND violations
               "${file}: includes \"${path}\", but ${layer}/ may include only ${allowed_text}/")
        endif()
      endforeach()
    endforeach()
  endforeach()
  set(${OUT_VAR} "${violations}" PARENT_SCOPE)
endfunction()
