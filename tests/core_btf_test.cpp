#include <cmath>
#include <limits>

#include <gtest/gtest.h>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "core/MeasuredBtf.h"
#include "harness/sample/SampleBtf.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {
/** Restores the memory limit a test changed. */
struct MemoryLimitGuard {
    std::uint64_t saved = memoryLimit();
    ~MemoryLimitGuard() { setMemoryLimit(saved); }
};
DirectionSet threeDirections() {
    return DirectionSet("three", {{0, 0}, {30, 0}, {30, 90}});
}
}  // namespace

TEST(MemoryGuard, RefusesBeforeAllocating) {
    MemoryLimitGuard guard;
    setMemoryLimit(1 << 20);
    // 400 * 400 * 151 * 151 * 3 * 4 bytes = 43.78e9 bytes = 40.77 GiB.
    try {
        MeasuredBtf btf(400, 400, DirectionSet::ubo2014(), DirectionSet::ubo2014());
        FAIL() << "allocated";
    } catch (const Error& e) {
        const std::string message = e.what();
        EXPECT_NE(message.find("BTF of 400x400 texels x 151 views x 151 lights: needs 40.8 GiB"),
                  std::string::npos)
            << message;
        EXPECT_NE(message.find("memory limit of 1.0 MiB"), std::string::npos) << message;
    }
}

TEST(MemoryGuard, AbsurdSizesDoNotOverflow) {
    EXPECT_EQ(MeasuredBtf::bytesNeeded(1 << 30, 1 << 30, 1u << 30, 1u << 30, Storage::Float),
              UINT64_MAX);
}

TEST(MemoryGuard, ParsesByteCounts) {
    EXPECT_EQ(parseBytes("16G"), 16ull << 30);
    EXPECT_EQ(parseBytes("512M"), 512ull << 20);
    EXPECT_EQ(parseBytes("1000"), 1000u);
    EXPECT_THROW(parseBytes("lots"), Error);
    EXPECT_THROW(parseBytes("-5G"), Error);
}

TEST(MeasuredBtf, InvalidDimensionsAreRefused) {
    EXPECT_THROW(MeasuredBtf(0, 4, threeDirections(), threeDirections()), Error);
}

TEST(MeasuredBtf, ImageAndAbrdfViewsAgree) {
    for (Storage storage : {Storage::Float, Storage::Half}) {
        MeasuredBtf btf(3, 2, threeDirections(), threeDirections(), storage);
        for (std::size_t v = 0; v < 3; ++v)
            for (std::size_t l = 0; l < 3; ++l)
                for (std::size_t t = 0; t < 6; ++t)
                    for (int c = 0; c < 3; ++c)
                        btf.setValue(v, l, t, c, float(v * 100 + l * 10 + t) + c * 0.25f);
        EXPECT_EQ(btf.memoryBytes(), MeasuredBtf::bytesNeeded(3, 2, 3, 3, storage));
        const std::vector<float> image = btf.image(2, 1);
        EXPECT_EQ(image[5 * 3 + 2], 215.5f);
        const std::vector<float> abrdf = btf.abrdf(4);
        EXPECT_EQ(abrdf[(1 * 3 + 2) * 3 + 1], 124.25f);
        std::vector<float> replaced(image.size(), 7.0f);
        btf.setImage(0, 0, replaced.data());
        EXPECT_EQ(btf.value(0, 0, 5, 2), 7.0f);
    }
}

TEST(ErrorMetrics, MatchesTheDefinitionOnAHandExample) {
    MeasuredBtf a(2, 1, threeDirections(), threeDirections()), b = a;
    // Texel 1 differs by (0.3, 0.4, 0) in one of 9 pairs: length 0.5, mean 0.5 / 9.
    b.setValue(1, 2, 1, 0, 0.3f);
    b.setValue(1, 2, 1, 1, 0.4f);
    const ErrorSummary e = computeError(a, b);
    EXPECT_NEAR(e.perTexel[1], 0.5 / 9, 1e-7);
    EXPECT_EQ(e.perTexel[0], 0.0f);
    EXPECT_NEAR(e.average, 0.25 / 9, 1e-7);
    EXPECT_EQ(e.minimum, 0.0);
    EXPECT_NEAR(e.maximum, 0.5 / 9, 1e-7);
    const double mse = 0.25 / (2 * 9 * 3);
    EXPECT_NEAR(e.rmse, std::sqrt(mse), 1e-7);
    EXPECT_NEAR(e.psnr, 10 * std::log10(1 / mse), 1e-4);
    EXPECT_TRUE(std::isinf(computeError(a, a).psnr));
}

