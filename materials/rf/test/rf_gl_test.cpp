// Method "rf" on the GPU: the fragment shader (materials/rf/rf.frag) equals RfMaterial::evaluate,
// at measured (view, light) pairs and between them (view interpolation through the baked table),
// for the default model and Boßerhoff and Nicoll 2003's variants.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <random>
#include <string>

#include "materials/rf/Rf.h"
#include "tests/gl/MaterialGpuCheck.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

// The default fit, its case of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp): 20 measured
// pairs spread over the Bonn set (every ring of views and lights is visited) and 5 unmeasured
// ones, one with the view beyond the outermost ring (horizon blending).
const bool kCases =
    test::registerGpuCases(RfMaterial::kMethod, {{"", test::GpuCase::sampleOfSize(8, 6),
                                                  test::bonnPairs(20, 4, 1, 81, 23, 5,
                                                                  {{{31.7f, 77}, {52, 200}},
                                                                   {{10, 33}, {68, 300}},
                                                                   {{52.5f, 171}, {7, 45}},
                                                                   {{80, 10}, {20, 100}},
                                                                   {{66, 250}, {44, 135}}}),
                                                  test::fixedBound(1e-3)}});

// Boßerhoff and Nicoll 2003's variants (diffuse=0, colour=rgb and both): one shader with uniforms
// selecting the terms. Models with random lobes (no fit needed to exercise the shader's
// arithmetic): per view and lobe channel a broad and a glossy lobe, the rgb channels with different
// axes and exponents.
TEST(RfGpu, VariantsMatchCpu) {
    const DirectionSet bonn = DirectionSet::bonn81();
    const RfMaterial::Variant variants[] = {{false, false}, {true, true}, {false, true}};
    for (const RfMaterial::Variant& variant : variants) {
        osg::ref_ptr<RfMaterial> m = RfMaterial::create(8, 6, bonn, bonn, 2, variant);
        std::mt19937 rng(7);
        std::uniform_real_distribution<float> unit(0.0f, 1.0f);
        for (std::size_t i = 0; i < m->rhoD.size(); ++i) m->rhoD.set(i, 0.1f * unit(rng));
        for (std::size_t i = 0; i < m->rhoV.size(); ++i) m->rhoV.set(i, 0.2f + 0.6f * unit(rng));
        const std::size_t texels = m->texelCount();
        const std::size_t groups = bonn.size() * std::size_t(m->lobeChannels());
        for (std::size_t g = 0; g < groups; ++g)
            for (int i = 0; i < 2; ++i)
                for (std::size_t t = 0; t < texels; ++t) {
                    const Direction axis{unit(rng) * (i == 0 ? 30.0f : 70.0f), unit(rng) * 360};
                    const float n = i == 0 ? 0.5f + 1.5f * unit(rng) : 4.0f + 28.0f * unit(rng);
                    const glm::vec3 a = axis.toVector() * (0.8f + 0.2f * unit(rng));
                    const float lobe[] = {a.x, a.y, a.z, n};
                    m->lobes.write(((g * 2 + i) * texels + t) * 4, lobe, 4);
                }
        const std::string name = std::string(variant.diffuse ? "diffuse=1" : "diffuse=0") +
                                 (variant.rgb ? " colour=rgb" : " colour=luminance");
        // Two measured pairs and two between the measured views (one beyond the outer ring).
        const std::pair<Direction, Direction> pairs[] = {{bonn[7], bonn[40]},
                                                         {bonn[66], bonn[12]},
                                                         {{31.7f, 77}, {52, 200}},
                                                         {{80, 10}, {20, 100}}};
        double worst = 0;
        for (const auto& [v, l] : pairs) {
            const test::GpuCpuComparison r =
                test::compareGpuWithCpu(*m, v.toVector(), l.toVector());
            worst = std::max(worst, r.maxAbsDifference);
            EXPECT_GT(r.pixelsCompared, 48) << name;
            EXPECT_LE(r.maxAbsDifference, 1e-3)
                << name << ", view " << v.theta << "/" << v.phi << " light " << l.theta << "/"
                << l.phi << ": " << r.worst;
        }
        std::cout << "rf " << name << " GPU vs CPU: largest difference " << worst << "\n";
    }
}

}  // namespace OSGBTF_TEST_FILE
