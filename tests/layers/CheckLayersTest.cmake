# cmake -DWORK=<empty folder> -P CheckLayersTest.cmake: runs the layer checker on small fake trees
# and compares its messages with the expected ones exactly, so a checker that finds nothing (or
# the wrong thing) fails here.
cmake_minimum_required(VERSION 3.22)  # policies as in the build (IN_LIST)
include(${CMAKE_CURRENT_LIST_DIR}/../../cmake/LayerRules.cmake)
file(REMOVE_RECURSE ${WORK})

function(write_tree root)  # pairs: file, its contents
  set(args ${ARGN})
  while(args)
    list(POP_FRONT args file content)
    file(WRITE ${root}/${file} "${content}\n")
  endwhile()
endfunction()

function(expect root)
  osgbtf_layer_violations(${root} got)
  if(NOT "${got}" STREQUAL "${ARGN}")
    list(JOIN got "\n  " got_text)
    list(JOIN ARGN "\n  " want_text)
    message(FATAL_ERROR "${root}: expected\n  ${want_text}\ngot\n  ${got_text}")
  endif()
endfunction()

# Downward includes, same-folder includes and system headers are fine.
write_tree(${WORK}/good
  core/A.h "#pragma once\n#include <vector>\n#include \"core/B.h\""
  core/B.h "#pragma once"
  loaders/L.cpp "#include \"core/A.h\""
  materials/pca/M.cpp "#include \"core/A.h\"\n#include \"Local.h\""
  materials/pca/CMakeLists.txt "osgbtf_method(RENDER M.cpp\n              FIT MFit.cpp\n              OWN MOwn.cpp)"
  materials/pca/MFit.cpp "#include \"fit/LightBasisFit.h\"\n#include \"materials/pca/M.h\""
  materials/pca/MOwn.cpp "#include \"materials/pca/M.h\""
  materials/pca/test/m_test.cpp "#include \"harness/H.h\"\n#include \"tests/TestUtil.h\""
  synthesis/K.cpp "#include \"core/A.h\""
  scene/S.cpp "#include \"materials/pca/M.h\"\n#include \"loaders/L.h\"\n#include \"synthesis/K.h\""
  harness/headless/H.cpp "#include \"scene/S.h\""
  plugins/btf/P.cpp "#include \"scene/S.h\"\n#include \"plugins/btf/P.h\""
  tools/btf/T.cpp "#include \"harness/H.h\""
  fuzz/F.cpp "#include \"plugins/btf/P.h\"\n#include \"harness/H.h\""
  tests/x_test.cpp "#include \"harness/H.h\"\n#include \"plugins/btf/P.h\"\n#include \"fuzz/F.h\"")
expect(${WORK}/good)

# Upward includes: each one reported once, with the file, the include and the rule. Sources are
# checked by their folder too (loaders/L.cpp may not include materials/ although libosgBTF holds
# both; an OWN source, which no library compiles, likewise), a method's FIT source as
# libosgBTFFit's, which may include fit/ but not harness/, and a method's test as the tests layer's.
write_tree(${WORK}/bad
  core/A.h "#pragma once\n#include \"loaders/L.h\""
  loaders/L.h "#include \"materials/Material.h\""
  loaders/L.cpp "#include \"materials/Material.h\""
  materials/M.h "  #  include \"harness/headless/HeadlessRenderer.h\""
  materials/n/CMakeLists.txt "osgbtf_method(RENDER N.cpp FIT NFit.cpp OWN NOwn.cpp)"
  materials/n/N.cpp "#include \"scene/MaterialNode.h\""
  materials/n/NFit.cpp "#include \"fit/FitCache.h\"\n#include \"harness/Compare.h\""
  materials/n/NOwn.cpp "#include \"fit/FitCache.h\""
  materials/n/test/n_test.cpp "#include \"harness/H.h\"\n#include \"tools/btf/Commands.h\""
  synthesis/K.h "#include \"materials/Material.h\""
  scene/S.h "#include \"harness/MaterialImage.h\""
  scene/F.h "#include \"fit/FitCache.h\""
  plugins/btf/P.cpp "#include \"core/A.h\"\n#include \"harness/Compare.h\""
  fuzz/F.cpp "#include \"tools/btf/Commands.h\"")
