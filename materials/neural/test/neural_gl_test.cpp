// Method "neural" on the GPU, its cases of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp):
// the fragment shader (materials/neural/neural.frag) runs the decoder network as
// NeuralMaterial::evaluate does, at measured (view, light) pairs and between them, for one to
// four hidden layers (the shader's two alternating halves of its hidden buffer) and the largest
// shape.
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

}  // namespace OSGBTF_TEST_FILE
