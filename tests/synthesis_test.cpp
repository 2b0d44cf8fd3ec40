// k-coherence synthesis and make-tileable (synthesis/): option errors, determinism, maps inside
// the sample, the quality figures on maps whose figures are known, a periodic sample's map is
// coherent modulo the period, and the edge blending's derived bounds.
#include <algorithm>
#include <cmath>
#include <cstdint>
#include <set>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include "core/CoordinateMap.h"
#include "core/Error.h"
#include "harness/sample/SampleBtf.h"
#include "synthesis/KCoherence.h"
#include "synthesis/Tileable.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

DirectionSet twoLights() {
    return DirectionSet("two", {{0, 0}, {45, 90}});
}
DirectionSet oneView() {
    return DirectionSet("one", {{0, 0}});
}

std::uint64_t nextRandom(std::uint64_t& state) {
    state = state * 6364136223846793005ull + 1442695040888963407ull;
    return state >> 33;
}

/** A sample that repeats a random period x period tile: every texel of the tile differs from the
 *  others (with probability 1), so equal values mean equal positions modulo the period. */
MeasuredBtf periodicSample(int size, int period) {
    MeasuredBtf btf(size, size, oneView(), twoLights());
    std::uint64_t state = 12345;
    std::vector<float> tile(std::size_t(period) * period * 6);
    for (float& v : tile) v = float(nextRandom(state) % 100000) / 100000.0f;
    for (std::size_t light = 0; light < 2; ++light) {
        std::vector<float> image(std::size_t(size) * size * 3);
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x)
                for (int c = 0; c < 3; ++c)
                    image[(std::size_t(y) * size + x) * 3 + c] =
                        tile[((std::size_t(y % period) * period + x % period) * 2 + light) * 3 + c];
        btf.setImage(0, light, image.data());
    }
    return btf;
}

/** The built-in woven sample (periodic: two weave repeats per side, so it tiles) with few
 *  directions. */
MeasuredBtf weave(int size) {
    SampleOptions options;
    options.width = options.height = size;
    options.views = DirectionSet("v", {{0, 0}, {45, 0}});
    options.lights = DirectionSet("l", {{0, 0}, {45, 90}, {60, 180}});
    return makeSampleBtf(options);
}

SynthesisOptions small(int size, int levels) {
    SynthesisOptions options;
    options.width = options.height = size;
    options.levels = levels;
    options.k = 3;
    options.neighbourhood = 2;
    return options;
}

int positiveModulo(int a, int m) {
    return ((a % m) + m) % m;
}

}  // namespace

TEST(Synthesis, OptionErrorsNameTheOptionAndTheProblem) {
    SynthesisOptions o = small(32, 3);
    EXPECT_EQ(errorOf([&] { validateSynthesisOptions(o, 16, 16, 6561); }),
              "--levels 3: the coarsest level of the 16x16 sample is 4x4, smaller than the 5x5 "
              "neighbourhood of --neighbourhood 2; use fewer levels");
    EXPECT_EQ(errorOf([&] { validateSynthesisOptions(o, 30, 32, 6561); }),
              "--levels 3: the sample's sides (30x32) must be multiples of 4");
    o = small(32, 2);
    EXPECT_EQ(errorOf([&] { validateSynthesisOptions(o, 16, 16, 6561); }), "no error");
    o.k = 0;
    EXPECT_EQ(errorOf([&] { validateSynthesisOptions(o, 16, 16, 6561); }),
              "--k must be in 1..64, got 0");
    o = small(32, 2);
    o.images = 7000;
    EXPECT_EQ(errorOf([&] { validateSynthesisOptions(o, 16, 16, 6561); }),
              "--images 7000: the sample has only 6561 images");
    o = small(0, 2);
    EXPECT_EQ(errorOf([&] { validateSynthesisOptions(o, 16, 16, 6561); }),
              "--size must be positive, got 0x0");
    const MeasuredBtf sample = periodicSample(16, 4);
    o = small(32, 3);
    EXPECT_EQ(errorOf([&] { analyseSample(sample, o); }),
              "--levels 3: the coarsest level of the 16x16 sample is 4x4, smaller than the 5x5 "
              "neighbourhood of --neighbourhood 2; use fewer levels");
}