expect(${WORK}/bad
  "core/A.h: includes \"loaders/L.h\", but core/ may include only core/"
  "loaders/L.cpp: includes \"materials/Material.h\", but loaders/ may include only core/, loaders/"
  "loaders/L.h: includes \"materials/Material.h\", but loaders/ may include only core/, loaders/"
  "materials/M.h: includes \"harness/headless/HeadlessRenderer.h\", but materials/ may include only core/, materials/"
  "materials/n/N.cpp: includes \"scene/MaterialNode.h\", but materials/ may include only core/, materials/"
  "materials/n/NOwn.cpp: includes \"fit/FitCache.h\", but materials/ may include only core/, materials/"
  "synthesis/K.h: includes \"materials/Material.h\", but synthesis/ may include only core/, synthesis/"
  "scene/F.h: includes \"fit/FitCache.h\", but scene/ may include only core/, loaders/, materials/, synthesis/, scene/"
  "scene/S.h: includes \"harness/MaterialImage.h\", but scene/ may include only core/, loaders/, materials/, synthesis/, scene/"
  "plugins/btf/P.cpp: includes \"harness/Compare.h\", but plugins/ may include only core/, loaders/, materials/, synthesis/, scene/, fit/, streaming/, environment/, plugins/"
  "fuzz/F.cpp: includes \"tools/btf/Commands.h\", but fuzz/ may include only core/, loaders/, materials/, synthesis/, scene/, fit/, streaming/, environment/, harness/, plugins/, fuzz/"
  "materials/n/test/n_test.cpp: includes \"tools/btf/Commands.h\", but a method's test/ (the tests layer) may include only core/, loaders/, materials/, synthesis/, scene/, fit/, streaming/, environment/, harness/, plugins/, fuzz/, tests/"
  "materials/n/NFit.cpp (osgBTFFit): includes \"harness/Compare.h\", but osgBTFFit may include only core/, loaders/, materials/, synthesis/, scene/, fit/")

# Per library: a method's fit source (libosgBTFFit's) may include fit/, its render source
# (libosgBTF's) may not, nor may the runtime include streaming/ or environment/.
function(expect_library root library files)
  osgbtf_library_include_violations(${root} ${library} "${files}" got)
  if(NOT "${got}" STREQUAL "${ARGN}")
    list(JOIN got "\n  " got_text)
    list(JOIN ARGN "\n  " want_text)
    message(FATAL_ERROR "${root} ${library}: expected\n  ${want_text}\ngot\n  ${got_text}")
  endif()
endfunction()
write_tree(${WORK}/libraries
  materials/ptm/PtmFit.cpp "#include \"fit/LightBasisFit.h\"\n#include \"materials/ptm/Ptm.h\""
  materials/ptm/Ptm.cpp "#include \"core/A.h\"\n#include \"fit/LightBasisFit.h\""
  scene/Node.cpp "#include \"streaming/TileSet.h\"\n#include \"environment/VertexEnvironment.h\""
  environment/Group.cpp "#include \"scene/MaterialNode.h\"\n#include \"fit/FitCache.h\"")
expect_library(${WORK}/libraries osgBTFFit "materials/ptm/PtmFit.cpp")
expect_library(${WORK}/libraries osgBTF "scene/Node.cpp;materials/ptm/Ptm.cpp"
  "materials/ptm/Ptm.cpp (osgBTF): includes \"fit/LightBasisFit.h\", but osgBTF may include only core/, loaders/, materials/, synthesis/, scene/"
  "scene/Node.cpp (osgBTF): includes \"streaming/TileSet.h\", but osgBTF may include only core/, loaders/, materials/, synthesis/, scene/"
  "scene/Node.cpp (osgBTF): includes \"environment/VertexEnvironment.h\", but osgBTF may include only core/, loaders/, materials/, synthesis/, scene/")
expect_library(${WORK}/libraries osgBTFEnvironment "environment/Group.cpp"
  "environment/Group.cpp (osgBTFEnvironment): includes \"fit/FitCache.h\", but osgBTFEnvironment may include only core/, loaders/, materials/, synthesis/, scene/, environment/")

# Include cycles: each reported once, from its alphabetically first header; a same-folder include
# resolves beside the including file. Acyclic diamonds are fine.
function(expect_cycles root)
  osgbtf_include_cycles(${root} got)
  if(NOT "${got}" STREQUAL "${ARGN}")
    list(JOIN got "\n  " got_text)
    list(JOIN ARGN "\n  " want_text)
    message(FATAL_ERROR "${root}: expected\n  ${want_text}\ngot\n  ${got_text}")
  endif()
endfunction()
write_tree(${WORK}/acyclic
  core/A.h "#include \"core/B.h\"\n#include \"core/C.h\""
  core/B.h "#include \"core/D.h\""
  core/C.h "#include \"D.h\""
  core/D.h "#pragma once")
expect_cycles(${WORK}/acyclic)
write_tree(${WORK}/cycles
  materials/Material.h "#include \"materials/Options.h\"\n#include \"materials/Registry.h\""
  materials/Options.h "#pragma once"
  materials/Registry.h "#include \"Material.h\""
  core/Self.h "#include \"core/Self.h\""
  scene/X.h "#include \"scene/Y.h\""
  scene/Y.h "#include \"scene/Z.h\""
  scene/Z.h "#include \"scene/X.h\"")
expect_cycles(${WORK}/cycles
  "include cycle: core/Self.h -> core/Self.h"
  "include cycle: materials/Material.h -> materials/Registry.h -> materials/Material.h"
  "include cycle: scene/X.h -> scene/Y.h -> scene/Z.h -> scene/X.h")
message(STATUS "layer checker: fake trees give the expected messages")
