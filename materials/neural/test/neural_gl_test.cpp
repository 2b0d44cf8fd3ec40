// Method "neural" on the GPU, its cases of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp):
// the fragment shader (materials/neural/neural.frag) runs the decoder network as
// NeuralMaterial::evaluate does, at measured (view, light) pairs and between them, for one to
// four hidden layers (the shader's two alternating halves of its hidden buffer) and the largest
// shape; and the network's shape compiled into its program, the weights read from uniforms.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "materials/MethodPrograms.h"
#include "materials/neural/Neural.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

std::vector<test::GpuCase> cases() {
    const auto pairs = test::spreadPairs(6, 3);
    std::vector<test::GpuCase> all;
    for (const char* options : {"latent=4 units=8 layers=1 steps=40 batch=256",
                                "latent=8 units=12 layers=3 steps=40 batch=256",
                                "latent=32 units=64 layers=4 steps=20 batch=256"})
        all.push_back({options, test::GpuCase::sampleOfSize(8, 6), pairs, test::fixedBound(1e-4)});
    return all;
}

const bool kCases = test::registerGpuCases(NeuralMaterial::kMethod, cases());

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

}  // namespace OSGBTF_TEST_FILE
