// Method "hsh" (materials/hsh): option errors first, then the basis against its definition
// (hand-worked values, the trigonometric form the RTI tools write, orthonormality over the
// hemisphere), exact recovery of a field of harmonics, least-squares optimality, per-view
// blending, save/load.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>
#include <limits>

#include <Eigen/Core>
#include <Eigen/QR>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/hsh/Hsh.h"
#include "tests/HshReference.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

using osgBTF::test::errorOf;

namespace {

const double kPi = 3.14159265358979323846;
const double kFloatU = std::ldexp(1.0, -24);

osg::ref_ptr<HshMaterial> fit(const BtfSource& btf, const std::string& options) {
    return HshMaterial::fit(btf, FitOptions::parse(options));
}

glm::vec3 unit(double thetaDegrees, double phiDegrees) {
    const double t = thetaDegrees * kPi / 180, p = phiDegrees * kPi / 180;
    return glm::vec3(float(std::sin(t) * std::cos(p)), float(std::sin(t) * std::sin(p)),
                     float(std::cos(t)));
}

/** A known coefficient: multiples of 1/64 (exact in half), c0 large enough that the field stays
 *  positive (no clamp acts). */
double trueCoefficient(std::size_t texel, std::size_t view, int channel, int k) {
    if (k == 0) return 4.0 + double((texel + view + std::size_t(channel)) % 4) / 8;
    const double magnitude = double(1 + (texel * 3 + view + std::size_t(k + channel)) % 7) / 64;
    return (texel + std::size_t(k) + view) % 2 ? magnitude : -magnitude;
}

/** A BTF (Bonn views and lights) whose every (texel, view, channel) is the order-n field of
 *  trueCoefficient(), from the trigonometric form. */
MeasuredBtf harmonicsBtf(int width, int height, int order) {
    const DirectionSet bonn = DirectionSet::bonn81();
    MeasuredBtf btf(width, height, bonn, bonn);
    for (std::size_t v = 0; v < bonn.size(); ++v)
        for (std::size_t l = 0; l < bonn.size(); ++l) {
            const auto h = test::hshTrigonometricForm(bonn.vector(l));
            for (std::size_t t = 0; t < btf.texelCount(); ++t)
                for (int c = 0; c < 3; ++c) {
                    double sum = 0;
                    for (int k = 0; k < order * order; ++k)
                        sum += trueCoefficient(t, v, c, k) * h[std::size_t(k)];
                    btf.setValue(v, l, t, c, float(sum));
                }
        }
    return btf;
}

}  // namespace

// ---- options -----------------------------------------------------------------------------------

TEST(HshOptions, InvalidOptionsAreRefusedWithExactMessages) {
    const MeasuredBtf btf = test::sampleBtf(3, 2);
    EXPECT_EQ(errorOf([&] { fit(btf, "order=5"); }),
              "hsh: option order must be an integer in 2..4, got 5");
    EXPECT_EQ(errorOf([&] { fit(btf, "order=1"); }),
              "hsh: option order must be an integer in 2..4, got 1");
    EXPECT_EQ(errorOf([&] { fit(btf, "views=some"); }),
              "hsh: option views must be one of front, all, got some");
    EXPECT_EQ(errorOf([&] { fit(btf, "storage=unorm8"); }),
              "hsh: option storage must be one of half, float, got unorm8");
    EXPECT_EQ(errorOf([&] { fit(btf, "terms=9"); }),
              "hsh: option terms is unknown (known: order, views, storage)");
    EXPECT_EQ(errorOf([&] { fit(MeasuredBtf(), ""); }), "hsh: the BTF is empty");
    // 151 views x 16 terms: more layers than a texture array is guaranteed to hold.
    std::vector<Direction> many;
    for (int i = 0; i < 151; ++i) many.push_back({float(i % 8) * 10, float(i) * 2.3f});
    EXPECT_EQ(errorOf([&] {
                  HshMaterial::create(2, 2, DirectionSet("many", many), DirectionSet::bonn81(),
                                      {4, true, MaterialTexture::Half});
              }),
              "hsh: 151 views x 16 coefficient layers need 2416 texture layers, more than the "
              "2048 OpenGL guarantees (use views=front or a lower order)");
}