TEST(Synthesis, DeterministicForASeedAndInsideTheSample) {
    const MeasuredBtf sample = weave(16);
    SynthesisOptions options = small(41, 2);  // odd: the finest level crops a coarser one
    options.height = 23;
    options.seed = 7;
    const SampleAnalysis analysis = analyseSample(sample, options);
    const CoordinateMap a = synthesizeMap(analysis, options);
    const CoordinateMap b = synthesizeMap(analyseSample(sample, options), options);
    EXPECT_EQ(a.coordinates, b.coordinates);
    ASSERT_EQ(a.width, 41);
    ASSERT_EQ(a.height, 23);
    EXPECT_EQ(a.sampleWidth, 16);
    EXPECT_EQ(a.sampleHeight, 16);
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x < a.width; ++x) {
            ASSERT_GE(a.sampleX(x, y), 0);
            ASSERT_LT(a.sampleX(x, y), 16);
            ASSERT_GE(a.sampleY(x, y), 0);
            ASSERT_LT(a.sampleY(x, y), 16);
        }
    options.seed = 8;
    EXPECT_NE(synthesizeMap(analysis, options).coordinates, a.coordinates);
}

TEST(Synthesis, SameResultOnOneThread) {
    // Fixed 256-texel chunks in every parallel step: 1024 texels are 4 chunks, the projection
    // (18 values to 8) and k-means (64 textons) both run.
    const MeasuredBtf sample = weave(32);
    SynthesisOptions options = small(40, 2);
    options.dimensions = 8;
    options.textons = 64;
    const SampleAnalysis analysis = analyseSample(sample, options);
    const CoordinateMap map = synthesizeMap(analysis, options);
    tbb::global_control one(tbb::global_control::max_allowed_parallelism, 1);
    const SampleAnalysis serial = analyseSample(sample, options);
    EXPECT_EQ(serial.levels.back().features, analysis.levels.back().features);
    EXPECT_EQ(serial.levels.back().texton, analysis.levels.back().texton);
    EXPECT_EQ(serial.levels.back().similar, analysis.levels.back().similar);
    EXPECT_EQ(synthesizeMap(serial, options).coordinates, map.coordinates);
}

TEST(Synthesis, QualityFiguresOfKnownMaps) {
    const MeasuredBtf sample = periodicSample(16, 4);
    const SampleAnalysis analysis = analyseSample(sample, small(16, 2));
    // The sample itself: every pair coherent, the same adjacent pairs as the sample's.
    CoordinateMap identity(16, 16, 16, 16);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) identity.sampleX(x, y) = x, identity.sampleY(x, y) = y;
    SynthesisQuality q = measureSynthesis(analysis, identity);
    EXPECT_EQ(q.coherenceRate, 1.0);
    EXPECT_NEAR(q.seamRatio, 1.0, 1e-12);
    EXPECT_GT(q.sampleMeanDistance, 0.0);
    // One texel everywhere: no pair coherent, no difference at all.
    const CoordinateMap constant(8, 8, 16, 16);
    q = measureSynthesis(analysis, constant);
    EXPECT_EQ(q.coherenceRate, 0.0);
    EXPECT_EQ(q.seamRatio, 0.0);
    // Shifted by half a period along x: still 4-periodic content but every source jumps by 2
    // along x, so no horizontal pair is coherent while every vertical one is (rate 1/2).
    CoordinateMap jumps(16, 16, 16, 16);
    for (int y = 0; y < 16; ++y)
        for (int x = 0; x < 16; ++x) jumps.sampleX(x, y) = (3 * x) % 16, jumps.sampleY(x, y) = y;
    q = measureSynthesis(analysis, jumps);
    EXPECT_NEAR(q.coherenceRate, 0.5, 1e-12);
}

