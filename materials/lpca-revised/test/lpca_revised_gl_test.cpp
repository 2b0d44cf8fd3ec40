// Method "lpca-revised" on the GPU, its cases of EveryMethod/MethodGpu
// (tests/gl/method_gpu_test.cpp): materials/lpca-revised/lpca-revised.frag (hardware trilinear
// filtering of the 3D grid) equals LpcaRevisedMaterial::evaluate on the CPU; the 8-bit grid within
// its quantisation bound (GPUs may filter 8-bit textures with 8-bit fractional weights).
#include <algorithm>
#include <cmath>

#include "materials/lpca-revised/LpcaRevised.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

/** One 8-bit step of every grid value, weighted by the folded weights alpha'_i (at least 1e-3). */
double eightBitBound(const Material& material) {
    const auto& m = static_cast<const LpcaRevisedMaterial&>(material);
    double bound = 1e-3;
    for (std::size_t t = 0; t < m.texelCount(); ++t) {
        double sum = 0;
        for (int i = 0; i < 5; ++i) sum += std::abs(m.weight(t, i)) / 255.0;
        bound = std::max(bound, sum);
    }
    return bound;
}

const bool kCases = test::registerGpuCases(
    LpcaRevisedMaterial::kMethod,
    {{"clusters=5 components=6 resolution=10", test::GpuCase::sampleOfSize(8, 6),
      test::clusterPairs(), test::fixedBound(1e-3)},
     {"clusters=3 components=5 resolution=8 storage=unorm8", test::GpuCase::sampleOfSize(8, 6),
      test::clusterPairs(), test::materialBound(eightBitBound)}});

}  // namespace OSGBTF_TEST_FILE
