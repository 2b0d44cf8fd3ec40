// Method "ptm" (materials/ptm): option errors, exact recovery of a PTM, least-squares optimality,
// luminance vs rgb on grey data, per-view blending, save/load, Boßerhoff and Nicoll 2003 Table 2
// memory.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include <Eigen/Core>
#include <Eigen/SVD>
#include <glm/common.hpp>
#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodOptions.h"
#include "materials/lambert/Lambert.h"
#include "materials/ptm/Ptm.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

using osgBTF::test::errorOf;

namespace {

/** Unit roundoff of float: every stored float value is within u of the exact one (relative). */
const double kFloatU = std::ldexp(1.0, -24);

osg::ref_ptr<PtmMaterial> fit(const BtfSource& btf, const std::string& options) {
    return PtmMaterial::fit(btf, FitOptions::parse(options));
}

/** A known coefficient: multiples of 1/32 with |a| >= 1/16 (exact in half, and far enough from 0
 *  that half's spacing there is coarse), a5 large enough for positive values. */
double trueCoefficient(std::size_t texel, std::size_t view, int channel, int k) {
    if (k == 5) return 1.0 + double((texel + view + std::size_t(channel)) % 4) / 8;
    const double magnitude = double(2 + (texel * 3 + view + std::size_t(k + channel)) % 7) / 32;
    return (texel + std::size_t(k) + view) % 2 ? magnitude : -magnitude;
}

double polynomial(const std::array<double, 6>& m, std::size_t texel, std::size_t view,
                  int channel) {
    double sum = 0;
    for (int k = 0; k < 6; ++k) sum += trueCoefficient(texel, view, channel, k) * m[k];
    return sum;
}

/** A BTF whose every (texel, view, channel) is the PTM trueCoefficient() defines, in float. */
MeasuredBtf ptmBtf(int width, int height) {
    const DirectionSet bonn = DirectionSet::bonn81();
    MeasuredBtf btf(width, height, bonn, bonn);
    for (std::size_t v = 0; v < bonn.size(); ++v)
        for (std::size_t l = 0; l < bonn.size(); ++l) {
            const auto m = PtmMaterial::monomials(bonn.vector(l));
            for (std::size_t t = 0; t < btf.texelCount(); ++t)
                for (int c = 0; c < 3; ++c) btf.setValue(v, l, t, c, float(polynomial(m, t, v, c)));
        }
    return btf;
}

/** The design matrix of a light set, built here from its definition. */
Eigen::MatrixXd design(const DirectionSet& lights) {
    Eigen::MatrixXd a(Eigen::Index(lights.size()), 6);
    for (std::size_t l = 0; l < lights.size(); ++l) {
        const glm::vec3 d = lights.vector(l);
        const double x = d.x, y = d.y;
        a.row(Eigen::Index(l)) << x * x, y * y, x * y, x, y, 1.0;
    }
    return a;
}

/** One (texel, view, channel)'s measured values over the lights. */
Eigen::VectorXd values(const MeasuredBtf& btf, std::size_t texel, std::size_t view, int c) {
    Eigen::VectorXd y(Eigen::Index(btf.lightCount()));
    for (std::size_t l = 0; l < btf.lightCount(); ++l)
        y(Eigen::Index(l)) = btf.value(view, l, texel, c);
    return y;
}

}  // namespace

// ---- options -----------------------------------------------------------------------------------

TEST(PtmOptions, InvalidOptionsAreRefusedWithExactMessages) {
    const MeasuredBtf btf = test::sampleBtf(3, 2);
    EXPECT_EQ(errorOf([&] { fit(btf, "colour=grey"); }),
              "ptm: option colour must be one of rgb, luminance, got grey");
    EXPECT_EQ(errorOf([&] { fit(btf, "views=some"); }),
              "ptm: option views must be one of front, all, got some");
    EXPECT_EQ(errorOf([&] { fit(btf, "storage=unorm8"); }),
              "ptm: option storage must be one of half, float, got unorm8");
    EXPECT_EQ(errorOf([&] { fit(btf, "lobes=2"); }),
              "ptm: option lobes is unknown (known: colour, views, storage)");
    EXPECT_EQ(errorOf([&] { fit(MeasuredBtf(), ""); }), "ptm: the BTF is empty");
    // One view: views=all is that view (a set of one direction interpolates to it).
    const DirectionSet one("one", {{0, 0}});
    MeasuredBtf single(2, 2, one, DirectionSet::bonn81());
    EXPECT_EQ(fit(single, "views=all")->slots(), 1);
    EXPECT_EQ(fit(single, "")->slots(), 1);
}

