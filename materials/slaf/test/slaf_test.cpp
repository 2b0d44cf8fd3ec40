// SLAF (materials/slaf): options, parameter recovery, robustness on the sample, interpolation at
// measured views, file round trip, memory accounting against Meseth et al. 2003 Table 2.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MaterialMath.h"
#include "materials/MethodOptions.h"
#include "materials/laf/Laf.h"
#include "materials/laf/Lobes.h"
#include "materials/slaf/Slaf.h"
#include "tests/ModelData.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

TEST(Slaf, InvalidOptionsAndInputAreRefused) {
    const MeasuredBtf btf = test::sampleBtf(2, 2);
    EXPECT_EQ(test::fitError<SlafMaterial>(btf, "lobes=0"),
              "slaf: option lobes must be an integer in 1..8, got 0");
    EXPECT_EQ(test::fitError<SlafMaterial>(btf, "rounds=-1"),
              "slaf: option rounds must be an integer in 0..10, got -1");
    EXPECT_EQ(test::fitError<SlafMaterial>(btf, "iterations=501"),
              "slaf: option iterations must be an integer in 1..500, got 501");
    EXPECT_EQ(test::fitError<SlafMaterial>(btf, "views=3"),
              "slaf: option views is unknown (known: lobes, iterations, rounds, cosine)");
    EXPECT_EQ(test::fitError<SlafMaterial>(MeasuredBtf(), ""), "slaf: cannot fit an empty BTF");
}

TEST(Slaf, RecoversAKnownModelFromNoisyData) {
    osg::ref_ptr<SlafMaterial> truth =
        SlafMaterial::create(3, 2, 2, DirectionSet::bonn81(), DirectionSet::bonn81());
    const std::size_t texels = truth->texelCount();
    for (std::size_t t = 0; t < texels; ++t) {
        for (int c = 0; c < 3; ++c) {
            truth->rhoD.set(t * 3 + c, quantizeUNorm8(0.1 + 0.03 * double(t) + 0.05 * c));
            truth->rhoS.set(t * 3 + c, quantizeUNorm8(1.0 - 0.25 * c));
        }
        const float sharp = 5.0f + 3.0f * float(t), k = std::pow(0.3f, 1.0f / sharp);
        const float diffuse[4] = {0.0f, 0.1f * float(t % 2), 0.6f, 1.0f};
        const float mirror[4] = {-k, -k, k, sharp};
        for (int i = 0; i < 4; ++i) {
            truth->lobes.set(t * 4 + i, roundHalf(diffuse[i]));
            truth->lobes.set((texels + t) * 4 + i, roundHalf(mirror[i]));
        }
        // View-dependent darkening toward grazing views, tinted differently per channel.
        for (std::size_t v = 0; v < 81; ++v) {
            const float z = truth->views().vector(v).z;
            for (int c = 0; c < 3; ++c)
                truth->scale.set((v * texels + t) * 3 + c,
                                 roundHalf(0.6 + 0.4 * std::pow(z, 1.0 + c + 0.5 * double(t))));
        }
    }
    const MeasuredBtf data = test::dataFromModel(*truth, 0.01f, 11);
    osg::ref_ptr<SlafMaterial> fitted = SlafMaterial::fit(data, {});
    const ErrorSummary vsTruth = test::modelError(test::dataFromModel(*truth, 0.0f, 1), *fitted);
    std::cout << "SLAF recovery: error vs truth avg " << vsTruth.average << " max "
              << vsTruth.maximum << "\n";
    RecordProperty("error_vs_truth_avg", std::to_string(vsTruth.average));
    // Known gap: LAF recovers its own model to 0.0004 (materials/laf/test/laf_test.cpp), SLAF only
    // to about 0.01 with the default 2 alternation rounds (the lobes start from a LAF fit biased by
    // the view table and the alternation converges slowly); bounded here so regressions show.
    EXPECT_LT(vsTruth.maximum, 0.015);
    EXPECT_LT(test::modelError(data, *fitted).average, 0.02);
    // A LAF fit cannot express T: SLAF must do clearly better on these data.
    EXPECT_LT(test::modelError(data, *fitted).average,
              0.8 * test::modelError(data, *LafMaterial::fit(data, {})).average);
}

