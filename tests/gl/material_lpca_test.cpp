// LPCA on the GPU (materials/lpca/lpca.frag) equals LpcaMaterial::evaluate on the CPU.
#include <gtest/gtest.h>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/lpca/Lpca.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

TEST(LpcaGpu, MatchesCpuAtMeasuredAndUnmeasuredDirections) {
    SampleOptions options;
    options.width = 8;
    options.height = 6;  // not square: catches swapped axes
    const MeasuredBtf btf = makeSampleBtf(options);
    osg::ref_ptr<LpcaMaterial> material =
        LpcaMaterial::fit(btf, FitOptions::parse("clusters=5 components=6"));
    std::vector<std::pair<Direction, Direction>> pairs;
    // 20 measured (view, light) pairs spread over the index range, and 5 unmeasured ones.
    for (std::size_t i = 0; i < 20; ++i)
        pairs.push_back({btf.views()[(i * 17) % 81], btf.lights()[(i * 29 + 5) % 81]});
    pairs.push_back({{31.7f, 77}, {52, 200}});
    pairs.push_back({{10, 300}, {70, 10}});
    pairs.push_back({{55, 133}, {5, 45}});
    pairs.push_back({{80, 190}, {40, 271}});  // beyond the measured 75 degrees
    pairs.push_back({{22, 11}, {66, 333}});
    for (const auto& [v, l] : pairs) {
        const test::GpuCpuComparison r =
            test::compareGpuWithCpu(*material, v.toVector(), l.toVector());
        EXPECT_GT(r.pixelsCompared, 48);
        EXPECT_LE(r.maxAbsDifference, 1e-3) << "view (" << v.theta << ", " << v.phi << ") light ("
                                            << l.theta << ", " << l.phi << "): " << r.worst;
    }
}

}  // namespace OSGBTF_TEST_FILE