TEST(HshOptions, DefaultsAreOrderThreeOnTheFrontViewInHalf) {
    const osg::ref_ptr<HshMaterial> m = fit(test::sampleBtf(3, 2), "");
    EXPECT_EQ(m->shape().order, 3);
    EXPECT_EQ(m->terms(), 9);
    EXPECT_FALSE(m->shape().perView);
    EXPECT_EQ(m->shape().storage, MaterialTexture::Half);
    EXPECT_EQ(m->frontView(), 0u);
    EXPECT_EQ(m->fitInfo.at("rank"), "9");
    // 9 half RGB coefficients: 27 values, 54 bytes per texel.
    EXPECT_DOUBLE_EQ(m->memory().valuesPerTexel, 27);
    EXPECT_DOUBLE_EQ(m->memory().bytesPerTexel, 54);
}

// ---- the basis ---------------------------------------------------------------------------------

// Values worked out by hand from the formulas of Hsh.h. At the normal (t = 1, s = 0) only the
// zonal terms remain: h0 = 1/sqrt(2 pi), h2 = sqrt(3/(2 pi)), h6 = sqrt(5/(2 pi)) (1 - 6 + 6),
// h12 = sqrt(7/(2 pi)) (-1 + 12 - 30 + 20). At theta 60, phi 0 (t = 1/2, s = 1/2, 2t - 1 = 0,
// t^2 - t = -1/4, 1 - 5t + 5t^2 = -1/4): h1 = sqrt(6/pi)/2, h4 = -sqrt(30/pi)/4,
// h6 = sqrt(5/(2 pi)) (-1/2), h9 = 2 sqrt(35/pi)/8, h11 = -2 sqrt(21/pi)/8, the rest 0.
TEST(HshBasis, MatchesHandWorkedValues) {
    std::array<double, 16> atNormal{};
    atNormal[0] = 1 / std::sqrt(2 * kPi);
    atNormal[2] = std::sqrt(3 / (2 * kPi));
    atNormal[6] = std::sqrt(5 / (2 * kPi));
    atNormal[12] = std::sqrt(7 / (2 * kPi));
    std::array<double, 16> at60{};
    at60[0] = 1 / std::sqrt(2 * kPi);
    at60[1] = std::sqrt(6 / kPi) / 2;
    at60[4] = -std::sqrt(30 / kPi) / 4;
    at60[6] = -std::sqrt(5 / (2 * kPi)) / 2;
    at60[9] = 2 * std::sqrt(35 / kPi) / 8;
    at60[11] = -2 * std::sqrt(21 / kPi) / 8;
    const glm::vec3 sixty(float(std::sqrt(0.75)), 0.0f, 0.5f);
    const auto d0 = HshMaterial::basisDouble({0, 0, 1});
    const auto d60 = HshMaterial::basisDouble(sixty);
    const auto f60 = HshMaterial::basis(sixty);
    for (std::size_t k = 0; k < 16; ++k) {
        EXPECT_NEAR(d0[k], atNormal[k], 1e-12) << "h" << k << " at the normal";
        // sixty's float components carry a rounding of ~3e-8.
        EXPECT_NEAR(d60[k], at60[k], 1e-6) << "h" << k << " at theta 60";
        EXPECT_NEAR(f60[k], at60[k], 1e-5) << "h" << k << " at theta 60 (float)";
    }
}

TEST(HshBasis, EqualsTheTrigonometricFormOfTheRtiTools) {
    for (const auto& [theta, phi] : std::vector<std::pair<double, double>>{
             {5, 10}, {30, 100}, {45, 200}, {60, 290}, {75, 333}, {89, 45}, {20, -170}}) {
        const glm::vec3 l = unit(theta, phi);
        const auto expected = test::hshTrigonometricForm(l);
        const auto got = HshMaterial::basisDouble(l);
        const auto gotFloat = HshMaterial::basis(l);
        for (std::size_t k = 0; k < 16; ++k) {
            EXPECT_NEAR(got[k], expected[k], 1e-9) << "h" << k << " at " << theta << "/" << phi;
            EXPECT_NEAR(gotFloat[k], expected[k], 2e-5) << "h" << k << " (float)";
        }
    }
}

