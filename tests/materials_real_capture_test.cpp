// Every method on a real capture: the handheld RTI capture of a painted icon in
// tests/data/rti-icon-64 (MIT, see its LICENSE; 1 view, 72 irregular lights), a 16 x 16 crop of
// it. Each method fits it with its quick options and beats the mean colour on it; fitted on 63
// of the lights, its error on the 9 left out is finite (and printed); ptm reaches the linear
// least-squares optimum, and so does hsh at every order, computed here with a QR decomposition
// instead of the methods' SVD.
#include <gtest/gtest.h>

#include <algorithm>
#include <cctype>
#include <cmath>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include <Eigen/Dense>
#include <glm/vec3.hpp>

#include "core/ErrorMetrics.h"
#include "loaders/LoadBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "tests/HshReference.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

constexpr int kCrop = 16, kCropX = 24, kCropY = 24;

/** The crop of the capture with the lights `keep` says, in their order. */
MeasuredBtf cropOfCapture(const std::function<bool(std::size_t)>& keep) {
    static const MeasuredBtf capture =
        loadMeasuredBtf(test::sourceDir() + "/tests/data/rti-icon-64");
    std::vector<std::size_t> lights;
    std::vector<Direction> directions;
    for (std::size_t l = 0; l < capture.lightCount(); ++l)
        if (keep(l)) {
            lights.push_back(l);
            directions.push_back(capture.lights()[l]);
        }
    MeasuredBtf crop(kCrop, kCrop, capture.views(), DirectionSet("rti-lights", directions));
    for (std::size_t i = 0; i < lights.size(); ++i)
        for (int y = 0; y < kCrop; ++y)
            for (int x = 0; x < kCrop; ++x)
                for (int c = 0; c < 3; ++c)
                    crop.setValue(0, i, std::size_t(y) * kCrop + x, c,
                                  capture.value(0, lights[i],
                                                std::size_t(y + kCropY) * capture.width() +
                                                    std::size_t(x + kCropX),
                                                c));
    return crop;
}

bool heldOut(std::size_t light) {
    return light % 8 == 3;
}

}  // namespace

class RealCapture : public ::testing::TestWithParam<std::string> {};

TEST_P(RealCapture, FitsBeatsTheMeanColourAndScoresHeldOutLights) {
    const std::string method = GetParam();
    const MeasuredBtf all = cropOfCapture([](std::size_t) { return true; });
    const MethodInfo& info = findMethod(method);
    osg::ref_ptr<Material> material = info.fit(all, FitOptions::parse(info.quickFitOptions));
    const ErrorSummary error =
        computeError(all, [&](std::size_t t, float* out) { material->evaluateMeasured(t, out); });
    EXPECT_EQ(error.nonFiniteValues, 0u);
    // The mean colour of the crop, the model that knows nothing.
    double mean[3] = {0, 0, 0};
    for (std::size_t l = 0; l < all.lightCount(); ++l)
        for (std::size_t t = 0; t < all.texelCount(); ++t)
            for (int c = 0; c < 3; ++c) mean[c] += all.value(0, l, t, c);
    for (double& m : mean) m /= double(all.lightCount() * all.texelCount());
    const double meanError = computeError(all, [&](std::size_t, float* out) {
                                 for (std::size_t l = 0; l < all.lightCount(); ++l)
                                     for (int c = 0; c < 3; ++c) out[l * 3 + c] = float(mean[c]);
                             }).average;
    if (method != "dummy") {
        EXPECT_LT(error.average, meanError) << method;
    }

    // Fitted without the held-out lights, evaluated at them.
    const MeasuredBtf training = cropOfCapture([](std::size_t l) { return !heldOut(l); });
    const MeasuredBtf test = cropOfCapture(heldOut);
    osg::ref_ptr<Material> fitted = info.fit(training, FitOptions::parse(info.quickFitOptions));
    const glm::vec3 view = test.views().vector(0);
    double squared = 0;
    std::size_t count = 0;
    for (std::size_t l = 0; l < test.lightCount(); ++l)
        for (int y = 0; y < kCrop; ++y)
            for (int x = 0; x < kCrop; ++x) {
                const glm::vec3 value = fitted->evaluate(x, y, view, test.lights().vector(l));
                for (int c = 0; c < 3; ++c) {
                    const double d = value[c] - test.value(0, l, std::size_t(y) * kCrop + x, c);
                    squared += d * d;
                    ++count;
                }
            }
    const double heldOutRmse = std::sqrt(squared / double(count));
    std::cout << method << " on the icon crop: error " << error.average << " (mean colour "
              << meanError << "), held-out lights RMSE " << heldOutRmse << "\n";
    EXPECT_TRUE(std::isfinite(heldOutRmse)) << method;
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, RealCapture, ::testing::ValuesIn(methodNames()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                             std::string name = info.param;
                             for (char& c : name)
                                 if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
                             return name;
                         });

