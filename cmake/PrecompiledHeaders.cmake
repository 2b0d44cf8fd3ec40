# Precompiled headers for the targets with many sources. Measured on this project (gcc 12, one
# test source at -Og): 250,000 preprocessed lines, ~98 % of them libstdc++, Eigen (with the x86
# intrinsics it pulls in), OSG and googletest, and ~60 % of the compile time is parsing them
# (-fsyntax-only 5.7 s of 9.4 s; a library source at -O2: 3.9 s of 6.4 s). Each target parses
# them once into its own PCH (targets differ in flags, so they cannot share one).
# Headers users include stay self-contained: the SDK check in .ci/run compiles a downstream
# project against the installed headers without any PCH, and OSGBTF_PCH=OFF builds everything
# as before. With ccache, PCHs need CCACHE_SLOPPINESS=pch_defines,time_macros (ccache manual).
option(OSGBTF_PCH "Precompile the third-party headers the large targets parse in every source" ON)

set(OSGBTF_PCH_STD <algorithm> <array> <atomic> <chrono> <cmath> <cstdint> <cstring> <filesystem>
    <fstream> <functional> <iostream> <limits> <map> <memory> <mutex> <numeric> <random> <set>
    <sstream> <string> <vector>)
set(OSGBTF_PCH_LIBRARIES <Eigen/Dense> <glm/glm.hpp> <Imath/half.h> <osg/Geometry> <osg/Node>
    <osg/StateSet> <osg/Texture2D> <osg/Uniform> <osgDB/ReadFile> <osgDB/Registry>)

# osgbtf_precompile_headers(target [EXTRA_HEADERS...]): the shared list plus the target's own.
function(osgbtf_precompile_headers target)
  if(OSGBTF_PCH)
    target_precompile_headers(${target} PRIVATE ${OSGBTF_PCH_STD} ${OSGBTF_PCH_LIBRARIES} ${ARGN})
  endif()
endfunction()
