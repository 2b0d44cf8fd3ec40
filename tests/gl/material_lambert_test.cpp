// The material framework end to end on its simplest method: fit, CPU reference, GPU == CPU.
#include <gtest/gtest.h>

#include "harness/sample/SampleBtf.h"
#include "materials/lambert/Lambert.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

TEST(LambertGpu, MatchesCpuAtMeasuredAndUnmeasuredDirections) {
    SampleOptions options;
    options.width = 8;
    options.height = 6;  // not square: catches swapped axes
    const MeasuredBtf btf = makeSampleBtf(options);
    osg::ref_ptr<LambertMaterial> material = LambertMaterial::fit(btf, {});
    const std::vector<std::pair<Direction, Direction>> pairs = {
        {{0, 0}, {0, 0}}, {{45, 20}, {60, 126}}, {{75, 345}, {30, 90}}, {{31.7f, 77}, {52, 200}}};
    for (const auto& [v, l] : pairs) {
        const test::GpuCpuComparison r =
            test::compareGpuWithCpu(*material, v.toVector(), l.toVector());
        EXPECT_GT(r.pixelsCompared, 48);
        EXPECT_LE(r.maxAbsDifference, 1e-5) << r.worst;
    }
}

}  // namespace OSGBTF_TEST_FILE
