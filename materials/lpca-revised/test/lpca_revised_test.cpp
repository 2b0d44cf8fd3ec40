// Revised LPCA (materials/lpca-revised): the elevated concentric map and its inverse, option
// errors, the resampled model against the LPCA it comes from, 8-bit quantisation, save/load,
// memory, and the error on the built-in sample.
#include <gtest/gtest.h>

#include <random>

#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodOptions.h"
#include "materials/lambert/Lambert.h"
#include "materials/lpca-revised/ConcentricMap.h"
#include "materials/lpca-revised/LpcaRevised.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

ErrorSummary errorOf(const MeasuredBtf& btf, const Material& m) {
    return computeError(btf, [&](std::size_t t, float* out) { m.evaluateMeasured(t, out); });
}

}  // namespace

TEST(ConcentricMap, InverseIsExactBothWays) {
    std::mt19937 random(3);
    std::uniform_real_distribution<double> unit(0.0, 1.0);
    for (int i = 0; i < 2000; ++i) {
        const glm::dvec2 p(unit(random), unit(random));
        const glm::dvec2 back = elevatedConcentricInverse(elevatedConcentricMap(p));
        EXPECT_NEAR(back.x, p.x, 1e-12);
        EXPECT_NEAR(back.y, p.y, 1e-12);
        const glm::dvec2 disc = concentricSquareToDisc(p);
        EXPECT_LE(glm::length(disc), 1.0 + 1e-12);
        const glm::dvec2 square = concentricDiscToSquare(disc);
        EXPECT_NEAR(square.x, p.x, 1e-12);
        EXPECT_NEAR(square.y, p.y, 1e-12);
        // Directions on the hemisphere round-trip too.
        const double theta = std::acos(unit(random)), phi = 2 * M_PI * unit(random);
        const glm::dvec3 d(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                           std::cos(theta));
        const glm::dvec3 again = elevatedConcentricMap(elevatedConcentricInverse(d));
        EXPECT_NEAR(glm::length(again - d), 0.0, 1e-12);
    }
    // Landmarks: the centre is the normal, the square's edge is the horizon, +s is +X.
    EXPECT_NEAR(glm::length(elevatedConcentricMap({0.5, 0.5}) - glm::dvec3(0, 0, 1)), 0, 1e-15);
    EXPECT_NEAR(glm::length(elevatedConcentricMap({1.0, 0.5}) - glm::dvec3(1, 0, 0)), 0, 1e-15);
    EXPECT_NEAR(glm::length(elevatedConcentricMap({0.5, 0.0}) - glm::dvec3(0, -1, 0)), 0, 1e-15);
    // Area preservation: z = 1 - rho^2 with rho the square's ring, so equal-area rings.
    EXPECT_NEAR(elevatedConcentricMap({0.75, 0.5}).z, 0.75, 1e-15);
}

TEST(LpcaRevised, InvalidOptionsAreRefusedWithClearMessages) {
    const MeasuredBtf btf = test::sampleBtf(4, 4);
    EXPECT_EQ(test::fitError<LpcaRevisedMaterial>(btf, "resolution=1"),
              "lpca-revised: option resolution must be an integer in 2..45, got 1");
    EXPECT_EQ(test::fitError<LpcaRevisedMaterial>(btf, "resolution=46"),
              "lpca-revised: option resolution must be an integer in 2..45, got 46");
    EXPECT_EQ(test::fitError<LpcaRevisedMaterial>(btf, "storage=float"),
              "lpca-revised: option storage must be one of half, unorm8, got float");
    EXPECT_EQ(test::fitError<LpcaRevisedMaterial>(btf, "clusters=0"),
              "lpca-revised: option clusters must be an integer in 1..256, got 0");
    EXPECT_EQ(test::fitError<LpcaRevisedMaterial>(btf, "clusters=200 resolution=16"),
              "lpca-revised: option resolution must be at most 10 with clusters=200 "
              "components=8 (k x n and c x n <= 2048, the 3D texture size), got 16");
    EXPECT_EQ(test::fitError<LpcaRevisedMaterial>(btf, "lobes=2"),
              "lpca-revised: option lobes is unknown (known: clusters, components, iterations, "
              "training, seed, resolution, storage)");
}