// Hemispherical harmonics are orthonormal over the hemisphere (Gautron et al. 2004): midpoint
// quadrature in (theta, phi) with the solid-angle weight sin(theta); 200 x 400 cells leave a
// quadrature error of ~1e-4 on these smooth functions (the s = sqrt(t - t^2) factors have an
// infinite derivative at the horizon, where the midpoint rule converges more slowly).
TEST(HshBasis, IsOrthonormalOverTheHemisphere) {
    const int n = 200;
    Eigen::Matrix<double, 16, 16> gram = Eigen::Matrix<double, 16, 16>::Zero();
    for (int i = 0; i < n; ++i)
        for (int j = 0; j < 2 * n; ++j) {
            const double theta = (i + 0.5) / n * kPi / 2, phi = (j + 0.5) / (2 * n) * 2 * kPi;
            const double weight = std::sin(theta) * (kPi / 2 / n) * (2 * kPi / (2 * n));
            const glm::vec3 l(float(std::sin(theta) * std::cos(phi)),
                              float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
            const auto h = HshMaterial::basisDouble(l);
            const Eigen::Map<const Eigen::Matrix<double, 16, 1>> v(h.data());
            gram += weight * v * v.transpose();
        }
    const double off = (gram - Eigen::Matrix<double, 16, 16>::Identity()).cwiseAbs().maxCoeff();
    std::cout << "largest deviation of the hemisphere Gram matrix from I: " << off << "\n";
    EXPECT_LT(off, 2e-3);
}

TEST(HshBasis, BelowTheHorizonIsTheHorizon) {
    const auto below = HshMaterial::basis(glm::vec3(0.8f, 0.0f, -0.6f));
    const auto horizon = HshMaterial::basis(glm::vec3(0.8f, 0.0f, 0.0f));
    for (std::size_t k = 0; k < 16; ++k) EXPECT_EQ(below[k], horizon[k]) << k;
}

// ---- fit ---------------------------------------------------------------------------------------

// Data that are a field of harmonics are recovered, for every order and per view: least squares
// returns the exact coefficients of consistent data, up to the data's float rounding amplified by
// the design's conditioning (bounded loosely here) and the coefficients' own rounding.
TEST(HshFit, RecoversAFieldOfHarmonicsPerViewAtEveryOrder) {
    for (int order = 2; order <= 4; ++order) {
        SCOPED_TRACE("order " + std::to_string(order));
        const MeasuredBtf btf = harmonicsBtf(3, 2, order);
        const osg::ref_ptr<HshMaterial> m =
            fit(btf, "views=all storage=float order=" + std::to_string(order));
        ASSERT_EQ(m->fitInfo.at("rank"), std::to_string(order * order));
        double worst = 0;
        for (std::size_t t = 0; t < btf.texelCount(); ++t)
            for (std::size_t v = 0; v < btf.viewCount(); ++v)
                for (int c = 0; c < 3; ++c)
                    for (int k = 0; k < order * order; ++k)
                        worst = std::max(worst, std::abs(double(m->coefficient(t, int(v), k, c)) -
                                                         trueCoefficient(t, v, c, k)));
        std::cout << "order " << order << ": largest coefficient error " << worst << "\n";
        EXPECT_LT(worst, 1e-4);
        // The half model rounds each coefficient to the nearest half: these multiples of 1/64
        // below 8 are exact in half, and the fit's error is far below half a step.
        const osg::ref_ptr<HshMaterial> half = fit(btf, "views=all order=" + std::to_string(order));
        for (int k = 0; k < order * order; ++k)
            EXPECT_EQ(half->coefficient(1, 5, k, 2), float(trueCoefficient(1, 5, 2, k))) << k;
    }
}

// Least squares: the fitted values (float storage) reach the optimum computed here by a QR
// solve of the design built from the trigonometric form, on the built-in sample's front view.
TEST(HshFit, ReachesTheLeastSquaresOptimum) {
    const MeasuredBtf btf = test::sampleBtf(4, 4);
    double previousOptimum = std::numeric_limits<double>::infinity();
    for (int order = 2; order <= 4; ++order) {
        const int n = order * order;
        const osg::ref_ptr<HshMaterial> m =
            fit(btf, "storage=float order=" + std::to_string(order));
        Eigen::MatrixXd a(Eigen::Index(btf.lightCount()), n);
        for (std::size_t l = 0; l < btf.lightCount(); ++l) {
            const auto h = test::hshTrigonometricForm(btf.lights().vector(l));
            for (int k = 0; k < n; ++k) a(Eigen::Index(l), k) = h[std::size_t(k)];
        }
        const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(a);
        double optimum = 0, fitted = 0;
        for (std::size_t t = 0; t < btf.texelCount(); ++t)
            for (int c = 0; c < 3; ++c) {
                Eigen::VectorXd y(Eigen::Index(btf.lightCount()));
                for (std::size_t l = 0; l < btf.lightCount(); ++l)
                    y(Eigen::Index(l)) = btf.value(0, l, t, c);
                optimum += (a * qr.solve(y) - y).squaredNorm();
                Eigen::VectorXd mine(n);
                for (int k = 0; k < n; ++k) mine(k) = m->coefficient(t, 0, k, c);
                fitted += (a * mine - y).squaredNorm();
            }
        std::cout << "order " << order << ": squared residual " << fitted << ", optimum " << optimum
                  << "\n";
        EXPECT_LE(fitted, optimum * (1 + 1e-5) + 1e-9) << "order " << order;
        // More terms never fit worse (nested bases): each order's optimum is at most the last's.
        EXPECT_LE(optimum, previousOptimum * (1 + 1e-9)) << "order " << order;
        previousOptimum = optimum;
    }
}

TEST(HshViews, BlendingAtAMeasuredViewReturnsThatViewsField) {
    const MeasuredBtf btf = harmonicsBtf(2, 2, 3);
    const osg::ref_ptr<HshMaterial> m = fit(btf, "views=all storage=float");
    for (const std::size_t v : {std::size_t(0), std::size_t(13), std::size_t(77)})
        for (const std::size_t l : {std::size_t(4), std::size_t(40)}) {
            const glm::vec3 got = m->evaluate(1, 0, btf.views().vector(v), btf.lights().vector(l));
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got[c], btf.value(v, l, 1, c), 1e-4)
                    << "view " << v << " light " << l << " channel " << c;
        }
}