TEST(PtmOptions, DefaultsAreTheSeedsRgbFrontViewPtmInHalf) {
    const osg::ref_ptr<PtmMaterial> m = fit(test::sampleBtf(3, 2), "");
    EXPECT_FALSE(m->shape().luminance);
    EXPECT_FALSE(m->shape().perView);
    EXPECT_EQ(m->shape().storage, MaterialTexture::Half);
    EXPECT_EQ(m->frontView(), 0u);  // Bonn view 0 is theta 0, the normal
    EXPECT_EQ(m->fitInfo.at("front-view"), "0/0");
    EXPECT_EQ(m->fitInfo.at("rank"), "6");
}

// ---- fit ---------------------------------------------------------------------------------------

// Data that are a PTM are recovered: least squares returns the exact coefficients of consistent
// data. The data are floats, so each value carries a rounding |dy| <= u |y|; the coefficients move
// by A+ dy, at most |dy|_2 / sigma_min(A) (sigma_min from a direct SVD of the design here), then
// are rounded to float (u |a|).
TEST(PtmFit, RecoversAPtmExactlyPerView) {
    const MeasuredBtf btf = ptmBtf(4, 3);
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(design(btf.lights()));
    const double sigmaMin = svd.singularValues()(5);
    ASSERT_GT(sigmaMin, 0.05);  // the Bonn lights determine all six terms
    const osg::ref_ptr<PtmMaterial> m = fit(btf, "views=all storage=float");
    const osg::ref_ptr<PtmMaterial> half = fit(btf, "views=all");
    double worst = 0;
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        for (std::size_t v = 0; v < btf.viewCount(); ++v)
            for (int c = 0; c < 3; ++c) {
                const double dy = kFloatU * values(btf, t, v, c).norm() / sigmaMin;
                for (int k = 0; k < 6; ++k) {
                    const double truth = trueCoefficient(t, v, c, k);
                    const double got = m->coefficient(t, int(v), k, c);
                    worst = std::max(worst, std::abs(got - truth));
                    ASSERT_LE(std::abs(got - truth), dy + kFloatU * std::abs(truth))
                        << "texel " << t << " view " << v << " channel " << c << " a" << k;
                    // That error is far below half a step of half at |a| >= 1/16 (2^-15), so
                    // the half model holds the true coefficients exactly.
                    ASSERT_EQ(half->coefficient(t, int(v), k, c), float(truth))
                        << "texel " << t << " view " << v << " channel " << c << " a" << k;
                }
            }
    std::cout << "largest coefficient error (float storage) " << worst << "\n";
}

// The luminance variant on data that are a colour times a PTM reproduces every measured value:
// the luminance fit's polynomial is the projection of the luminance values (A A+ dy has norm at
// most |dy|), the colour the projection of each channel onto it; each stage moves a value by at
// most the data's rounding in the 2-norm, and evaluating 6 float terms adds 6 u sum |a_k m_k|.
TEST(PtmFit, LuminanceVariantRecoversAColourTimesAPtm) {
    const DirectionSet bonn = DirectionSet::bonn81();
    MeasuredBtf btf(3, 3, bonn, bonn);
    const double colour[3][3] = {{0.9, 0.6, 0.3}, {0.2, 0.5, 1.4}, {1.0, 1.0, 1.0}};
    for (std::size_t v = 0; v < bonn.size(); ++v)
        for (std::size_t l = 0; l < bonn.size(); ++l) {
            const auto m = PtmMaterial::monomials(bonn.vector(l));
            for (std::size_t t = 0; t < btf.texelCount(); ++t)
                for (int c = 0; c < 3; ++c)
                    btf.setValue(v, l, t, c, float(colour[t % 3][c] * polynomial(m, t, v, 0)));
        }
    for (const char* views : {"front", "all"}) {
        const osg::ref_ptr<PtmMaterial> m =
            fit(btf, std::string("colour=luminance storage=float views=") + views);
        std::vector<float> model(btf.imageCount() * 3);
        for (std::size_t t = 0; t < btf.texelCount(); ++t) {
            m->evaluateMeasured(t, model.data());
            for (std::size_t v = 0; v < btf.viewCount(); ++v) {
                // The front model holds view 0's PTM only: compare where it is defined.
                if (std::string(views) == "front" && v != 0) continue;
                for (int c = 0; c < 3; ++c) {
                    double sumTerms = 0;
                    for (int k = 0; k < 6; ++k)
                        sumTerms += std::abs(colour[t % 3][c] * trueCoefficient(t, v, 0, k));
                    const double bound =
                        3 * kFloatU * values(btf, t, v, c).norm() + 8 * kFloatU * sumTerms;
                    for (std::size_t l = 0; l < btf.lightCount(); ++l)
                        ASSERT_NEAR(model[(v * btf.lightCount() + l) * 3 + c],
                                    btf.value(v, l, t, c), bound)
                            << views << " texel " << t << " view " << v << " light " << l;
                }
            }
        }
        // The colour has unit Rec. 709 luminance (the polynomial is the luminance): exactly for
        // the exact fit; the stored polynomial and colour are rounded to float, a few u of the
        // colour's size.
        for (std::size_t t = 0; t < btf.texelCount(); ++t) {
            float rgb[3];
            m->colour.read(t * 3, 3, rgb);
            EXPECT_NEAR(0.2126 * rgb[0] + 0.7152 * rgb[1] + 0.0722 * rgb[2], 1.0,
                        16 * kFloatU * (1 + rgb[0] + rgb[1] + rgb[2]))
                << t;
        }
    }
}

