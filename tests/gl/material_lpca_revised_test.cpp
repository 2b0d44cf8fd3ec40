// Revised LPCA on the GPU (materials/lpca-revised/lpca-revised.frag, hardware trilinear filtering
// of the 3D grid) equals LpcaRevisedMaterial::evaluate on the CPU; the 8-bit grid within its
// quantisation bound (GPUs may filter 8-bit textures with 8-bit fractional weights).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/lpca-revised/LpcaRevised.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

std::vector<std::pair<Direction, Direction>> directionPairs(const MeasuredBtf& btf) {
    std::vector<std::pair<Direction, Direction>> pairs;
    for (std::size_t i = 0; i < 20; ++i)
        pairs.push_back({btf.views()[(i * 17) % 81], btf.lights()[(i * 29 + 5) % 81]});
    pairs.push_back({{31.7f, 77}, {52, 200}});
    pairs.push_back({{10, 300}, {70, 10}});
    pairs.push_back({{55, 133}, {5, 45}});
    pairs.push_back({{80, 190}, {40, 271}});
    pairs.push_back({{22, 11}, {66, 333}});
    return pairs;
}

void check(const LpcaRevisedMaterial& material, const MeasuredBtf& btf, double tolerance) {
    for (const auto& [v, l] : directionPairs(btf)) {
        const test::GpuCpuComparison r =
            test::compareGpuWithCpu(material, v.toVector(), l.toVector());
        EXPECT_GT(r.pixelsCompared, 48);
        EXPECT_LE(r.maxAbsDifference, tolerance)
            << "view (" << v.theta << ", " << v.phi << ") light (" << l.theta << ", " << l.phi
            << "): " << r.worst;
    }
}

MeasuredBtf sample() {
    SampleOptions options;
    options.width = 8;
    options.height = 6;  // not square: catches swapped axes
    return makeSampleBtf(options);
}

}  // namespace

TEST(LpcaRevisedGpu, MatchesCpuAtMeasuredAndUnmeasuredDirections) {
    const MeasuredBtf btf = sample();
    osg::ref_ptr<LpcaRevisedMaterial> material =
        LpcaRevisedMaterial::fit(btf, FitOptions::parse("clusters=5 components=6 resolution=10"));
    check(*material, btf, 1e-3);
}

TEST(LpcaRevisedGpu, EightBitMatchesCpuWithinItsQuantisationBound) {
    const MeasuredBtf btf = sample();
    osg::ref_ptr<LpcaRevisedMaterial> material = LpcaRevisedMaterial::fit(
        btf, FitOptions::parse("clusters=3 components=5 resolution=8 storage=unorm8"));
    // One 8-bit step of every grid value, weighted by the folded weights alpha'_i.
    double bound = 1e-3;
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        double sum = 0;
        for (int i = 0; i < 5; ++i) sum += std::abs(material->weight(t, i)) / 255.0;
        bound = std::max(bound, sum);
    }
    std::cout << "8-bit tolerance " << bound << "\n";
    check(*material, btf, bound);
}

}  // namespace OSGBTF_TEST_FILE