// ---- file --------------------------------------------------------------------------------------

TEST(HshFile, SaveLoadRoundTripIsExactAndBadParametersAreNamed) {
    const MeasuredBtf btf = test::sampleBtf(3, 2);
    for (const char* options : {"", "order=4 views=all storage=float", "order=2"}) {
        const osg::ref_ptr<HshMaterial> m = fit(btf, options);
        const osg::ref_ptr<Material> back = materialFromFile(m->toFittedMaterial());
        const auto* hsh = dynamic_cast<const HshMaterial*>(back.get());
        ASSERT_NE(hsh, nullptr) << options;
        EXPECT_EQ(hsh->shape().order, m->shape().order);
        EXPECT_EQ(hsh->shape().perView, m->shape().perView);
        for (const glm::vec3& light : {glm::vec3(0, 0, 1), glm::vec3(0.6f, 0.48f, 0.64f)})
            EXPECT_EQ(hsh->evaluate(2, 1, {0.3f, 0.1f, 0.948683f}, light),
                      m->evaluate(2, 1, {0.3f, 0.1f, 0.948683f}, light))
                << options;
    }
    FittedMaterial file = fit(btf, "")->toFittedMaterial();
    file.source = "x.btfmat";
    file.parameters["order"] = "5";
    EXPECT_EQ(errorOf([&] { materialFromFile(file); }),
              "x.btfmat: parameter 'order' must be 2, 3 or 4, got '5'");
    file.parameters["order"] = "4";  // 16 layers expected, the file has 9
    EXPECT_EQ(errorOf([&] { materialFromFile(file); }),
              "x.btfmat: texture 'coefficients' must be 3x2, 16 layer(s) of RGB half");
}

}  // namespace OSGBTF_TEST_FILE
