# Precompiled headers for the targets with many sources. Measured on this project (gcc 12, one
# test source at -Og): 250,000 preprocessed lines, ~98 % of them libstdc++, Eigen (with the x86
# intrinsics it pulls in), OSG and googletest, and ~60 % of the compile time is parsing them
# (-fsyntax-only 5.7 s of 9.4 s; a library source at -O2: 3.9 s of 6.4 s). Each target parses
# them once into its own PCH (targets differ in flags, so they cannot share one).
# Headers users include stay self-contained: the SDK check in .ci/run compiles a downstream
# project against the installed headers without any PCH, and OSGBTF_PCH=OFF builds everything
# as before. With ccache, PCHs need CCACHE_SLOPPINESS=pch_defines,time_macros (ccache manual).
#
# Default: on with clang, off with GCC. GCC maps its whole PCH (~290 MB for the library's list)
# into every source, parsed or not: an empty source with it costs ~5 s of CPU, so every source
# that includes little pays more than it saves. Measured (gcc 12, -O2, each source compiled with
# and without back to back): 15 library sources 89 CPU-s without against 128 s with (0.70x;
# core/BtfSource.cpp 1.3 s against 6.7 s), test and tool sources about even (fmf's unit tests,
# materials/fmf/test/fmf_test.cpp, 10.6 against 10.1, btf's FitCommand 11.5 against 10.8), and each PCH costs ~25 s to make. clang
# reads a PCH lazily (core/Error.cpp 0.50 s with it, 0.54 s without), so it keeps them.
if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
  set(osgbtf_pch_default ON)
else()
  set(osgbtf_pch_default OFF)
endif()
option(OSGBTF_PCH "Precompile the third-party headers the large targets parse in every source"
       ${osgbtf_pch_default})

set(OSGBTF_PCH_STD <algorithm> <array> <atomic> <chrono> <cmath> <cstdint> <cstring> <filesystem>
    <fstream> <functional> <iostream> <limits> <map> <memory> <mutex> <numeric> <random> <set>
    <sstream> <string> <vector>)
set(OSGBTF_PCH_LIBRARIES <Eigen/Dense> <glm/glm.hpp> <Imath/half.h> <osg/Geometry> <osg/Node>
    <osg/StateSet> <osg/Texture2D> <osg/Uniform> <osgDB/ReadFile> <osgDB/Registry>)

# osgbtf_precompile_headers(target [EXTRA_HEADERS...]): the shared list plus the target's own.
function(osgbtf_precompile_headers target)
  if(OSGBTF_PCH)
    target_precompile_headers(${target} PRIVATE ${OSGBTF_PCH_STD} ${OSGBTF_PCH_LIBRARIES} ${ARGN})
    # ccache hashes the PCH's bytes into every object that uses it. clang writes the header's
    # mtime (new in every configure) and the working directory into the PCH: without these two
    # flags no object of a clang build is ever reused from another build folder (measured: 0 hits
    # across two clones; with them and the same source path, identical PCHs). Each only changes
    # what is recorded, not the code.
    if(CMAKE_CXX_COMPILER_ID STREQUAL "Clang")
      target_compile_options(${target} PRIVATE "SHELL:-Xclang -fno-pch-timestamp"
                                               -ffile-compilation-dir=.)
    endif()
  endif()
endfunction()
