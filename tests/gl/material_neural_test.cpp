// Method "neural": the fragment shader (materials/neural/neural.frag) runs the decoder network as
// NeuralMaterial::evaluate does, at measured (view, light) pairs and between them, for one to
// four hidden layers (the shader's two alternating halves of its hidden buffer) and the largest
// shape.
#include <gtest/gtest.h>

#include <iostream>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/MethodPrograms.h"
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

TEST(NeuralGpu, TheShapeIsCompiledInAndSmallNetworksReadTheirWeightsFromUniforms) {
    const DirectionSet d = DirectionSet::bonn81();
    const auto shaped = [&](int latent, int layers, int units) {
        osg::ref_ptr<NeuralMaterial> m = new NeuralMaterial;
        m->setShape(4, 3, d, d, latent, layers, units);
        for (std::size_t i = 0; i < m->decoder.data.size(); ++i)
            m->decoder.data[i] = float(i % 97) * 0.01f;
        return m;
    };
    // The default network (L 8, 2 x 32): per group of 4 neurons 1 + inputs vec4, inputs 8 + 8
    // features, then 32, the output's one group on 32: 8 x 17 + 8 x 33 + 33.
    const osg::ref_ptr<NeuralMaterial> standard = shaped(8, 2, 32);
    EXPECT_EQ(standard->gpuWeightVectors(), 8 * 17 + 8 * 33 + 33);
    EXPECT_EQ(standard->shaderDefines(),
              (std::vector<std::string>{"OSGBTF_NEURAL_LATENT_GROUPS 2", "OSGBTF_NEURAL_LAYERS 2",
                                        "OSGBTF_NEURAL_UNITS 32", "OSGBTF_NEURAL_WEIGHTS 433"}));
    // The largest (L 32, 4 x 64): 16 x 41 + 3 x 16 x 65 + 65 vec4, more than the uniforms hold.
    const osg::ref_ptr<NeuralMaterial> largest = shaped(32, 4, 64);
    EXPECT_EQ(largest->gpuWeightVectors(), 16 * 41 + 3 * 16 * 65 + 65);
    EXPECT_FALSE(largest->usesUniformWeights());
    EXPECT_EQ(largest->shaderDefines().size(), 3u);
    // Both layouts hold the same numbers: group by group, the texture's row without its padding.
    for (const osg::ref_ptr<NeuralMaterial>& m : {standard, largest}) {
        const std::vector<float> packed = m->gpuWeights();
        const MaterialTexture rows = m->gpuDecoder();
        std::size_t at = 0;
        for (int k = 0; k <= m->hiddenLayers(); ++k)
            for (int g = 0; g < (m->layerOutputs(k) + 3) / 4; ++g) {
                const int row = k * m->units() / 4 + g;
                for (int v = 0; v < 1 + m->layerInputs(k); ++v, at += 4)
                    for (int c = 0; c < 4; ++c)
                        ASSERT_EQ(packed[at + c],
                                  rows.data[(std::size_t(row) * rows.width + v) * 4 + c])
                            << "layer " << k << " group " << g << " vec4 " << v;
            }
        EXPECT_EQ(at, packed.size());
    }
    // One program per shape, named by its defines; the state sets bind what the program reads.
    EXPECT_NE(methodProgram(*standard).get(), methodProgram(*largest).get());
    EXPECT_EQ(methodProgram(*standard).get(), methodProgram(*shaped(8, 2, 32)).get());
    EXPECT_NE(methodProgram(*standard)->getName().find("OSGBTF_NEURAL_WEIGHTS=433"),
              std::string::npos);
    EXPECT_NE(standard->sharedStateSet()->getUniform("neuralWeights"), nullptr);
    EXPECT_EQ(standard->sharedStateSet()->getUniform("neuralUnits"), nullptr);
    EXPECT_EQ(largest->sharedStateSet()->getUniform("neuralWeights"), nullptr);
}

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
