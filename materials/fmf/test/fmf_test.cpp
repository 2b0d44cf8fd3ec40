// Method "fmf" (materials/fmf): option errors, Eckart-Young optimality of both SVD paths against a
// direct SVD, rendering hand-made DFMF/FMF factors as stored (every colour model, DRR, cosine,
// per-channel ranks), half rounding, save/load, Table 2 memory, and the error on the sample.
#include <atomic>
#include <cmath>
#include <iostream>
#include <random>

#include <gtest/gtest.h>
#include <Eigen/Core>

#include "core/DirectionInterpolation.h"
#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "core/LowRank.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MaterialState.h"
#include "materials/MethodOptions.h"
#include "materials/fmf/Fmf.h"
#include "materials/lambert/Lambert.h"
#include "tests/RandomFactors.h"
#include "tests/ReferenceSvd.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::randomFactors;

namespace {

/** The ABRDF matrix of Schwartz et al. 2013: rows (view, light, channel), columns texels, in
 * double. */
Eigen::MatrixXd abrdfMatrix(const MeasuredBtf& btf) {
    const std::size_t images = btf.viewCount() * btf.lightCount();
    Eigen::MatrixXd a(Eigen::Index(images * 3), Eigen::Index(btf.texelCount()));
    for (std::size_t v = 0; v < btf.viewCount(); ++v)
        for (std::size_t l = 0; l < btf.lightCount(); ++l)
            for (std::size_t t = 0; t < btf.texelCount(); ++t)
                for (int c = 0; c < 3; ++c)
                    a(Eigen::Index((v * btf.lightCount() + l) * 3 + std::size_t(c)),
                      Eigen::Index(t)) = btf.value(v, l, t, c);
    return a;
}

/** Optimal rank-c Frobenius error (Eckart-Young) from all singular values. */
double optimalError(const Eigen::VectorXd& s, int c) {
    return std::sqrt(s.tail(s.size() - c).squaredNorm());
}

/** Frobenius error of the material's evaluateMeasured against the data. */
double modelError(const MeasuredBtf& btf, const FmfMaterial& m) {
    const std::size_t n = btf.viewCount() * btf.lightCount() * 3;
    std::vector<float> data(n), model(n);
    double sum = 0;
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        btf.abrdf(t, data.data());
        m.evaluateMeasured(t, model.data());
        for (std::size_t i = 0; i < n; ++i) sum += std::pow(double(model[i]) - data[i], 2);
    }
    return std::sqrt(sum);
}

const std::vector<std::pair<Direction, Direction>> kUnmeasured = {{{31.7f, 77}, {52, 200}},
                                                                  {{8, 11}, {68, 301}},
                                                                  {{52, 160}, {82, 45}},
                                                                  {{44, 333}, {37.5f, 95}}};

}  // namespace

TEST(Fmf, InvalidOptionsAreRefusedWithClearMessages) {
    const MeasuredBtf btf = test::sampleBtf(4, 3);
    EXPECT_EQ(test::fitError<FmfMaterial>(btf, "components=0"),
              "fmf: option components must be an integer >= 1, got 0");
    EXPECT_EQ(test::fitError<FmfMaterial>(btf, "components=many"),
              "fmf: option components must be an integer >= 1, got many");
    EXPECT_EQ(test::fitError<FmfMaterial>(btf, "storage=unorm8"),
              "fmf: option storage must be one of half, float, got unorm8");
    EXPECT_EQ(test::fitError<FmfMaterial>(btf, "clusters=2"),
              "fmf: option clusters is unknown (known: components, storage)");
    // 12 texels: the rank of the 19683 x 12 matrix is at most 12.
    EXPECT_EQ(test::fitError<FmfMaterial>(btf, "components=13"),
              "fmf: option components must be at most 12 for this BTF (its texels, or 3 x "
              "views x lights if fewer), got 13");
    EXPECT_EQ(test::fitError<FmfMaterial>(MeasuredBtf(), ""), "fmf: the BTF is empty");
}

