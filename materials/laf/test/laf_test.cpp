// LAF (materials/laf): options, parameter recovery, robustness on the sample, file round trip,
// memory accounting against Meseth et al. 2003 Table 2.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MaterialMath.h"
#include "materials/MethodRegistry.h"
#include "materials/laf/Laf.h"
#include "materials/laf/Lobes.h"
#include "materials/lambert/Lambert.h"
#include "tests/ModelData.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

TEST(Laf, InvalidOptionsAndInputAreRefused) {
    const MeasuredBtf btf = test::sampleBtf(2, 2);
    EXPECT_EQ(test::fitError<LafMaterial>(btf, "lobes=0"),
              "laf: option lobes must be an integer in 1..8, got 0");
    EXPECT_EQ(test::fitError<LafMaterial>(btf, "lobes=9"),
              "laf: option lobes must be an integer in 1..8, got 9");
    EXPECT_EQ(test::fitError<LafMaterial>(btf, "lobes=two"),
              "laf: option lobes must be an integer in 1..8, got two");
    EXPECT_EQ(test::fitError<LafMaterial>(btf, "iterations=0"),
              "laf: option iterations must be an integer in 1..500, got 0");
    EXPECT_EQ(test::fitError<LafMaterial>(btf, "clusters=4"),
              "laf: option clusters is unknown (known: lobes, iterations, cosine)");
    EXPECT_EQ(test::fitError<LafMaterial>(btf, "cosine=2"),
              "laf: option cosine must be 0 or 1, got 2");
    EXPECT_EQ(test::fitError<LafMaterial>(MeasuredBtf(), ""), "laf: cannot fit an empty BTF");
}

TEST(Laf, TwoVariableNonNegativeLeastSquares) {
    const double f[] = {1, 1, 1, 1}, g[] = {0, 1, 2, 3};
    double a, b;
    const double exact[] = {0.5, 1.5, 2.5, 3.5};  // 0.5 + 1 * g
    nonNegativeLeastSquares2(f, g, exact, 4, 1, a, b);
    EXPECT_NEAR(a, 0.5, 1e-12);
    EXPECT_NEAR(b, 1.0, 1e-12);
    const double falling[] = {3, 2, 1, 0};  // unconstrained slope < 0: beta clamps to 0
    nonNegativeLeastSquares2(f, g, falling, 4, 1, a, b);
    EXPECT_EQ(b, 0.0);
    EXPECT_NEAR(a, 1.5, 1e-12);
}

TEST(Laf, RecoversAKnownModelFromNoisyData) {
    // Per texel a different diffuse-like lobe and mirror lobe, colours on the 8-bit grid.
    osg::ref_ptr<LafMaterial> truth =
        LafMaterial::create(4, 3, 2, DirectionSet::bonn81(), DirectionSet::bonn81());
    const std::size_t texels = truth->texelCount();
    for (std::size_t t = 0; t < texels; ++t) {
        for (int c = 0; c < 3; ++c) {
            truth->rhoD.set(t * 3 + c, quantizeUNorm8(0.05 + 0.02 * double(t) + 0.05 * c));
            truth->rhoS.set(t * 3 + c, quantizeUNorm8(1.0 - 0.2 * c));
        }
        const float diffuse[4] = {0.1f * float(t % 3), 0.0f, 0.5f, 1.0f};
        const float sharp = 6.0f + 2.0f * float(t), k = std::pow(0.4f, 1.0f / sharp);
        const float mirror[4] = {-k, -k, k, sharp};
        for (int i = 0; i < 4; ++i) {
            truth->lobes.set(t * 4 + i, roundHalf(diffuse[i]));
            truth->lobes.set((texels + t) * 4 + i, roundHalf(mirror[i]));
        }
    }
    const float noise = 0.01f;
    const MeasuredBtf data = test::dataFromModel(*truth, noise, 7);
    osg::ref_ptr<LafMaterial> fitted = LafMaterial::fit(data, {});
    ASSERT_EQ(fitted->lobeCount(), 2);
    // Fitted model vs the noise-free truth: close to it, far below the noise amplitude.
    const MeasuredBtf clean = test::dataFromModel(*truth, 0.0f, 1);
    const ErrorSummary vsTruth = test::modelError(clean, *fitted);
    RecordProperty("error_vs_truth_avg", std::to_string(vsTruth.average));
    std::cout << "LAF recovery: error vs truth avg " << vsTruth.average << " max "
              << vsTruth.maximum << "\n";
    EXPECT_LT(vsTruth.maximum, 0.01);
    // And vs the noisy data the error is the noise's own: |uniform RGB noise| ~ 0.0095 for +-0.01.
    EXPECT_LT(test::modelError(data, *fitted).average, 0.0125);
    EXPECT_EQ(fitted->fitInfo.at("fallbacks"), "0");
}

