// Every method on degenerate data: a constant BTF, a rank-1 BTF (texel
// albedo times one ABRDF) and duplicate texels (two distinct texels, each repeated). Such data
// make the low-rank fits rank-deficient: components beyond the data's rank must come out unused
// (zero), not as amplified rounding noise, and no method may produce NaN or Inf. Each bound below
// is derived from what the method's model can represent and how it stores it.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <iostream>

#include "core/ErrorMetrics.h"
#include "core/LowRank.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "materials/lambert/Lambert.h"
#include "materials/lpca/Lpca.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

constexpr int kWidth = 4, kHeight = 4;
/** 102/255: exactly representable in the 8-bit colours of LAF, SLAF and RF. */
constexpr float kConstant = 102.0f / 255.0f;

using ValueOf = std::function<float(std::size_t texel, std::size_t pair, int channel)>;

MeasuredBtf makeBtf(const ValueOf& value) {
    MeasuredBtf btf(kWidth, kHeight, DirectionSet::bonn81(), DirectionSet::bonn81());
    const std::size_t lights = btf.lightCount();
    for (std::size_t v = 0; v < btf.viewCount(); ++v)
        for (std::size_t l = 0; l < lights; ++l)
            for (std::size_t t = 0; t < btf.texelCount(); ++t)
                for (int ch = 0; ch < 3; ++ch)
                    btf.setValue(v, l, t, ch, value(t, v * lights + l, ch));
    return btf;
}

/** Two distinct, realistic ABRDFs: texels of the built-in sample. */
const MeasuredBtf& sampleSource() {
    static const MeasuredBtf btf = [] {
        SampleOptions options;
        options.width = 4;
        options.height = 4;
        return makeSampleBtf(options);
    }();
    return btf;
}

MeasuredBtf constantBtf() {
    return makeBtf([](std::size_t, std::size_t, int) { return kConstant; });
}

/** Albedo of texel t in the rank-1 BTF: a scalar in [0.5, 1]. */
float albedo(std::size_t t) {
    return 0.5f + 0.5f * float(t) / float(kWidth * kHeight - 1);
}
/** The colour of the rank-1 BTF's ABRDF: a fixed RGB, so that the BTF is rank 1 both as LPCA sees
 *  it (texels x (view, light, RGB)) and as PCA does per view ((texel, RGB) x light). */
constexpr float kColour[3] = {1.0f, 0.8f, 0.6f};

MeasuredBtf rankOneBtf() {
    const std::vector<float> f = sampleSource().abrdf(5);
    return makeBtf([&](std::size_t t, std::size_t pair, int ch) {
        const float luminance = (f[pair * 3] + f[pair * 3 + 1] + f[pair * 3 + 2]) / 3.0f;
        return albedo(t) * luminance * kColour[ch];
    });
}

/** Texel t is a copy of sample texel 9 when t % 3 == 0, else of sample texel 2. */
bool isSecondKind(std::size_t t) {
    return t % 3 == 0;
}

MeasuredBtf duplicateBtf() {
    const std::vector<float> a = sampleSource().abrdf(2), b = sampleSource().abrdf(9);
    return makeBtf([&](std::size_t t, std::size_t pair, int ch) {
        return (isSecondKind(t) ? b : a)[pair * 3 + std::size_t(ch)];
    });
}

struct Fitted {
    osg::ref_ptr<Material> material;
    ErrorSummary error;
};

Fitted fitMethod(const std::string& method, const std::string& options, const MeasuredBtf& btf) {
    Fitted f;
    f.material = findMethod(method).fit(btf, FitOptions::parse(options));
    f.error =
        computeError(btf, [&](std::size_t t, float* out) { f.material->evaluateMeasured(t, out); });
    std::cout << method << " [" << options << "]: error avg " << f.error.average << " max "
              << f.error.maximum << " rmse " << f.error.rmse << "\n";
    return f;
}

