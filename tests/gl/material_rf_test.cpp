// Method "rf": the fragment shader (shaders/rf.frag) equals RfMaterial::evaluate, at measured
// (view, light) pairs and between them (view interpolation through the baked table).
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include "harness/sample/SampleBtf.h"
#include "materials/rf/Rf.h"
#include "tests/gl/MaterialGpuCheck.h"

using namespace osgBTF;

TEST(RfGpu, MatchesCpuAtMeasuredAndUnmeasuredDirections) {
    SampleOptions options;
    options.width = 8;
    options.height = 6;  // not square: catches swapped axes
    const MeasuredBtf btf = makeSampleBtf(options);
    osg::ref_ptr<RfMaterial> material = RfMaterial::fit(btf, {});
    std::vector<std::pair<Direction, Direction>> pairs;
    // 20 measured pairs spread over the Bonn set (every ring of views and lights is visited).
    for (std::size_t i = 0; i < 20; ++i)
        pairs.push_back({btf.views()[(i * 4 + 1) % 81], btf.lights()[(i * 23 + 5) % 81]});
    // 5 unmeasured ones, one with the view beyond the outermost ring (horizon blending).
    pairs.push_back({{31.7f, 77}, {52, 200}});
    pairs.push_back({{10, 33}, {68, 300}});
    pairs.push_back({{52.5f, 171}, {7, 45}});
    pairs.push_back({{80, 10}, {20, 100}});
    pairs.push_back({{66, 250}, {44, 135}});
    double worst = 0;
    for (const auto& [v, l] : pairs) {
        const test::GpuCpuComparison r =
            test::compareGpuWithCpu(*material, v.toVector(), l.toVector());
        worst = std::max(worst, r.maxAbsDifference);
        EXPECT_GT(r.pixelsCompared, 48) << "view " << v.theta << "/" << v.phi;
        EXPECT_LE(r.maxAbsDifference, 1e-3) << "view " << v.theta << "/" << v.phi << " light "
                                            << l.theta << "/" << l.phi << ": " << r.worst;
    }
    std::cout << "rf GPU vs CPU: largest difference " << worst << " over " << pairs.size()
              << " (view, light) pairs\n";
}