TEST(Laf, SampleFitIsFiniteBoundedAndBeatsLambert) {
    const MeasuredBtf btf = test::sampleBtf(8, 6);
    osg::ref_ptr<LafMaterial> m = LafMaterial::fit(btf, {});
    for (float v : m->rhoD.floats()) ASSERT_TRUE(v >= 0.0f && v <= 1.0f);
    for (float v : m->rhoS.floats()) ASSERT_TRUE(v >= 0.0f && v <= 1.0f);
    for (std::size_t i = 0; i < m->lobes.size(); ++i) {
        ASSERT_TRUE(std::isfinite(m->lobes[i]));
        if (i % 4 == 3) {
            ASSERT_GE(m->lobes[i], 0.5f);
        }  // n > 0: valid lobes only
    }
    const ErrorSummary error = test::modelError(btf, *m);
    EXPECT_EQ(error.nonFiniteValues, 0u);
    // No divergent texel: each is within its data's spread around the texel's best lit-texture
    // colour (rho * l_z, the Lambert baseline, what the fitter falls back to), plus the 8-bit
    // versus half rounding of that colour.
    const ErrorSummary lambert = test::modelError(btf, *LambertMaterial::fit(btf, {}));
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        EXPECT_LE(error.perTexel[t], lambert.perTexel[t] + 0.004) << "texel " << t;
    std::cout << "LAF on the 8x6 sample: error avg " << error.average << " min " << error.minimum
              << " max " << error.maximum << " (lambert avg " << lambert.average << ")\n";
    RecordProperty("error_avg", std::to_string(error.average));
    EXPECT_LT(error.average, lambert.average);
}

TEST(Laf, LiteralSeedModelWithoutCosineIsAvailable) {
    // cosine=0: Meseth et al. 2003 eq. 2 as printed. Fits its own data and round-trips the flag.
    osg::ref_ptr<LafMaterial> truth =
        LafMaterial::create(2, 2, 1, DirectionSet::bonn81(), DirectionSet::bonn81());
    FittedMaterial file = truth->toFittedMaterial();
    file.parameters["cosine"] = "0";
    truth = LafMaterial::fromFile(file);
    ASSERT_FALSE(truth->cosine());
    for (std::size_t t = 0; t < 4; ++t) {
        for (int c = 0; c < 3; ++c) {
            truth->rhoD.set(t * 3 + c, quantizeUNorm8(0.2 + 0.1 * c));
            truth->rhoS.set(t * 3 + c, quantizeUNorm8(0.8));
        }
        const float lobe[4] = {-0.9f, -0.9f, 0.9f, 4.0f + float(t)};
        for (int i = 0; i < 4; ++i) truth->lobes.set(t * 4 + i, roundHalf(lobe[i]));
    }
    const MeasuredBtf data = test::dataFromModel(*truth, 0.0f, 1);
    osg::ref_ptr<LafMaterial> fitted =
        LafMaterial::fit(data, FitOptions::parse("lobes=1 cosine=0"));
    EXPECT_FALSE(fitted->cosine());
    EXPECT_LT(test::modelError(data, *fitted).maximum, 0.005);
    EXPECT_FALSE(LafMaterial::fromFile(fitted->toFittedMaterial())->cosine());
}

TEST(Laf, SaveLoadRoundTripIsExact) {
    test::TempDir dir;
    osg::ref_ptr<LafMaterial> m =
        LafMaterial::fit(test::sampleBtf(5, 3), FitOptions::parse("lobes=1"));
    saveMaterial(*m, dir.file("laf.exr"));
    osg::ref_ptr<Material> back = loadMaterial(dir.file("laf.exr"));
    ASSERT_EQ(back->methodName(), "laf");
    const LafMaterial& l = static_cast<const LafMaterial&>(*back);
    EXPECT_EQ(l.lobeCount(), 1);
    EXPECT_EQ(l.rhoD, m->rhoD);
    EXPECT_EQ(l.rhoS, m->rhoS);
    EXPECT_EQ(l.lobes, m->lobes);
    EXPECT_EQ(l.fitInfo.at("iterations"), m->fitInfo.at("iterations"));
    EXPECT_EQ(l.evaluate(4, 2, {0, 0.6f, 0.8f}, {0.6f, 0, 0.8f}),
              m->evaluate(4, 2, {0, 0.6f, 0.8f}, {0.6f, 0, 0.8f}));
    const auto info = test::runCommand("oiiotool --info " + test::shellQuote(dir.file("laf.exr")));
    EXPECT_EQ(info.exitCode, 0) << info.output;
}

TEST(Laf, MemoryMatchesMeseth2003Table2) {
    // The standard configuration: 256 x 256 texels, Bonn 81 x 81 directions, 2 lobes.
    osg::ref_ptr<LafMaterial> m =
        LafMaterial::create(256, 256, 2, DirectionSet::bonn81(), DirectionSet::bonn81());
    EXPECT_EQ(m->memory().valuesPerTexel, 14.0);
    EXPECT_EQ(m->memory().bytesPerTexel, 22.0);
    EXPECT_EQ(m->memory().totalBytes, 22u * 256u * 256u);
    osg::ref_ptr<LafMaterial> one =
        LafMaterial::create(4, 4, 1, DirectionSet::bonn81(), DirectionSet::bonn81());
    EXPECT_EQ(one->memory().valuesPerTexel, 10.0);
    EXPECT_EQ(one->memory().bytesPerTexel, 14.0);
}

TEST(Laf, IsRegistered) {
    const MethodInfo& info = findMethod("laf");
    EXPECT_FALSE(info.description.empty());
    ASSERT_EQ(info.options.size(), 3u);
    EXPECT_EQ(info.options[0].name, "lobes");
}

}  // namespace OSGBTF_TEST_FILE