/** No NaN or Inf in any stored array of the material nor in its evaluation. */
void expectFinite(const Fitted& f, const std::string& what) {
    EXPECT_EQ(f.error.nonFiniteValues, 0u) << what;
    EXPECT_TRUE(std::isfinite(f.error.average)) << what;
    EXPECT_TRUE(std::isfinite(f.error.rmse)) << what;
    const FittedMaterial file = f.material->toFittedMaterial();
    for (const MaterialTexture& texture : file.textures) {
        std::size_t bad = 0;
        for (float v : texture.data) bad += std::isfinite(v) ? 0 : 1;
        EXPECT_EQ(bad, 0u) << what << ": texture " << texture.name;
    }
}

/** Lambert's error on the constant BTF, derived: rho = c sum(l_z) / sum(l_z^2) (its least-squares
 *  fit, the same for every texel and channel), so each texel's error is the mean over (v, l) of
 *  sqrt(3) |c - rho l_z|. */
double lambertConstantError() {
    const DirectionSet lights = DirectionSet::bonn81();
    double sum = 0, sum2 = 0;
    for (std::size_t l = 0; l < lights.size(); ++l) {
        const double z = lights[l].toVector().z;
        sum += z;
        sum2 += z * z;
    }
    const double rho = kConstant * sum / sum2;
    double error = 0;
    for (std::size_t l = 0; l < lights.size(); ++l)
        error += std::sqrt(3.0) * std::abs(kConstant - rho * lights[l].toVector().z);
    return error / double(lights.size());
}

/** The per-texel error relative to a value scale: half storage rounds to 2^-11 relative; a few
 *  roundings (Eigen-BRDF and weight, RGB length sqrt(3)) stay well below 4e-3 of the largest
 *  value. */
constexpr double kHalfRelative = 4e-3;

double maxValue(const MeasuredBtf& btf) {
    double m = 0;
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        for (float v : btf.abrdf(t)) m = std::max(m, double(v));
    return m;
}

}  // namespace

// ---- lambert -----------------------------------------------------------------------------------

TEST(Degenerate, LambertOnConstantDataHasItsDerivedError) {
    // rho l_z cannot be constant in l, so Lambert is not exact here; its error is known exactly
    // (lambertConstantError), up to the half rounding of rho.
    const Fitted f = fitMethod("lambert", "", constantBtf());
    expectFinite(f, "lambert constant");
    const double expected = lambertConstantError();
    std::cout << "lambert constant: derived error " << expected << "\n";
    EXPECT_NEAR(f.error.average, expected, 1e-3 * expected);
    EXPECT_NEAR(f.error.maximum, expected, 1e-3 * expected);
}

TEST(Degenerate, LambertOnRankOneDataScalesWithTheAlbedo) {
    // rho(t) = albedo(t) rho_f (the fit is linear in the data), so the error of texel t is
    // albedo(t) times the error of the ABRDF alone: error / albedo is one number for every texel,
    // up to the half storage of rho: rounding it (unit roundoff 2^-11) moves error / albedo by at
    // most 2^-11 |rho_f| mean(l_z), in each of the two texels compared.
    const MeasuredBtf btf = rankOneBtf();
    const Fitted f = fitMethod("lambert", "", btf);
    expectFinite(f, "lambert rank-1");
    const auto* m = dynamic_cast<const LambertMaterial*>(f.material.get());
    ASSERT_NE(m, nullptr);
    const double rhoF =
        std::sqrt(double(m->albedo[0]) * m->albedo[0] + double(m->albedo[1]) * m->albedo[1] +
                  double(m->albedo[2]) * m->albedo[2]) /
        albedo(0);
    double meanZ = 0;
    for (std::size_t l = 0; l < btf.lightCount(); ++l) meanZ += btf.lights().vector(l).z;
    meanZ /= double(btf.lightCount());
    const double tolerance = 2 * std::ldexp(1.0, -11) * rhoF * meanZ;
    const double reference = f.error.perTexel[0] / albedo(0);
    EXPECT_GT(reference, 10 * tolerance);  // the check below means something
    for (std::size_t t = 1; t < btf.texelCount(); ++t)
        EXPECT_NEAR(f.error.perTexel[t] / albedo(t), reference, tolerance) << "texel " << t;
}

