// Method "neural": the fragment shader (materials/neural/neural.frag) runs the decoder network as
// NeuralMaterial::evaluate does, at measured (view, light) pairs and between them, for one to
// four hidden layers (the shader's two alternating halves of its hidden buffer) and the largest
// shape.
#include <gtest/gtest.h>

#include <iostream>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/neural/Neural.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

void expectGpuEqualsCpu(const std::string& options) {
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;  // not square: catches swapped axes
    const MeasuredBtf btf = makeSampleBtf(sample);
    const osg::ref_ptr<NeuralMaterial> m = NeuralMaterial::fit(btf, FitOptions::parse(options));
    const DirectionSet& d = btf.views();
    std::vector<std::pair<glm::vec3, glm::vec3>> pairs;
    for (int i = 0; i < 6; ++i)
        pairs.push_back({d.vector((i * 37 + 3) % 81), d.vector((i * 53 + 11) % 81)});
    for (const auto& [v, l] : std::vector<std::pair<Direction, Direction>>{
             {{31.7f, 77}, {52, 200}}, {{8, 10}, {67, 300}}, {{72, 181}, {12, 5}}})
        pairs.push_back({v.toVector(), l.toVector()});
    double worst = 0;
    for (const auto& [view, light] : pairs) {
        const test::GpuCpuComparison r = test::compareGpuWithCpu(*m, view, light);
        worst = std::max(worst, r.maxAbsDifference);
        EXPECT_GT(r.pixelsCompared, 48);
        EXPECT_LE(r.maxAbsDifference, 1e-4) << options << ": " << r.worst;
    }
    std::cout << "neural [" << options << "] GPU vs CPU: largest difference " << worst << "\n";
}

}  // namespace

TEST(NeuralGpu, OneHiddenLayerMatchesCpu) {
    expectGpuEqualsCpu("latent=4 units=8 layers=1 steps=40 batch=256");
}

TEST(NeuralGpu, ThreeHiddenLayersMatchCpu) {
    expectGpuEqualsCpu("latent=8 units=12 layers=3 steps=40 batch=256");
}

TEST(NeuralGpu, TheLargestNetworkMatchesCpu) {
    expectGpuEqualsCpu("latent=32 units=64 layers=4 steps=20 batch=256");
}

}  // namespace OSGBTF_TEST_FILE