TEST(Synthesis, PeriodicSampleGivesAMapCoherentModuloThePeriod) {
    // Every texel has a zero-distance candidate (the neighbours it sees agree modulo the period,
    // by induction over the scanline and from the coarser level), the textons are exact (no
    // more texels than textons) and equal values mean equal positions modulo the period: so
    // every adjacent pair must advance by exactly one texel modulo 4. Jumps (patch -1) go to
    // the most similar texels, all of them period translates here (distance 0), so they must
    // keep that too.
    const int period = 4;
    const MeasuredBtf sample = periodicSample(16, period);
    for (int k : {1, 3})
        for (int patch : {0, -1}) {
            SynthesisOptions options = small(37, 2);
            options.height = 29;
            options.k = k;
            options.patch = patch;
            options.seed = 3;
            const CoordinateMap map = synthesizeMap(analyseSample(sample, options), options);
            int broken = 0;
            for (int y = 0; y < map.height; ++y)
                for (int x = 0; x < map.width; ++x) {
                    if (x + 1 < map.width) {
                        broken += positiveModulo(map.sampleX(x + 1, y) - map.sampleX(x, y) - 1,
                                                 period) != 0;
                        broken +=
                            positiveModulo(map.sampleY(x + 1, y) - map.sampleY(x, y), period) != 0;
                    }
                    if (y + 1 < map.height) {
                        broken +=
                            positiveModulo(map.sampleX(x, y + 1) - map.sampleX(x, y), period) != 0;
                        broken += positiveModulo(map.sampleY(x, y + 1) - map.sampleY(x, y) - 1,
                                                 period) != 0;
                    }
                }
            EXPECT_EQ(broken, 0) << "k " << k << ", patch " << patch;
        }
}

TEST(Synthesis, TileableSampleSeamRatioAndRandomPatches) {
    const MeasuredBtf sample = weave(32);
    SynthesisOptions options = small(96, 2);
    options.seed = 11;
    const SampleAnalysis analysis = analyseSample(sample, options);
    const CoordinateMap map = synthesizeMap(analysis, options);
    const SynthesisQuality q = measureSynthesis(analysis, map);
    EXPECT_LE(q.seamRatio, 2.0);
    EXPECT_GT(q.coherenceRate, 0.5);
    // Not one copy of the sample tiled: the offsets (source - position) of the output texels
    // take several values (a tiling has exactly one).
    std::set<std::pair<int, int>> offsets;
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x)
            offsets.insert({positiveModulo(map.sampleX(x, y) - x, 32),
                            positiveModulo(map.sampleY(x, y) - y, 32)});
    EXPECT_GT(offsets.size(), 4u);
}

TEST(Synthesis, ImageSelectionAndProjectionSizes) {
    const MeasuredBtf sample = weave(16);
    SynthesisOptions options = small(16, 1);
    options.images = 2;  // of 6: images 0 and 3
    SampleAnalysis analysis = analyseSample(sample, options);
    EXPECT_EQ(analysis.images, (std::vector<std::size_t>{0, 3}));
    EXPECT_EQ(analysis.valuesPerTexel, 6u);
    EXPECT_EQ(analysis.levels.back().dimensions, 6);  // fewer values than --dimensions: as is
    options.images = 0;
    options.dimensions = 8;
    analysis = analyseSample(sample, options);
    EXPECT_EQ(analysis.valuesPerTexel, 18u);
    EXPECT_EQ(analysis.levels.back().dimensions, 8);
    EXPECT_EQ(analysis.levels.back().similarCount, 4);  // max(k - 1, jump targets)
    // The candidate lists never hold the texel itself.
    const SynthesisLevel& level = analysis.levels.back();
    for (std::size_t p = 0; p < level.texels(); ++p)
        for (int j = 0; j < level.similarCount; ++j)
            ASSERT_NE(level.similar[p * level.similarCount + j], std::int32_t(p));
}

namespace {

/** Largest |difference| over the given pairs of texels, all images and channels. */
template <typename Pairs>
float largestDifference(const MeasuredBtf& btf, const Pairs& pairs) {
    float largest = 0;
    for (std::size_t v = 0; v < btf.viewCount(); ++v)
        for (std::size_t l = 0; l < btf.lightCount(); ++l)
            for (const auto& [a, b] : pairs)
                for (int c = 0; c < 3; ++c)
                    largest =
                        std::max(largest, std::abs(btf.value(v, l, a, c) - btf.value(v, l, b, c)));
    return largest;
}

MeasuredBtf randomSample(int width, int height) {
    MeasuredBtf btf(width, height, oneView(), twoLights());
    std::uint64_t state = 99;
    for (std::size_t l = 0; l < 2; ++l)
        for (std::size_t t = 0; t < btf.texelCount(); ++t)
            for (int c = 0; c < 3; ++c)
                btf.setValue(0, l, t, c, float(nextRandom(state) % 100000) / 100000.0f);
    return btf;
}

}  // namespace