TEST(ErrorMetrics, NanInTheModelIsCountedNotHidden) {
    MeasuredBtf a(1, 1, threeDirections(), threeDirections());
    const ErrorSummary e = computeError(a, [](std::size_t, float* out) {
        for (int i = 0; i < 27; ++i) out[i] = 0;
        out[4] = std::numeric_limits<float>::quiet_NaN();
    });
    EXPECT_EQ(e.nonFiniteValues, 1u);
    EXPECT_GT(e.average, 0.0);
}

TEST(ErrorMetrics, DifferentSizesAreRefused) {
    MeasuredBtf a(2, 1, threeDirections(), threeDirections()),
        b(1, 2, threeDirections(), threeDirections());
    EXPECT_THROW(computeError(a, b), Error);
}

TEST(SampleBtf, ValuesAreInRangeAndShadowsFollowTheLight) {
    SampleOptions options;
    options.width = options.height = 32;
    const MeasuredBtf btf = makeSampleBtf(options);
    ASSERT_EQ(btf.viewCount(), 81u);
    float lo = 1, hi = 0;
    for (std::size_t v = 0; v < 81; v += 10)
        for (std::size_t l = 0; l < 81; ++l)
            for (float x : btf.image(v, l)) {
                lo = std::min(lo, x);
                hi = std::max(hi, x);
            }
    EXPECT_GE(lo, 0.0f);
    EXPECT_LE(hi, 1.0f);
    EXPECT_GT(hi, 0.3f);
    // Grazing light from +X (phi 0) and from -X (phi 180) must darken different texels: the
    // per-texel difference between the two images is large somewhere in both directions.
    const int l0 = btf.lights().find(75, 0), l180 = btf.lights().find(75, 180);
    const std::vector<float> a = btf.image(0, l0), b = btf.image(0, l180);
    float aBrighter = 0, bBrighter = 0;
    for (std::size_t i = 0; i < a.size(); ++i) {
        aBrighter = std::max(aBrighter, a[i] - b[i]);
        bBrighter = std::max(bBrighter, b[i] - a[i]);
    }
    EXPECT_GT(aBrighter, 0.1f);
    EXPECT_GT(bBrighter, 0.1f);
}

// The weave repeats every two cells (8 texels at 16 texels and 2 threads): without variation the
// sample equals itself shifted by that period, with variation its cells differ (that is what
// makes tiling it visible and synthesis worth testing on it).
TEST(SampleBtf, VariationBreaksThePeriodWithinTheSample) {
    SampleOptions options;
    options.width = options.height = 16;
    options.views = DirectionSet("one", {{0, 0}});
    options.lights = DirectionSet("two", {{0, 0}, {45, 30}});
    auto largestShiftDifference = [](const MeasuredBtf& btf) {
        float largest = 0;
        for (std::size_t l = 0; l < 2; ++l) {
            const std::vector<float> image = btf.image(0, l);
            for (int y = 0; y < 16; ++y)
                for (int x = 0; x < 8; ++x)
                    for (int c = 0; c < 3; ++c)
                        largest = std::max(largest,
                                           std::fabs(image[(std::size_t(y) * 16 + x) * 3 + c] -
                                                     image[(std::size_t(y) * 16 + x + 8) * 3 + c]));
        }
        return largest;
    };
    EXPECT_LT(largestShiftDifference(makeSampleBtf(options)), 1e-4f);
    options.variation = 0.6f;
    const MeasuredBtf varied = makeSampleBtf(options);
    EXPECT_GT(largestShiftDifference(varied), 0.02f);
    EXPECT_EQ(largestShiftDifference(makeSampleBtf(options)), largestShiftDifference(varied));
}

}  // namespace OSGBTF_TEST_FILE