// Least squares: the residual of each fitted (texel, channel) is orthogonal to the six design
// columns. With float storage the stored coefficients are the exact solution rounded (|da_j| <=
// u |a_j|), so A^T r = -A^T A da: |(A^T r)_k| <= u sum_j |G_kj| |a_j|.
TEST(PtmFit, ResidualIsOrthogonalToTheDesignColumns) {
    const MeasuredBtf btf = test::sampleBtf(6, 5);
    const Eigen::MatrixXd a = design(btf.lights());
    const Eigen::MatrixXd gram = a.transpose() * a;
    const osg::ref_ptr<PtmMaterial> m = fit(btf, "storage=float");
    double worstRatio = 0;
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        for (int c = 0; c < 3; ++c) {
            Eigen::VectorXd coefficients(6);
            for (int k = 0; k < 6; ++k) coefficients(k) = m->coefficient(t, 0, k, c);
            const Eigen::VectorXd y = values(btf, t, 0, c);
            const Eigen::VectorXd projection = a.transpose() * (y - a * coefficients);
            const Eigen::VectorXd bound =
                kFloatU * (gram.cwiseAbs() * coefficients.cwiseAbs()).array() + 1e-12;
            // Meaningful: the data themselves are far from orthogonal to the columns.
            EXPECT_GT((a.transpose() * y).cwiseAbs().maxCoeff(), 1e3 * bound.maxCoeff());
            for (int k = 0; k < 6; ++k) {
                worstRatio = std::max(worstRatio, std::abs(projection(k)) / bound(k));
                EXPECT_LE(std::abs(projection(k)), bound(k))
                    << "texel " << t << " channel " << c << " column " << k;
            }
        }
    std::cout << "largest |A^T r| / bound " << worstRatio << "\n";
}