TEST(Degenerate, LambertOnDuplicateTexelsGivesEqualCopiesEqualErrors) {
    const MeasuredBtf btf = duplicateBtf();
    const Fitted f = fitMethod("lambert", "", btf);
    expectFinite(f, "lambert duplicates");
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        EXPECT_EQ(f.error.perTexel[t], f.error.perTexel[isSecondKind(t) ? 0 : 1]) << "texel " << t;
}

// ---- analytic methods: laf, slaf, rf -----------------------------------------------------------

namespace {

/** LAF and SLAF contain Lambert's model rho_d l_z (lobes off, T = 1), RF a constant term per
 *  texel, and all fit by least squares: on the constant BTF their RMSE cannot exceed Lambert's
 *  beyond their storage rounding (8-bit colours: half a step, 0.5/255, per channel). On rank-1 and
 *  duplicate data the lobe fits are local searches with no closed-form optimum to compare with, so
 *  there the check is that nothing becomes NaN or Inf. */
void expectAnalyticBehaves(const std::string& method) {
    const Fitted lambert = fitMethod("lambert", "", constantBtf());
    const Fitted constant = fitMethod(method, "", constantBtf());
    expectFinite(constant, method + " constant");
    EXPECT_LE(constant.error.rmse, lambert.error.rmse + 0.5 / 255.0) << method;
    EXPECT_LE(constant.error.average, lambert.error.average + std::sqrt(3.0) * 0.5 / 255.0)
        << method;
    // RF represents the constant exactly: rho_d = 102/255 is an 8-bit value, rho_v = 0.
    if (method == "rf") {
        EXPECT_LT(constant.error.maximum, 1e-6) << method;
    }
    expectFinite(fitMethod(method, "", rankOneBtf()), method + " rank-1");
    expectFinite(fitMethod(method, "", duplicateBtf()), method + " duplicates");
}

}  // namespace

TEST(Degenerate, LafStaysFiniteAndNoWorseThanLambert) {
    expectAnalyticBehaves("laf");
}
TEST(Degenerate, SlafStaysFiniteAndNoWorseThanLambert) {
    expectAnalyticBehaves("slaf");
}
TEST(Degenerate, RfStaysFiniteAndNoWorseThanLambert) {
    expectAnalyticBehaves("rf");
}

// ---- pca ---------------------------------------------------------------------------------------

namespace {

/** Per view, PCA factors the (texel, RGB) x light matrix. Its rank: constant 1, rank-1 BTF 1 (the
 *  fixed colour), duplicates at most 6 (two texels x RGB). With 8 components and float storage
 *  the fit is exact up to float rounding; the components beyond the rank must be unused, not
 *  noise that least squares then mixes in. */
void expectPcaExact(const MeasuredBtf& btf, const std::string& what) {
    const Fitted f = fitMethod("pca", "components=8 storage=float", btf);
    expectFinite(f, "pca " + what);
    EXPECT_LT(f.error.maximum, 1e-5 * maxValue(btf)) << what;
}

/** unorm8 Eigen-Textures (the default): on rank-1 data (non-negative, so the Eigen-Texture's
 *  entries share one sign) value = alpha E with |alpha| * range(E) <= the largest value of that
 *  (view, light), and quantising E to half a step of 1/255 of its range changes each channel by at
 *  most 0.5/255 of that value; the least-squares weights only lower the squared error. */
void expectPcaUnorm8(const MeasuredBtf& btf, const std::string& what) {
    const Fitted f = fitMethod("pca", "components=8", btf);
    expectFinite(f, "pca unorm8 " + what);
    EXPECT_LT(f.error.rmse, 0.5 / 255.0 * maxValue(btf)) << what;
}

}  // namespace