TEST(MakeTileable, BorderErrors) {
    EXPECT_EQ(errorOf([] { validateTileBorder(9, 16, 20); }),
              "--border 9: must be in 1..8 (half the 16x20 sample's smaller side)");
    EXPECT_EQ(errorOf([] { validateTileBorder(0, 16, 20); }),
              "--border 0: must be in 1..8 (half the 16x20 sample's smaller side)");
    EXPECT_EQ(defaultTileBorder(16, 20), 2);
    EXPECT_EQ(defaultTileBorder(4, 4), 1);
}

TEST(MakeTileable, EdgesMatchWithinTheDerivedBoundAndTheInteriorIsUntouched) {
    const int w = 20, h = 14, b = 3;
    const MeasuredBtf in = randomSample(w, h);
    const MeasuredBtf out = makeTileable(in, b);
    auto texel = [&](int x, int y) { return std::size_t(y) * w + x; };
    std::vector<std::pair<std::size_t, std::size_t>> leftRight, bottomTop, interior;
    for (int y = 0; y < h; ++y) leftRight.push_back({texel(0, y), texel(w - 1, y)});
    for (int x = 0; x < w; ++x) bottomTop.push_back({texel(x, 0), texel(x, h - 1)});
    for (int y = 0; y < h; ++y)
        for (int x = 0; x + 1 < w; ++x) interior.push_back({texel(x, y), texel(x + 1, y)});
    for (int y = 0; y + 1 < h; ++y)
        for (int x = 0; x < w; ++x) interior.push_back({texel(x, y), texel(x, y + 1)});
    // Texels at least b from every edge keep their values bit for bit.
    for (std::size_t l = 0; l < 2; ++l)
        for (int y = b; y < h - b; ++y)
            for (int x = b; x < w - b; ++x)
                for (int c = 0; c < 3; ++c)
                    ASSERT_EQ(out.value(0, l, texel(x, y), c), in.value(0, l, texel(x, y), c));
    // Derived in synthesis/Tileable.h: the row pass leaves each left-right jump e_h at
    // e_h/(2b+1); the column pass, spreading jumps that the row pass changed by at most max|e_h|,
    // leaves |e_v| + max|e_h| over 2b+1 at the top/bottom edge and adds at most half the change of
    // two left-right jumps to each, so at most 2 max|e_h|/(2b+1) there. 1e-6: float rounding.
    const float eh = largestDifference(in, leftRight), ev = largestDifference(in, bottomTop);
    const float spread = 2.0f * b + 1.0f;
    EXPECT_GT(eh, 0.5f);  // the input does not tile: there is something to blend
    EXPECT_LE(largestDifference(out, leftRight), 2.0f * eh / spread + 1e-6f);
    EXPECT_LE(largestDifference(out, bottomTop), (ev + eh) / spread + 1e-6f);
    // A tiled pair of the result shows no seam larger than its own neighbour differences.
    EXPECT_LE(std::max(largestDifference(out, leftRight), largestDifference(out, bottomTop)),
              largestDifference(out, interior));
}

TEST(MakeTileable, RowPassAloneShrinksTheJumpExactly) {
    // Equal rows: the column pass has no jump to spread (top = bottom), so the left-right jump
    // becomes exactly -e/(2b+1) and every step in the bands changes by e/(2b+1).
    const int w = 12, h = 4, b = 2;
    MeasuredBtf in(w, h, oneView(), DirectionSet("one", {{0, 0}}));
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                in.setValue(0, 0, std::size_t(y) * w + x, c, 0.1f * float(x));
    const MeasuredBtf out = makeTileable(in, b);
    const float e = in.value(0, 0, w - 1, 0) - in.value(0, 0, 0, 0);
    EXPECT_NEAR(out.value(0, 0, 0, 0) - out.value(0, 0, w - 1, 0), -e / 5.0f, 1e-6f);
    for (int x = 0; x + 1 < w; ++x) {
        const bool band = x < b || x + 1 >= w - b;
        const float step = out.value(0, 0, x + 1, 0) - out.value(0, 0, x, 0);
        EXPECT_NEAR(step, band ? 0.1f - e / 5.0f : 0.1f, 1e-6f) << x;
    }
}

}  // namespace OSGBTF_TEST_FILE