TEST(Slaf, SampleFitIsFiniteBoundedAndNotWorseThanLaf) {
    const MeasuredBtf btf = test::sampleBtf(6, 5);
    osg::ref_ptr<SlafMaterial> m = SlafMaterial::fit(btf, {});
    for (float v : m->scale.floats()) ASSERT_TRUE(std::isfinite(v) && v >= 0.0f);
    for (std::size_t i = 0; i < m->lobes.size(); ++i) {
        ASSERT_TRUE(std::isfinite(m->lobes[i]));
        if (i % 4 == 3) {
            ASSERT_GE(m->lobes[i], 0.5f);
        }
    }
    const ErrorSummary error = test::modelError(btf, *m);
    EXPECT_EQ(error.nonFiniteValues, 0u);
    // No divergent texel: bounded by the data's spread around each view's best lit-texture colour
    // (T(v) * l_z with rho_d = 1: what the fitter falls back to), plus half-float rounding.
    std::vector<float> abrdf(81 * 81 * 3);
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        btf.abrdf(t, abrdf.data());
        double spread = 0;
        for (std::size_t v = 0; v < 81; ++v) {
            double colour[3] = {0, 0, 0}, zz = 0;
            for (std::size_t l = 0; l < 81; ++l) {
                const double z = btf.lights().vector(l).z;
                zz += z * z;
                for (int c = 0; c < 3; ++c) colour[c] += abrdf[(v * 81 + l) * 3 + c] * z;
            }
            for (std::size_t l = 0; l < 81; ++l) {
                const double z = btf.lights().vector(l).z;
                double d2 = 0;
                for (int c = 0; c < 3; ++c) {
                    const double d = abrdf[(v * 81 + l) * 3 + c] - colour[c] / zz * z;
                    d2 += d * d;
                }
                spread += std::sqrt(d2) / 6561.0;
            }
        }
        EXPECT_LE(error.perTexel[t], spread + 1e-3) << "texel " << t;
    }
    const ErrorSummary laf = test::modelError(btf, *LafMaterial::fit(btf, {}));
    std::cout << "SLAF on the 6x5 sample: error avg " << error.average << " min " << error.minimum
              << " max " << error.maximum << " (laf avg " << laf.average << ")\n";
    RecordProperty("error_avg", std::to_string(error.average));
    EXPECT_LE(error.average, laf.average);
}

TEST(Slaf, InterpolationIsExactAtMeasuredViews) {
    osg::ref_ptr<SlafMaterial> m =
        SlafMaterial::fit(test::sampleBtf(3, 2), FitOptions::parse("rounds=0"));
    std::vector<float> abrdf(81 * 81 * 3);
    m->evaluateMeasured(4, abrdf.data());
    for (std::size_t v : {0, 5, 33, 80})
        for (std::size_t l : {0, 17, 64}) {
            const glm::vec3 e = m->evaluate(1, 1, m->views().vector(v), m->lights().vector(l));
            for (int c = 0; c < 3; ++c) EXPECT_EQ(e[c], abrdf[(v * 81 + l) * 3 + c]);
        }
}

// LAF is SLAF with T fixed at 1 (both are LobeMaterial): a SLAF holding a LAF fit's colours and
// lobes with T = 1 gives exactly LAF's values.
TEST(Slaf, WithTheViewTableAtOneIsLaf) {
    osg::ref_ptr<LafMaterial> laf = LafMaterial::fit(test::sampleBtf(3, 2), FitOptions::parse(""));
    osg::ref_ptr<SlafMaterial> slaf =
        SlafMaterial::create(3, 2, laf->lobeCount(), laf->views(), laf->lights());
    slaf->rhoD = laf->rhoD;
    slaf->rhoS = laf->rhoS;
    slaf->lobes = laf->lobes;
    std::vector<float> a(81 * 81 * 3), b(81 * 81 * 3);
    for (std::size_t t = 0; t < 6; ++t) {
        laf->evaluateMeasured(t, a.data());
        slaf->evaluateMeasured(t, b.data());
        EXPECT_EQ(a, b) << "texel " << t;
    }
    float peak = 0;
    for (float v : a) peak = std::max(peak, v);
    EXPECT_GT(peak, 0.1f);  // a real fit, not zeros on both sides
}

TEST(Slaf, SaveLoadRoundTripIsExact) {
    test::TempDir dir;
    osg::ref_ptr<SlafMaterial> m =
        SlafMaterial::fit(test::sampleBtf(4, 3), FitOptions::parse("rounds=1"));
    saveMaterial(*m, dir.file("slaf.exr"));
    osg::ref_ptr<Material> back = loadMaterial(dir.file("slaf.exr"));
    ASSERT_EQ(back->methodName(), "slaf");
    const SlafMaterial& s = static_cast<const SlafMaterial&>(*back);
    EXPECT_EQ(s.lobeCount(), 2);
    EXPECT_EQ(s.rhoD, m->rhoD);
    EXPECT_EQ(s.rhoS, m->rhoS);
    EXPECT_EQ(s.lobes, m->lobes);
    EXPECT_EQ(s.scale, m->scale);
    EXPECT_EQ(s.evaluate(3, 2, {0.1f, 0.5f, 0.86f}, {0.6f, 0, 0.8f}),
              m->evaluate(3, 2, {0.1f, 0.5f, 0.86f}, {0.6f, 0, 0.8f}));
    const auto info = test::runCommand("oiiotool --info " + test::shellQuote(dir.file("slaf.exr")));
    EXPECT_EQ(info.exitCode, 0) << info.output;
}

TEST(Slaf, MemoryMatchesMeseth2003Table2) {
    osg::ref_ptr<SlafMaterial> m =
        SlafMaterial::create(256, 256, 2, DirectionSet::bonn81(), DirectionSet::bonn81());
    EXPECT_EQ(m->memory().valuesPerTexel, 257.0);
    EXPECT_EQ(m->memory().bytesPerTexel, 508.0);
    EXPECT_EQ(m->memory().totalBytes, 508u * 256u * 256u);
}

}  // namespace OSGBTF_TEST_FILE