TEST(Degenerate, PcaIsExactOnConstantData) {
    expectPcaExact(constantBtf(), "constant");
    expectPcaUnorm8(constantBtf(), "constant");
}
TEST(Degenerate, PcaIsExactOnRankOneData) {
    expectPcaExact(rankOneBtf(), "rank-1");
    expectPcaUnorm8(rankOneBtf(), "rank-1");
}
TEST(Degenerate, PcaIsExactOnDuplicateTexels) {
    expectPcaExact(duplicateBtf(), "duplicates");
}

TEST(Degenerate, TruncatedSvdLeavesComponentsBeyondTheRankZero) {
    // The PCA building block directly: a rank-1 (texel, RGB) x light matrix asked for rank 4
    // must return one component and three zero columns on both sides, and reproduce the matrix.
    const MeasuredBtf btf = rankOneBtf();
    const std::size_t rows = btf.texelCount() * 3, cols = btf.lightCount();
    std::vector<float> a(rows * cols);
    for (std::size_t l = 0; l < cols; ++l) {
        const std::vector<float> image = btf.image(40, l);
        std::copy(image.begin(), image.end(), a.begin() + l * rows);
    }
    const TruncatedSvd svd = truncatedSvd(a.data(), rows, cols, 4);
    for (int k = 1; k < 4; ++k) {
        double u2 = 0, v2 = 0;
        for (std::size_t r = 0; r < rows; ++r)
            u2 += double(svd.u[k * rows + r]) * svd.u[k * rows + r];
        for (std::size_t c = 0; c < cols; ++c)
            v2 += double(svd.v[k * cols + c]) * svd.v[k * cols + c];
        EXPECT_EQ(u2, 0.0) << "U column " << k;
        EXPECT_EQ(v2, 0.0) << "V column " << k;
    }
    double maxError = 0, maxA = 0;
    for (std::size_t c = 0; c < cols; ++c)
        for (std::size_t r = 0; r < rows; ++r) {
            const double model = svd.u[r] * svd.singularValues[0] * svd.v[c];
            maxError = std::max(maxError, std::abs(model - a[c * rows + r]));
            maxA = std::max(maxA, double(std::abs(a[c * rows + r])));
        }
    EXPECT_LT(maxError, 1e-5 * maxA);
}

// ---- lpca --------------------------------------------------------------------------------------

namespace {

/** LPCA with 2 clusters x 4 components. The texel x (view, light, RGB) matrix has rank 1
 *  (constant, rank-1) or 2 (duplicates: each cluster can hold one kind, or one cluster both), so
 *  the fit is exact up to the half storage of Eigen-BRDFs and weights (kHalfRelative). The
 *  components beyond the rank must be zero: else they are rounding noise of the Gram route. */
void expectLpcaExact(const MeasuredBtf& btf, const std::string& what, int rank) {
    const Fitted f = fitMethod("lpca", "clusters=2 components=4 training=0", btf);
    expectFinite(f, "lpca " + what);
    EXPECT_LT(f.error.maximum, kHalfRelative * maxValue(btf)) << what;
    const auto* m = dynamic_cast<const LpcaMaterial*>(f.material.get());
    ASSERT_NE(m, nullptr);
    for (int k = 0; k < m->clusters(); ++k)
        for (int i = rank; i < m->components(); ++i) {
            double norm2 = 0;
            for (std::size_t v = 0; v < m->views().size(); ++v) {
                const std::size_t e = m->eigenBrdfRun(k, i, v);
                for (std::size_t j = 0; j < m->lights().size() * 3; ++j)
                    norm2 += double(m->eigenBrdfs[e + j]) * m->eigenBrdfs[e + j];
            }
            EXPECT_EQ(norm2, 0.0) << what << ": cluster " << k << " component " << i;
        }
}

}  // namespace

TEST(Degenerate, LpcaIsExactOnConstantData) {
    expectLpcaExact(constantBtf(), "constant", 1);
}
TEST(Degenerate, LpcaIsExactOnRankOneData) {
    expectLpcaExact(rankOneBtf(), "rank-1", 1);
}
TEST(Degenerate, LpcaIsExactOnDuplicateTexels) {
    expectLpcaExact(duplicateBtf(), "duplicates", 2);
}