// On grey data (R = G = B) the luminance of the channel fits is the channel fit, and the
// least-squares colour of a polynomial that is the projection of the data is 1: both variants
// give the same values, up to float rounding of the coefficients (u sum_k |a_k m_k|) and of the
// colour. The stored polynomial P = P* + A d (|d_k| <= u |a_k|) gives colour <y, P> / <P, P> =
// 1 - <P*, A d> / <P*, P*> + O(u^2), off by at most u K with K = sum_k |a_k| |A e_k| / |A a|.
TEST(PtmFit, LuminanceOnGreyDataEqualsRgb) {
    const MeasuredBtf colourful = test::sampleBtf(4, 4);
    MeasuredBtf grey(4, 4, colourful.views(), colourful.lights());
    for (std::size_t v = 0; v < grey.viewCount(); ++v)
        for (std::size_t l = 0; l < grey.lightCount(); ++l)
            for (std::size_t t = 0; t < grey.texelCount(); ++t) {
                const float y = colourful.value(v, l, t, 1);
                for (int c = 0; c < 3; ++c) grey.setValue(v, l, t, c, y);
            }
    const osg::ref_ptr<PtmMaterial> rgb = fit(grey, "storage=float views=all");
    const osg::ref_ptr<PtmMaterial> lum = fit(grey, "storage=float views=all colour=luminance");
    const Eigen::MatrixXd a = design(grey.lights());
    for (std::size_t t = 0; t < grey.texelCount(); ++t)
        for (int slot = 0; slot < rgb->slots(); slot += 7) {
            Eigen::VectorXd coefficients(6);
            double spread = 0;
            for (int k = 0; k < 6; ++k) {
                coefficients(k) = rgb->coefficient(t, slot, k, 0);
                spread += std::abs(coefficients(k)) * a.col(k).norm();
            }
            const double colourBound = 2 * kFloatU * (spread / (a * coefficients).norm() + 1);
            for (std::size_t l = 0; l < grey.lightCount(); l += 5) {
                const glm::vec3 d = grey.lights().vector(l);
                const glm::vec3 p = rgb->field(t, slot, d.x, d.y),
                                q = lum->field(t, slot, d.x, d.y);
                const auto m = PtmMaterial::monomials(d);
                double sumTerms = 0;
                for (int k = 0; k < 6; ++k)
                    sumTerms += std::abs(rgb->coefficient(t, slot, k, 0) * m[k]);
                const double bound = colourBound * std::abs(p.r) + 4 * kFloatU * sumTerms;
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(p[c], q[c], bound) << "texel " << t << " view " << slot;
            }
        }
}

// ---- views -------------------------------------------------------------------------------------

// At a measured view the Delaunay weights are that view's (1, 0, 0), up to the float rounding of
// the barycentric coordinates (well below 1e-5 for directions on the unit sphere), so the blend is
// that view's own PTM; between views it is a blend of distinct PTMs.
TEST(PtmViews, BlendingAtAMeasuredViewReturnsThatViewsPtm) {
    const MeasuredBtf btf = test::sampleBtf(4, 3);
    const osg::ref_ptr<PtmMaterial> m = fit(btf, "views=all colour=luminance");
    const DirectionSet& views = m->views();
    const std::vector<Direction> lights = {{0, 0}, {37, 110}, {60, 285}, {80, 10}};
    int distinct = 0;
    for (std::size_t v = 0; v < views.size(); v += 4)
        for (const Direction& light : lights) {
            const glm::vec3 l = light.toVector();
            const std::size_t t = (v * 5) % m->texelCount();
            const int x = int(t % 4), y = int(t / 4);
            const glm::vec3 own = glm::max(m->field(t, int(v), l.x, l.y), glm::vec3(0.0f));
            const glm::vec3 other =
                glm::max(m->field(t, int((v + 1) % views.size()), l.x, l.y), glm::vec3(0.0f));
            const glm::vec3 got = m->evaluate(x, y, views.vector(v), l);
            const float scale = std::max({1.0f, own.r, own.g, own.b});
            for (int c = 0; c < 3; ++c) ASSERT_NEAR(got[c], own[c], 1e-5f * scale) << v;
            distinct += glm::length(own - other) > 1e-3f ? 1 : 0;
        }
    EXPECT_GT(distinct, 10);  // the views' PTMs differ, so the check above can fail
    // The front model ignores the view.
    const osg::ref_ptr<PtmMaterial> front = fit(btf, "");
    const glm::vec3 l = Direction{30, 60}.toVector();
    EXPECT_EQ(front->evaluate(1, 2, views.vector(0), l),
              front->evaluate(1, 2, views.vector(40), l));
}

// ---- file and memory ---------------------------------------------------------------------------