TEST(Fmf, FitErrorIsTheOptimalRankCError) {
    // 30 texels: the exact Gram path. Float storage, so the error is the SVD's own.
    const MeasuredBtf btf = test::sampleBtf(6, 5);
    const Eigen::MatrixXd a = abrdfMatrix(btf);
    const Eigen::VectorXd s = test::referenceSingularValues(a);
    for (int c : {1, 4, 12}) {
        osg::ref_ptr<FmfMaterial> m = FmfMaterial::fit(
            btf, FitOptions::parse("storage=float components=" + std::to_string(c)));
        EXPECT_EQ(m->fitInfo.at("algorithm"), "gram");
        const double optimal = optimalError(s, c), got = modelError(btf, *m);
        EXPECT_LE(got, optimal * 1.001) << c;
        EXPECT_GE(got, optimal * 0.999) << c;  // nothing beats Eckart-Young
        // The factors follow the file convention: S = singular values, folded into SxV.
        for (int k = 0; k < c; ++k)
            EXPECT_NEAR(m->factors().factors[0].S(k), s(k), 1e-4 * s(0)) << k;
        EXPECT_NEAR(m->completeFactors().factors[0].SxV.col(0).norm(), s(0), 1e-4 * s(0));
    }
}

TEST(Fmf, RandomisedSvdReachesTheOptimalError) {
    // The randomised path (forced: no Gram) on the sample's 19683 x 256 matrix, read in blocks of
    // 30 rows, against a direct SVD: its Frobenius error within 0.1 % of the optimum.
    const MeasuredBtf btf = test::sampleBtf(16, 16);
    const Eigen::MatrixXd a = abrdfMatrix(btf);
    const Eigen::MatrixXf af = a.cast<float>();
    const Eigen::VectorXd sigma = test::referenceSingularValues(a);
    RowBlockSource source;
    source.rows = std::size_t(a.rows());
    source.cols = std::size_t(a.cols());
    source.blockRows = 30;  // 19683 rows: the last block is shorter
    source.fill = [&](std::size_t first, std::size_t count, float* out) {
        for (std::size_t r = 0; r < count; ++r)
            for (std::size_t t = 0; t < source.cols; ++t)
                out[r * source.cols + t] = af(Eigen::Index(first + r), Eigen::Index(t));
    };
    StreamedSvdOptions options;
    options.gramColumns = 0;
    std::atomic<std::size_t> progress{0};
    options.progress = [&](std::size_t rows) { progress += rows; };
    for (int c : {4, 16}) {
        progress = 0;
        const TruncatedSvd svd = streamedTruncatedSvd(source, c, options);
        EXPECT_EQ(progress, source.rows * std::size_t(options.passes(source.cols)));
        const Eigen::Map<const Eigen::MatrixXf> u(svd.u.data(), a.rows(), c),
            v(svd.v.data(), a.cols(), c);
        Eigen::VectorXd s(c);
        for (int k = 0; k < c; ++k) s(k) = svd.singularValues[std::size_t(k)];
        const Eigen::MatrixXd approx =
            u.cast<double>() * s.asDiagonal() * v.cast<double>().transpose();
        const double got = (a - approx).norm(), optimal = optimalError(sigma, c);
        EXPECT_LE(got, optimal * 1.001) << c;
        EXPECT_GE(got, optimal * 0.999) << c;
        // residualSquared() from ||A||^2 minus the kept squares is that same error.
        EXPECT_NEAR(std::sqrt(svd.residualSquared()), got, 1e-3 * got) << c;
    }
    // Deterministic: the same seed gives the same factors.
    EXPECT_EQ(streamedTruncatedSvd(source, 4, options).u,
              streamedTruncatedSvd(source, 4, options).u);
}

