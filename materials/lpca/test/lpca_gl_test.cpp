// Method "lpca" on the GPU, its case of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp):
// materials/lpca/lpca.frag equals LpcaMaterial::evaluate at 20 measured (view, light) pairs spread
// over the index range and 5 unmeasured ones (one beyond the measured 75 degrees).
#include "materials/lpca/Lpca.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

const bool kCases = test::registerGpuCases(
    LpcaMaterial::kMethod, {{"clusters=5 components=6", test::GpuCase::sampleOfSize(8, 6),
                             test::clusterPairs(), test::fixedBound(1e-3)}});

}  // namespace OSGBTF_TEST_FILE