TEST(LpcaRevised, ReproducesTheLpcaModelItResamples) {
    // At the measured directions the resampled model differs from the LPCA model only by the
    // resampling (bilinear on the grid instead of the Delaunay interpolation) and the storage
    // rounding: never better than LPCA on the data, a finer grid closer, and (at n = 24) far
    // below the Lambert baseline. (n = 8 is about as far from the data as Lambert here: the
    // resampling error, not the LPCA error, dominates this nearly exactly fitted 8x8 sample.)
    const MeasuredBtf btf = test::sampleBtf(8, 8);
    osg::ref_ptr<LpcaMaterial> lpca =
        LpcaMaterial::fit(btf, FitOptions::parse("clusters=4 components=4"));
    const double lpcaError = errorOf(btf, *lpca).average;
    const double lambertError = errorOf(btf, *LambertMaterial::fit(btf, {})).average;
    double errors[2];
    for (int i : {0, 1}) {
        const int n = i == 0 ? 8 : 24;
        osg::ref_ptr<LpcaRevisedMaterial> revised = LpcaRevisedMaterial::fromLpca(*lpca, n, false);
        errors[i] = errorOf(btf, *revised).average;
        std::cout << "resolution " << n << ": error avg " << errors[i] << " (lpca " << lpcaError
                  << ", lambert " << lambertError << ")\n";
        EXPECT_GE(errors[i], lpcaError);
    }
    EXPECT_LT(errors[1], errors[0]);
    EXPECT_LT(errors[1], 0.5 * lambertError);
}

TEST(LpcaRevised, EightBitStorageStaysWithinItsQuantisationBound) {
    // Each grid value is off by at most half a step, s_i / 255 in E units (the trilinear filter
    // is a convex combination, so no more after filtering); with alpha'_i = 2 s_i alpha_i a
    // texel's value is off by sum_i |alpha'_i| / 510, plus the half rounding of the folded
    // weights and offset (2^-11 relative, q <= 1) and of the half model's grid (|E| <= s_i).
    const MeasuredBtf btf = test::sampleBtf(6, 4);
    osg::ref_ptr<LpcaMaterial> lpca =
        LpcaMaterial::fit(btf, FitOptions::parse("clusters=3 components=4"));
    osg::ref_ptr<LpcaRevisedMaterial> half = LpcaRevisedMaterial::fromLpca(*lpca, 12, false);
    osg::ref_ptr<LpcaRevisedMaterial> byte = LpcaRevisedMaterial::fromLpca(*lpca, 12, true);
    EXPECT_TRUE(byte->eightBit());
    for (float v : byte->grid.floats()) EXPECT_FLOAT_EQ(v * 255.0f, std::round(v * 255.0f));
    std::vector<float> a(81 * 81 * 3), b(a.size());
    double worst = 0, worstBound = 0;
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        double bound = std::abs(byte->weight(t, 4)) / 2048.0 + 1e-6;
        for (int i = 0; i < 4; ++i)
            bound += std::abs(byte->weight(t, i)) * (1.0 / 510 + 1.0 / 2048 + 1.0 / 4096);
        half->evaluateMeasured(t, a.data());
        byte->evaluateMeasured(t, b.data());
        double largest = 0;
        for (std::size_t i = 0; i < a.size(); ++i)
            largest = std::max(largest, double(std::abs(a[i] - b[i])));
        worst = std::max(worst, largest);
        worstBound = std::max(worstBound, bound);
        EXPECT_LE(largest, bound) << "texel " << t;
    }
    std::cout << "8-bit vs half: largest difference " << worst << " (bound up to " << worstBound
              << "); error avg half " << errorOf(btf, *half).average << ", 8-bit "
              << errorOf(btf, *byte).average << "\n";
    const MemoryFootprint m8 = byte->memory();
    EXPECT_EQ(m8.totalBytes, 24u * (1 + 5 * 2) + std::uint64_t(3 * 12) * (4 * 12) * (12 * 12) * 3);
}

