// Method "lambert" on the GPU, its case of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp):
// the material framework end to end on its simplest method, fit, CPU reference, GPU == CPU.
#include "materials/lambert/Lambert.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

const bool kCases = test::registerGpuCases(LambertMaterial::kMethod,
                                           {{"", test::GpuCase::sampleOfSize(8, 6),
                                             test::vectorPairs({{{0, 0}, {0, 0}},
                                                                {{45, 20}, {60, 126}},
                                                                {{75, 345}, {30, 90}},
                                                                {{31.7f, 77}, {52, 200}}}),
                                             test::fixedBound(1e-5)}});

}  // namespace OSGBTF_TEST_FILE
