// SLAF and its GPU twin: the fragment shader (view table blend included) equals
// SlafMaterial::evaluate.
#include <gtest/gtest.h>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/slaf/Slaf.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

TEST(SlafGpu, MatchesCpuAtMeasuredAndUnmeasuredDirections) {
    SampleOptions options;
    options.width = 8;
    options.height = 6;  // not square: catches swapped axes
    const MeasuredBtf btf = makeSampleBtf(options);
    osg::ref_ptr<SlafMaterial> material =
        SlafMaterial::fit(btf, FitOptions::parse("iterations=20 rounds=1"));
    const DirectionSet& d = btf.views();
    std::vector<std::pair<glm::vec3, glm::vec3>> pairs;
    // 20 measured (view, light) pairs spread over the 81 x 81, grazing ones included.
    for (int i = 0; i < 20; ++i)
        pairs.push_back({d.vector((i * 37 + 3) % 81), d.vector((i * 53 + 11) % 81)});
    // 5 unmeasured ones.
    const std::vector<std::pair<Direction, Direction>> unmeasured = {{{31.7f, 77}, {52, 200}},
                                                                     {{8, 10}, {67, 300}},
                                                                     {{72, 181}, {12, 5}},
                                                                     {{50, 250}, {50, 70}},
                                                                     {{20, 130}, {80, 320}}};
    for (const auto& [v, l] : unmeasured) pairs.push_back({v.toVector(), l.toVector()});
    for (const auto& [view, light] : pairs) {
        const test::GpuCpuComparison r = test::compareGpuWithCpu(*material, view, light);
        EXPECT_GT(r.pixelsCompared, 48);
        EXPECT_LE(r.maxAbsDifference, 1e-3) << r.worst;
    }
}

TEST(SlafGpu, OneLobeMaterialRendersToo) {
    SampleOptions options;
    options.width = 5;
    options.height = 3;
    osg::ref_ptr<SlafMaterial> material = SlafMaterial::fit(
        makeSampleBtf(options), FitOptions::parse("lobes=1 iterations=10 rounds=0"));
    const test::GpuCpuComparison r = test::compareGpuWithCpu(
        *material, Direction{30, 60}.toVector(), Direction{45, 200}.toVector());
    EXPECT_LE(r.maxAbsDifference, 1e-3) << r.worst;
}

}  // namespace OSGBTF_TEST_FILE
