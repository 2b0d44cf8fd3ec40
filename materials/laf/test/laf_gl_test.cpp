// Method "laf" on the GPU, its cases of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp): the
// fragment shader (materials/laf/laf.frag) equals LafMaterial::evaluate at measured and unmeasured
// directions, and a one-lobe material renders too.
#include "materials/laf/Laf.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

const bool kCases = test::registerGpuCases(
    LafMaterial::kMethod,
    {{"iterations=20", test::GpuCase::sampleOfSize(8, 6), test::spreadPairs(20, 5),
      test::fixedBound(1e-3)},
     {"lobes=1 iterations=10", test::GpuCase::sampleOfSize(5, 3),
      test::vectorPairs({{{30, 60}, {45, 200}}}), test::fixedBound(1e-3), -1}});

}  // namespace OSGBTF_TEST_FILE