TEST(Fmf, RendersEveryFactorVariantAsStoredAtMeasuredDirections) {
    struct Variant {
        std::string name;
        FactorModel model;
        std::array<int, 3> ranks;
        int colorModel;
        std::uint32_t drr;
        bool cosine;
    };
    const std::vector<Variant> variants = {
        {"fmf", FactorModel::Fmf, {5, 5, 5}, 0, 0, false},
        {"fmf drr cosine", FactorModel::Fmf, {6, 6, 6}, 0, 1, true},
        {"dfmf rgb", FactorModel::Dfmf, {3, 5, 2}, 0, 0, false},
        {"dfmf yuv", FactorModel::Dfmf, {4, 1, 7}, 1, 0, true},
        {"dfmf pca", FactorModel::Dfmf, {2, 6, 3}, 3, 0, false},
        {"dfmf ycocg", FactorModel::Dfmf, {5, 5, 1}, 4, 0, false},
        {"dfmf exp-yuv", FactorModel::Dfmf, {8, 3, 4}, 11, 0, true}};
    for (const Variant& variant : variants) {
        FactoredBtf f = randomFactors(variant.model, variant.ranks, 5, 4, 7);
        test::setDecoding(f, variant.colorModel, variant.drr, variant.cosine);
        for (auto storage : {MaterialTexture::Float, MaterialTexture::Half}) {
            osg::ref_ptr<FmfMaterial> m = FmfMaterial::fromFactors(f, storage);
            const FactoredBtf stored = m->completeFactors();
            // U and SxV are kept once, as the GPU textures: no copy stays in the factors.
            for (const BtfFactor& kept : m->factors().factors) {
                EXPECT_EQ(kept.SxV.size(), 0);
                EXPECT_EQ(kept.U.size(), 0);
            }
            EXPECT_EQ(m->u().halves.empty(), storage == MaterialTexture::Float);
            EXPECT_EQ(m->width(), 5);
            EXPECT_EQ(m->height(), 4);
            EXPECT_EQ(stored.components(2),
                      variant.model == FactorModel::Fmf ? variant.ranks[0] : variant.ranks[2]);
            // Half storage: U and SxV are the rounded values, within half's 2^-11 relative.
            for (std::size_t i = 0; i < f.factors.size(); ++i) {
                const float d = (stored.factors[i].U - f.factors[i].U).cwiseAbs().maxCoeff();
                EXPECT_LE(d, storage == MaterialTexture::Half ? 0.5f / 2048 : 0.0f);
                ASSERT_EQ(stored.factors[i].SxV.rows(), 20);
                EXPECT_EQ(stored.factors[i].SxV.cols(), stored.factors[i].U.cols());
                if (storage == MaterialTexture::Half)
                    for (Eigen::Index j = 0; j < stored.factors[i].SxV.size(); ++j) {
                        const float x = stored.factors[i].SxV.data()[j];
                        EXPECT_EQ(float(Imath::half(x)), x);
                    }
            }
            // At measured directions: FactoredBtf's decode of the stored factors.
            std::vector<float> abrdf(stored.imageCount() * 3), expected(abrdf.size());
            for (int y = 0; y < 4; ++y)
                for (int x = 0; x < 5; ++x) {
                    const std::size_t texel = std::size_t(y) * 5 + std::size_t(x);
                    for (std::size_t v : {0u, 17u, 80u})
                        for (std::size_t l : {0u, 33u, 79u}) {
                            const glm::vec3 want = stored.value(v, l, x, y);
                            const glm::vec3 got =
                                m->evaluate(x, y, m->views().vector(v), m->lights().vector(l));
                            for (int c = 0; c < 3; ++c)
                                EXPECT_NEAR(got[c], want[c], 1e-5f * (1 + std::abs(want[c])))
                                    << variant.name << " " << x << "," << y << " " << v << "/" << l;
                        }
                    m->evaluateMeasured(texel, abrdf.data());
                    stored.decodeAbrdfs({texel}, expected.data());
                    for (std::size_t i = 0; i < abrdf.size(); ++i)
                        ASSERT_NEAR(abrdf[i], expected[i], 1e-5f * (1 + std::abs(expected[i])))
                            << variant.name << " texel " << texel << " value " << i;
                }
        }
    }
}

TEST(Fmf, BlendsFactorSumsBeforeDecodingAtUnmeasuredDirections) {
    // Model 11 (exp-YUV) with the cosine: the expected value is the decode of the blended sums of
    // the 9 combinations (the exact Delaunay weights), divided by the query light's z.
    FactoredBtf f = randomFactors(FactorModel::Dfmf, {4, 2, 3}, 3, 2, 11);
    f.colorModel = 11;
    f.cosine = true;
    osg::ref_ptr<FmfMaterial> m = FmfMaterial::fromFactors(f, MaterialTexture::Float);
    // The raw sums: the same factors read as RGB without the cosine.
    FactoredBtf raw = m->completeFactors();
    raw.colorModel = 0;
    raw.cosine = false;
    const DirectionInterpolator interpolator(f.views);
    for (const auto& [vd, ld] : kUnmeasured) {
        const glm::vec3 view = vd.toVector(), light = ld.toVector();
        const InterpolationWeights wv = interpolator.weights(view);
        const InterpolationWeights wl = interpolator.weights(light);
        EXPECT_GT(std::count_if(wv.weight.begin(), wv.weight.end(), [](float w) { return w > 0; }),
                  1);
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 3; ++x) {
                glm::vec3 sums(0.0f);
                for (int i = 0; i < 3; ++i)
                    for (int j = 0; j < 3; ++j)
                        sums += wv.weight[std::size_t(i)] * wl.weight[std::size_t(j)] *
                                raw.value(std::size_t(wv.index[std::size_t(i)]),
                                          std::size_t(wl.index[std::size_t(j)]), x, y);
                const float s[3] = {sums.x, sums.y, sums.z};
                float rgb[3];
                f.decodeColor(s, rgb);
                const glm::vec3 got = m->evaluate(x, y, view, light);
                for (int c = 0; c < 3; ++c) {
                    const float want = rgb[c] / light.z;
                    EXPECT_NEAR(got[c], want, 1e-5f * (1 + std::abs(want)));
                }
            }
    }
}