TEST(PtmFile, SaveLoadRoundTripIsExact) {
    test::TempDir dir;
    for (const char* options : {"", "colour=luminance views=all"}) {
        const osg::ref_ptr<PtmMaterial> m = fit(test::sampleBtf(5, 3), options);
        saveMaterial(*m, dir.file("ptm.exr"));
        osg::ref_ptr<Material> loaded = loadMaterial(dir.file("ptm.exr"));
        ASSERT_EQ(loaded->methodName(), "ptm");
        const PtmMaterial& back = static_cast<const PtmMaterial&>(*loaded);
        EXPECT_EQ(back.shape().luminance, m->shape().luminance) << options;
        EXPECT_EQ(back.shape().perView, m->shape().perView) << options;
        EXPECT_EQ(back.coefficients, m->coefficients) << options;
        EXPECT_EQ(back.colour, m->colour) << options;
        const glm::vec3 v = Direction{37, 110}.toVector(), l = Direction{22, 300}.toVector();
        EXPECT_EQ(back.evaluate(4, 2, v, l), m->evaluate(4, 2, v, l)) << options;
    }
    // A file whose arrays do not match its declared shape is refused with the reason.
    const osg::ref_ptr<PtmMaterial> m = fit(test::sampleBtf(5, 3), "");
    FittedMaterial broken = m->toFittedMaterial();
    broken.parameters["views"] = "all";
    saveFittedMaterial(broken, dir.file("broken.exr"));
    EXPECT_EQ(
        errorOf([&] { loadMaterial(dir.file("broken.exr")); }),
        dir.file("broken.exr") + ": texture 'coefficients' must be 5x3, 486 layer(s) of RGB half");
    broken = m->toFittedMaterial();
    broken.parameters["colour"] = "grey";
    saveFittedMaterial(broken, dir.file("broken.exr"));
    EXPECT_EQ(errorOf([&] { loadMaterial(dir.file("broken.exr")); }),
              dir.file("broken.exr") + ": parameter 'colour' must be rgb or luminance, got 'grey'");
}

// Boßerhoff and Nicoll 2003 Table 2 (256x256, one view): PTM-RGB 6 MB, PTM-Lum 3 MB, i.e. 96 and 48
// bytes per texel: 18 coefficients in 6 RGBA float textures (24 floats) and 6 + 3 in 3 (12 floats).
// Ours stores the same 18 and 9 values without the unused fourth channel, as half: 36 and 18 bytes.
TEST(PtmMemory, MatchesBosserhoff2003Table2ValueCounts) {
    const DirectionSet bonn = DirectionSet::bonn81();
    struct Case {
        bool luminance, perView;
        MaterialTexture::PixelKind storage;
        double values, bytes;
    };
    for (const Case& c : {Case{false, false, MaterialTexture::Half, 18, 36},
                          Case{true, false, MaterialTexture::Half, 9, 18},
                          Case{false, false, MaterialTexture::Float, 18, 72},
                          Case{false, true, MaterialTexture::Half, 81 * 18, 81 * 36},
                          Case{true, true, MaterialTexture::Half, 81 * 9, 81 * 18}}) {
        PtmMaterial::Shape shape;
        shape.luminance = c.luminance;
        shape.perView = c.perView;
        shape.storage = c.storage;
        // Per texel the count is the same at any size; 16x16 keeps the 81-view models small.
        const osg::ref_ptr<PtmMaterial> m = PtmMaterial::create(16, 16, bonn, bonn, shape);
        const MemoryFootprint f = m->memory();
        EXPECT_DOUBLE_EQ(f.valuesPerTexel, c.values);
        EXPECT_DOUBLE_EQ(f.bytesPerTexel, c.bytes);
        EXPECT_EQ(f.totalBytes, std::uint64_t(c.bytes * 256));
    }
}

TEST(PtmSample, ErrorsOnTheBuiltInSample) {
    // For the record (README); the check: one PTM per view is the least-squares optimum of each
    // view, so its RMSE is below that of the front view's PTM used for every view (the clamp at 0
    // and half rounding change both by far less than the views differ).
    const MeasuredBtf btf = test::sampleBtf(16, 16);
    const auto errorOfFit = [&](const Material& m) {
        return computeError(btf, [&](std::size_t t, float* out) { m.evaluateMeasured(t, out); });
    };
    const ErrorSummary lambert = errorOfFit(*LambertMaterial::fit(btf, {}));
    std::cout << "lambert: avg " << lambert.average << " rmse " << lambert.rmse << "\n";
    double frontRmse = 0, allRmse = 0;
    for (const char* options :
         {"", "colour=luminance", "views=all", "views=all colour=luminance"}) {
        const osg::ref_ptr<PtmMaterial> m = fit(btf, options);
        const ErrorSummary e = errorOfFit(*m);
        std::cout << "ptm [" << options << "]: avg " << e.average << " min " << e.minimum << " max "
                  << e.maximum << " rmse " << e.rmse << "\n";
        EXPECT_EQ(e.nonFiniteValues, 0u);
        if (std::string(options).empty()) frontRmse = e.rmse;
        if (std::string(options) == "views=all") allRmse = e.rmse;
    }
    EXPECT_LT(allRmse, frontRmse);
}

}  // namespace OSGBTF_TEST_FILE