TEST(LpcaRevised, SaveLoadRoundTripIsExactAndOiioReadsTheFile) {
    test::TempDir dir;
    const MeasuredBtf btf = test::sampleBtf(5, 3);
    for (const char* storage : {"half", "unorm8"}) {
        osg::ref_ptr<LpcaRevisedMaterial> m = LpcaRevisedMaterial::fit(
            btf, FitOptions::parse(std::string("clusters=2 components=5 resolution=6 storage=") +
                                   storage));
        const std::string file = dir.file(std::string("revised_") + storage + ".exr");
        saveMaterial(*m, file);
        osg::ref_ptr<Material> back = loadMaterial(file);
        ASSERT_EQ(back->methodName(), "lpca-revised");
        const LpcaRevisedMaterial& b = static_cast<const LpcaRevisedMaterial&>(*back);
        EXPECT_EQ(b.eightBit(), m->eightBit());
        EXPECT_EQ(b.resolution(), 6);
        EXPECT_EQ(b.clusterOf, m->clusterOf);
        EXPECT_EQ(b.weights, m->weights);
        EXPECT_EQ(b.grid, m->grid);
        EXPECT_EQ(b.evaluate(1, 2, {0.3f, 0.1f, 0.9f}, {-0.5f, 0.2f, 0.7f}),
                  m->evaluate(1, 2, {0.3f, 0.1f, 0.9f}, {-0.5f, 0.2f, 0.7f}));
        const auto info = test::runCommand("oiiotool --info " + test::shellQuote(file));
        EXPECT_EQ(info.exitCode, 0) << info.output;
    }
}

TEST(LpcaRevised, MemoryFollowsFromTheGrid) {
    // 256x256 texels, 32 clusters x 8 components, 8^4 grid: the per-texel part is LPCA's
    // (1 + 8 values, 17 bytes); the grid replaces the 81x81 Eigen-BRDFs by 8^4 samples each.
    // (16^4, the default, gives 9 + 768 values, 17 + 1536 bytes: the same formula.)
    osg::ref_ptr<LpcaMaterial> lpca =
        LpcaMaterial::ofShape(256, 256, DirectionSet::bonn81(), DirectionSet::bonn81(), 32, 8);
    osg::ref_ptr<LpcaRevisedMaterial> revised = LpcaRevisedMaterial::fromLpca(*lpca, 8, false);
    const MemoryFootprint m = revised->memory();
    const double grid = 32.0 * 8 * 4096 * 3 / 65536;
    std::cout << "lpca-revised 32x8, 8^4 grid, 256x256: " << m.valuesPerTexel << " values, "
              << m.bytesPerTexel << " bytes per texel\n";
    EXPECT_DOUBLE_EQ(m.valuesPerTexel, 9 + grid);
    EXPECT_DOUBLE_EQ(m.bytesPerTexel, 17 + 2 * grid);
}

TEST(LpcaRevised, ErrorOnTheBuiltInSampleIsWellBelowTheLambertBaseline) {
    const MeasuredBtf btf = test::sampleBtf(16, 16);
    osg::ref_ptr<LpcaRevisedMaterial> m =
        LpcaRevisedMaterial::fit(btf, FitOptions::parse("clusters=8 components=4"));
    const ErrorSummary e = errorOf(btf, *m);
    osg::ref_ptr<LambertMaterial> lambert = LambertMaterial::fit(btf, {});
    const ErrorSummary base = errorOf(btf, *lambert);
    std::cout << "lpca-revised (8 clusters, 4 components, 16^4) on the 16x16 sample: error avg "
              << e.average << " min " << e.minimum << " max " << e.maximum << "; lambert avg "
              << base.average << "\n";
    ::testing::Test::RecordProperty("error_avg", std::to_string(e.average));
    EXPECT_EQ(e.nonFiniteValues, 0u);
    EXPECT_LT(e.average, 0.75 * base.average);
}

}  // namespace OSGBTF_TEST_FILE