TEST(Fmf, BadFactorsAreRefused) {
    FactoredBtf f = randomFactors(FactorModel::Dfmf, {2, 2, 2}, 3, 2, 1);
    f.colorModel = 7;
    EXPECT_EQ(test::errorOf([&] { FmfMaterial::fromFactors(f); }),
              "random.btf: DFMF colour model 7 is not supported (supported: 0 RGB, 1 YUV, 3 "
              "PCA, 4 YCoCg, 11 exp-YUV)");
    f.colorModel = 0;
    f.factors[1].SxV(3, 1) = 1e5f;
    EXPECT_EQ(test::errorOf([&] { FmfMaterial::fromFactors(f); }),
              "random.btf: fmf: SxV value 100000 exceeds the half range (65504); use "
              "storage=float");
    EXPECT_EQ(test::errorOf([&] { FmfMaterial::fromFactors(f, MaterialTexture::Float); }),
              "no error");
    f.factors.pop_back();
    EXPECT_EQ(test::errorOf([&] { FmfMaterial::fromFactors(f); }),
              "random.btf: inconsistent factors: 2 factor sets (DFMF needs 3) for 6561 images "
              "of 6 texels");
}

TEST(Fmf, SaveLoadRoundTripIsExact) {
    test::TempDir dir;
    FactoredBtf dfmf = randomFactors(FactorModel::Dfmf, {3, 6, 2}, 5, 3, 3);
    dfmf.colorModel = 3;
    dfmf.cosine = true;
    dfmf.colorMean = {0.1f, 0.2f, 1.0f / 3.0f};
    dfmf.colorMatrix = {0.5f, 0.2f, 0.1f, -0.3f, 0.6f, 0.2f, 0.1f, -0.2f, 0.7f};
    FactoredBtf drr = randomFactors(FactorModel::Fmf, {5, 5, 5}, 4, 4, 4);
    drr.dynamicRangeReduction = 1;
    drr.eps = 1e-4f;
    std::vector<osg::ref_ptr<FmfMaterial>> materials = {
        FmfMaterial::fromFactors(dfmf, MaterialTexture::Half),
        FmfMaterial::fromFactors(drr, MaterialTexture::Float),
        FmfMaterial::fit(test::sampleBtf(8, 6), FitOptions::parse("components=5"))};
    for (std::size_t i = 0; i < materials.size(); ++i) {
        const FmfMaterial& m = *materials[i];
        const std::string path = dir.file("fmf-" + std::to_string(i) + ".exr");
        saveMaterial(m, path);
        osg::ref_ptr<Material> loaded = loadMaterial(path);
        ASSERT_EQ(loaded->methodName(), "fmf");
        const FmfMaterial& back = static_cast<const FmfMaterial&>(*loaded);
        const FactoredBtf a = m.completeFactors(), b = back.completeFactors();
        EXPECT_EQ(back.storage(), m.storage());
        EXPECT_EQ(b.model, a.model);
        EXPECT_EQ(b.colorModel, a.colorModel);
        EXPECT_EQ(b.colorMean, a.colorMean);
        EXPECT_EQ(b.colorMatrix, a.colorMatrix);
        EXPECT_EQ(b.cosine, a.cosine);
        EXPECT_EQ(b.dynamicRangeReduction, a.dynamicRangeReduction);
        EXPECT_EQ(b.eps, a.eps);
        ASSERT_EQ(b.factors.size(), a.factors.size());
        for (std::size_t f = 0; f < a.factors.size(); ++f) {
            EXPECT_EQ(b.factors[f].U, a.factors[f].U) << i;
            EXPECT_EQ(b.factors[f].SxV, a.factors[f].SxV) << i;
            EXPECT_EQ(b.factors[f].S, a.factors[f].S) << i;
        }
        const glm::vec3 view = Direction{33, 71}.toVector(), light = Direction{52, 200}.toVector();
        EXPECT_EQ(back.evaluate(2, 1, view, light), m.evaluate(2, 1, view, light));
        EXPECT_EQ(back.fitInfo, m.fitInfo);
    }
    // assignFrom and the osg copy keep the factors.
    osg::ref_ptr<FmfMaterial> copy = new FmfMaterial;
    copy->assignFrom(*materials[0]);
    EXPECT_EQ(copy->completeFactors().factors[1].U, materials[0]->completeFactors().factors[1].U);
    osg::ref_ptr<FmfMaterial> cloned =
        static_cast<FmfMaterial*>(materials[1]->clone(osg::CopyOp::SHALLOW_COPY));
    EXPECT_EQ(cloned->completeFactors().factors[0].SxV,
              materials[1]->completeFactors().factors[0].SxV);
}

