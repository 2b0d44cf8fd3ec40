// Method "slaf" on the GPU, its cases of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp): the
// fragment shader (materials/slaf/slaf.frag, view table blend included) equals
// SlafMaterial::evaluate at measured and unmeasured directions, and a one-lobe material renders
// too.
#include "materials/slaf/Slaf.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

const bool kCases = test::registerGpuCases(
    SlafMaterial::kMethod,
    {{"iterations=20 rounds=1", test::GpuCase::sampleOfSize(8, 6), test::spreadPairs(20, 5),
      test::fixedBound(1e-3)},
     {"lobes=1 iterations=10 rounds=0", test::GpuCase::sampleOfSize(5, 3),
      test::vectorPairs({{{30, 60}, {45, 200}}}), test::fixedBound(1e-3), -1}});

}  // namespace OSGBTF_TEST_FILE