TEST(Degenerate, LpcaOnIdenticalTexelsOfTheSample) {
    // The case found in review: every texel a copy of one sample texel (all its colour and
    // structure, rank 1), clusters=2 components=4 gave error 0.293.
    const std::vector<float> f = sampleSource().abrdf(5);
    const MeasuredBtf btf = makeBtf(
        [&](std::size_t, std::size_t pair, int ch) { return f[pair * 3 + std::size_t(ch)]; });
    expectLpcaExact(btf, "identical texels", 1);
}

// ---- lpca-revised ------------------------------------------------------------------------------

namespace {

/** Revised LPCA resamples each Eigen-BRDF onto a concentric grid and interpolates it back, which
 *  is not exact for a varying ABRDF. So the bound is relative: with the extra components unused,
 *  2 clusters x 4 components reconstruct no worse than 1 cluster x `rank` components (the same
 *  subspace, resampled the same way), up to half rounding. On constant data the resampling of a
 *  constant is exact (the interpolation weights sum to 1), so the error is ~0. */
void expectRevisedNoWorseThanItsRank(const MeasuredBtf& btf, const std::string& what, int rank) {
    const Fitted full = fitMethod("lpca-revised", "clusters=2 components=4 training=0", btf);
    const Fitted minimal =
        fitMethod("lpca-revised", "clusters=1 training=0 components=" + std::to_string(rank), btf);
    expectFinite(full, "lpca-revised " + what);
    expectFinite(minimal, "lpca-revised minimal " + what);
    EXPECT_LE(full.error.average, minimal.error.average + kHalfRelative * maxValue(btf)) << what;
}

}  // namespace

TEST(Degenerate, LpcaRevisedIsExactOnConstantData) {
    const MeasuredBtf btf = constantBtf();
    expectRevisedNoWorseThanItsRank(btf, "constant", 1);
    const Fitted f = fitMethod("lpca-revised", "clusters=2 components=4 training=0", btf);
    EXPECT_LT(f.error.maximum, kHalfRelative * kConstant);
}
TEST(Degenerate, LpcaRevisedOnRankOneData) {
    expectRevisedNoWorseThanItsRank(rankOneBtf(), "rank-1", 1);
}
TEST(Degenerate, LpcaRevisedOnDuplicateTexels) {
    // Rank 2 overall; a single cluster needs both components.
    expectRevisedNoWorseThanItsRank(duplicateBtf(), "duplicates", 2);
}

// ---- ptm ---------------------------------------------------------------------------------------

namespace {

/** A constant is the PTM a5 = c (the design's constant column), so the fit is exact up to the
 *  half storage (unit roundoff 2^-11): rgb rounds a5 once; luminance rounds the luminance's a5 and
 *  then the colour c / a5, two roundings; the other coefficients are rounding noise of the double
 *  fit (below 1e-6). Per texel error = RGB length of that. Rank-1 and duplicate data are no PTM:
 *  there the check is that nothing becomes NaN or Inf. */
void expectPtmBehaves(const std::string& options) {
    const Fitted constant = fitMethod("ptm", options, constantBtf());
    expectFinite(constant, "ptm constant " + options);
    const double roundings = options.find("luminance") != std::string::npos ? 2 : 1;
    EXPECT_LT(constant.error.maximum,
              std::sqrt(3.0) * (roundings * std::ldexp(1.0, -11) * kConstant + 1e-6))
        << options;
    expectFinite(fitMethod("ptm", options, rankOneBtf()), "ptm rank-1 " + options);
    expectFinite(fitMethod("ptm", options, duplicateBtf()), "ptm duplicates " + options);
}

}  // namespace

TEST(Degenerate, PtmIsExactOnConstantDataAndStaysFinite) {
    expectPtmBehaves("");
    expectPtmBehaves("colour=luminance");
    expectPtmBehaves("views=all");
    expectPtmBehaves("views=all colour=luminance");
}

}  // namespace OSGBTF_TEST_FILE