TEST(Fmf, LoadingTakesTheFilesUAndSxvTexturesWithThePaddingZeroed) {
    // What loadMaterial hands over: the u and sxv textures as halves, moved into the material
    // (their padding beyond rank 3 is garbage here, which must not reach the renders).
    FittedMaterial file = FmfMaterial::fit(test::sampleBtf(4, 3), FitOptions::parse("components=3"))
                              ->toFittedMaterial();
    for (MaterialTexture& t : file.textures)
        if (t.kind == MaterialTexture::Half) {
            t.halves.assign(t.data.begin(), t.data.end());
            t.data.clear();
        }
    MaterialTexture* sxv = nullptr;
    for (MaterialTexture& t : file.textures)
        if (t.name == "sxv") sxv = &t;
    ASSERT_NE(sxv, nullptr);
    ASSERT_EQ(sxv->depth, 1);  // rank 3: one layer, component 3 is padding
    const Imath::half* before = sxv->halves.data();
    for (std::size_t texel = 0; texel < 12; ++texel) sxv->halves[texel * 4 + 3] = 7.0f;
    MaterialTexture* u = &file.texture("u");
    ASSERT_EQ(u->width, 1);  // one group of 4 per (view, light, channel) row
    const Imath::half* uBefore = u->halves.data();
    for (std::size_t row = 0; row < u->halves.size() / 4; ++row) u->halves[row * 4 + 3] = -5.0f;
    const FittedMaterial copy = file;
    osg::ref_ptr<FmfMaterial> m = FmfMaterial::fromFile(std::move(file));
    const MaterialTexture kept = m->sxvTexture();
    ASSERT_EQ(kept.data.size(), copy.texture("sxv").halves.size());
    for (std::size_t i = 0; i < kept.data.size(); ++i)
        EXPECT_EQ(kept.data[i], i % 4 == 3 ? 0.0f : float(copy.texture("sxv").halves[i])) << i;
    const MaterialTexture keptU = m->uTexture();
    ASSERT_EQ(keptU.data.size(), copy.texture("u").halves.size());
    for (std::size_t i = 0; i < keptU.data.size(); ++i)
        EXPECT_EQ(keptU.data[i], i % 4 == 3 ? 0.0f : float(copy.texture("u").halves[i])) << i;
    // Held, not copied: the material's textures are the file's arrays.
    EXPECT_EQ(m->sxv().halves.data(), before);
    EXPECT_TRUE(m->sxv().data.empty());
    EXPECT_EQ(m->u().halves.data(), uBefore);
    EXPECT_TRUE(m->u().data.empty());
    FittedMaterial infinite = copy;
    for (MaterialTexture& t : infinite.textures)
        if (t.name == "sxv") t.halves[5] = std::numeric_limits<Imath::half>::infinity();
    infinite.source = "inf.btfmat";
    EXPECT_EQ(test::errorOf([&] { FmfMaterial::fromFile(infinite); }),
              "inf.btfmat: fmf: SxV value inf exceeds the half range (65504); use storage=float");
    FittedMaterial infiniteU = copy;
    infiniteU.texture("u").halves[6] = -std::numeric_limits<Imath::half>::infinity();
    infiniteU.source = "inf.btfmat";
    EXPECT_EQ(test::errorOf([&] { FmfMaterial::fromFile(infiniteU); }),
              "inf.btfmat: fmf: U value -inf exceeds the half range (65504); use storage=float");
}