namespace {

/** A linear method (float storage) fitted to the whole crop reaches the least-squares optimum of
 *  its basis, computed here by QR on the design `basis` builds per light; it may only do as well
 *  or better (its clamp at 0 can only lower an error). Returns (fitted, optimum) squared errors. */
std::pair<double, double> expectLeastSquaresOptimum(
    const std::string& method, const std::string& options, int terms,
    const std::function<Eigen::RowVectorXd(const glm::vec3&)>& basis) {
    const MeasuredBtf btf = cropOfCapture([](std::size_t) { return true; });
    osg::ref_ptr<Material> fitted = findMethod(method).fit(btf, FitOptions::parse(options));
    const std::size_t lights = btf.lightCount();
    Eigen::MatrixXd design(lights, terms);
    for (std::size_t l = 0; l < lights; ++l)
        design.row(Eigen::Index(l)) = basis(btf.lights().vector(l));
    const Eigen::ColPivHouseholderQR<Eigen::MatrixXd> qr(design);
    std::vector<float> model(lights * 3);
    double worstExcess = 0, optimumSum = 0, modelSum = 0;
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        fitted->evaluateMeasured(t, model.data());
        for (int c = 0; c < 3; ++c) {
            Eigen::VectorXd values(lights);
            for (std::size_t l = 0; l < lights; ++l)
                values[Eigen::Index(l)] = btf.value(0, l, t, c);
            const double optimum = (design * qr.solve(values) - values).squaredNorm();
            double error = 0;
            for (std::size_t l = 0; l < lights; ++l) {
                const double d = model[l * 3 + c] - values[Eigen::Index(l)];
                error += d * d;
            }
            optimumSum += optimum;
            modelSum += error;
            worstExcess = std::max(worstExcess, error - optimum);
        }
    }
    std::cout << method << " [" << options << "] on the icon crop: squared error " << modelSum
              << ", least-squares optimum " << optimumSum << "\n";
    // Float rounding of 72-term sums of values up to 1: far below 1e-6 per texel and channel.
    EXPECT_LE(worstExcess, 1e-6) << method << " " << options;
    EXPECT_GT(optimumSum, 0.0) << method;  // the model does not fit the photos exactly
    return {modelSum, optimumSum};
}

}  // namespace

TEST(RealCapture, PtmReachesTheLinearLeastSquaresOptimum) {
    // The six polynomial coefficients of Malzbender et al. 2001 per texel and channel.
    expectLeastSquaresOptimum("ptm", "colour=rgb storage=float", 6, [](const glm::vec3& d) {
        Eigen::RowVectorXd row(6);
        row << d.x * d.x, d.y * d.y, d.x * d.y, d.x, d.y, 1.0;
        return row;
    });
}

TEST(RealCapture, HshReachesTheLinearLeastSquaresOptimumAtEveryOrder) {
    // The harmonics of the RTI tools (tests/HshReference.h), 4, 9 and 16 per channel: each order
    // fits at least as well as the one below (nested bases).
    double previous = 1e300;
    for (int order = 2; order <= 4; ++order) {
        const int terms = order * order;
        const double optimum =
            expectLeastSquaresOptimum("hsh", "storage=float order=" + std::to_string(order), terms,
                                      [terms](const glm::vec3& d) {
                                          const auto h = test::hshTrigonometricForm(d);
                                          Eigen::RowVectorXd row(terms);
                                          for (int k = 0; k < terms; ++k)
                                              row(k) = h[std::size_t(k)];
                                          return row;
                                      })
                .second;
        EXPECT_LT(optimum, previous) << "order " << order;
        previous = optimum;
    }
}

}  // namespace OSGBTF_TEST_FILE