TEST(Fmf, FileWithMismatchedTexturesIsRefused) {
    test::TempDir dir;
    osg::ref_ptr<FmfMaterial> m =
        FmfMaterial::fit(test::sampleBtf(4, 3), FitOptions::parse("components=3"));
    FittedMaterial file = m->toFittedMaterial();
    file.parameters["components"] = "5";
    saveFittedMaterial(file, dir.file("bad.exr"));
    EXPECT_EQ(test::errorOf([&] { loadMaterial(dir.file("bad.exr")); }),
              dir.file("bad.exr") +
                  ": texture 'u' must be 2x243x81 RGBA half or float (as 'u') for components 5");
    file.parameters["components"] = "3,x";  // fmf: one rank
    saveFittedMaterial(file, dir.file("bad2.exr"));
    EXPECT_EQ(test::errorOf([&] { loadMaterial(dir.file("bad2.exr")); }),
              dir.file("bad2.exr") + ": parameter 'components' must be a number, got '3,x'");
}

TEST(Fmf, MemoryCountsSxvPerTexelAndUShared) {
    // Bonn 81 x 81, 256 x 256 texels, 32 components, half: SxV 32 values = 64 bytes per texel;
    // U (19683 x 32 halves, shared by all texels) 1.26 MB = 19.2 bytes per texel.
    FactoredBtf f = randomFactors(FactorModel::Fmf, {32, 32, 32}, 256, 256, 2);
    osg::ref_ptr<FmfMaterial> m = FmfMaterial::fromFactors(std::move(f));
    const FmfMaterial::MemoryBreakdown b = m->memoryBreakdown();
    EXPECT_EQ(b.perTexelValues, 32.0);
    EXPECT_EQ(b.perTexelBytes, 64.0);
    EXPECT_DOUBLE_EQ(b.sharedValues, 19683.0 * 32 / 65536);
    EXPECT_DOUBLE_EQ(b.sharedBytes, 2 * 19683.0 * 32 / 65536);
    EXPECT_EQ(b.uBytes, 19683ull * 32 * 2);
    EXPECT_EQ(b.sxvBytes, 65536ull * 32 * 2);
    const MemoryFootprint mf = m->memory();
    EXPECT_DOUBLE_EQ(mf.bytesPerTexel, 64.0 + b.sharedBytes);
    EXPECT_EQ(mf.totalBytes, b.uBytes + b.sxvBytes);
    EXPECT_EQ(mf.sharedBytes, b.uBytes);  // btf compare's line under Table 2
    // DFMF with per-channel ranks 5, 8, 1: SxV layers of 4 padded: (2 + 2 + 1) x 4 values;
    // U rows padded to the widest channel (2 groups).
    osg::ref_ptr<FmfMaterial> d =
        FmfMaterial::fromFactors(randomFactors(FactorModel::Dfmf, {5, 8, 1}, 4, 4, 2));
    EXPECT_EQ(d->memoryBreakdown().perTexelValues, 20.0);
    EXPECT_EQ(d->memoryBreakdown().uBytes, 6561ull * 3 * 8 * 2);
    EXPECT_EQ(d->layerOffset(2), 4);
}

TEST(Fmf, SampleErrorIsFarBelowTheLambertBaseline) {
    const MeasuredBtf btf = test::sampleBtf(32, 32);
    osg::ref_ptr<FmfMaterial> m = FmfMaterial::fit(btf, {});
    const ErrorSummary fmf =
        computeError(btf, [&](std::size_t t, float* out) { m->evaluateMeasured(t, out); });
    osg::ref_ptr<LambertMaterial> lambert = LambertMaterial::fit(btf, {});
    const ErrorSummary base =
        computeError(btf, [&](std::size_t t, float* out) { lambert->evaluateMeasured(t, out); });
    std::cout << "fmf (32 components, half) on the 32x32 sample: error avg " << fmf.average
              << " min " << fmf.minimum << " max " << fmf.maximum << " (lambert avg "
              << base.average << "), fit " << m->fitInfo.at("seconds") << " s\n";
    EXPECT_EQ(fmf.nonFiniteValues, 0u);
    EXPECT_LT(fmf.average, base.average / 4);
}

}  // namespace OSGBTF_TEST_FILE
