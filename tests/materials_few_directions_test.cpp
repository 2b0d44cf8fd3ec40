// Issue 49: every method on the direction sets real captures have: one view (an RTI capture, a
// Bonn folder of one view), two views, a few views on one azimuth (one line of the disc map), a
// few irregular views, and irregular lights. Each fits with its quick options, evaluates finite
// everywhere, and is no worse than the constant (mean-colour) model on its own data; a set of one
// direction interpolates to that direction's value, a set of two along the segment between them
// (docs/formats.md, "Interpolating few directions").
#include <gtest/gtest.h>

#include <cctype>
#include <cmath>
#include <iostream>
#include <string>
#include <tuple>
#include <vector>

#include <glm/geometric.hpp>

#include "core/DirectionInterpolation.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "tests/FewDirectionCases.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

MeasuredBtf sampleWith(const test::DirectionCase& directions) {
    SampleOptions options;
    options.width = options.height = 4;
    options.views = directions.views;
    options.lights = directions.lights;
    return makeSampleBtf(options);
}

/** The error of the model that is the BTF's mean colour everywhere: what a fit must beat. */
double constantModelError(const MeasuredBtf& btf) {
    double sum[3] = {0, 0, 0};
    const std::size_t values = btf.viewCount() * btf.lightCount();
    std::vector<float> abrdf;
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        for (std::size_t v = 0; v < btf.viewCount(); ++v)
            for (std::size_t l = 0; l < btf.lightCount(); ++l)
                for (int c = 0; c < 3; ++c) sum[c] += btf.value(v, l, t, c);
    const double count = double(values * btf.texelCount());
    const float mean[3] = {float(sum[0] / count), float(sum[1] / count), float(sum[2] / count)};
    return computeError(btf,
                        [&](std::size_t, float* out) {
                            for (std::size_t k = 0; k < values; ++k)
                                for (int c = 0; c < 3; ++c) out[k * 3 + c] = mean[c];
                        })
        .average;
}

}  // namespace

TEST(FewDirections, OneDirectionIsConstantAndTwoBlendAlongTheirSegment) {
    const DirectionSet one("front", {{20, 40}});
    const DirectionInterpolator single(one);
    for (const glm::vec3& query :
         {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(1, 0.3f, 0.2f)), glm::vec3(-1, 0, 0)}) {
        const InterpolationWeights w = single.weights(query);
        EXPECT_EQ(w.index[0], 0);
        EXPECT_EQ(w.weight[0], 1.0f);
        EXPECT_EQ(w.weight[1] + w.weight[2], 0.0f);
    }
    // Two directions on the x axis of the disc map (azimuth 0 and 180): a query between them in
    // the map gets the fractions of the distances, one beyond an end gets that end alone.
    const DirectionSet two("two", {{40, 0}, {40, 180}});
    const DirectionInterpolator pair(two);
    const glm::vec2 a = directionToDisc(two.vector(0)), b = directionToDisc(two.vector(1));
    const glm::vec2 quarter = a + 0.25f * (b - a);
    const InterpolationWeights w = pair.weights(discToDirection(quarter));
    const float toA = w.index[0] == 0 ? w.weight[0] : w.weight[1];
    EXPECT_NEAR(toA, 0.75f, 1e-5f);
    EXPECT_NEAR(w.weight[0] + w.weight[1] + w.weight[2], 1.0f, 1e-6f);
    const InterpolationWeights beyond = pair.weights(discToDirection(a * 1.2f));
    EXPECT_EQ(beyond.weight[beyond.index[0] == 0 ? 0 : 1], 1.0f);
    // The GPU table gives the same weights (the shader reads it the same way).
    const DirectionTable table = pair.table(8, 64);
    const InterpolationWeights fromTable =
        DirectionInterpolator::lookupTable(table, discToDirection(quarter));
    EXPECT_EQ(fromTable.weight, w.weight);
    EXPECT_EQ(fromTable.index, w.index);
    // Still refused: nothing to interpolate, and the same direction twice.
    EXPECT_EQ(test::errorOf([] { DirectionInterpolator(DirectionSet("none", {})); }),
              "direction set 'none': no directions to interpolate");
    EXPECT_EQ(test::errorOf([] {
                  DirectionInterpolator(DirectionSet("twice", {{30, 0}, {30, 0}}));
              }),
              "direction set 'twice': duplicate direction at index 1");
}

class FewDirections : public ::testing::TestWithParam<test::MethodAndDirections> {};

TEST_P(FewDirections, EveryMethodFitsEvaluatesFiniteAndBeatsTheMeanColour) {
    const std::string method = std::get<0>(GetParam());
    const test::DirectionCase directions =
        test::directionCases()[std::size_t(std::get<1>(GetParam()))];
    const MeasuredBtf btf = sampleWith(directions);
    const MethodInfo& info = findMethod(method);
    osg::ref_ptr<Material> material = info.fit(btf, FitOptions::parse(info.quickFitOptions));
    ASSERT_TRUE(material);
    EXPECT_EQ(material->views().size(), btf.viewCount());
    const ErrorSummary error =
        computeError(btf, [&](std::size_t t, float* out) { material->evaluateMeasured(t, out); });
    EXPECT_EQ(error.nonFiniteValues, 0u);
    const double constant = constantModelError(btf);
    std::cout << method << " on " << directions.name << ": error " << error.average
              << ", mean colour " << constant << "\n";
    // The dummy test method models nothing; every real one models more than a constant.
    if (method != "dummy") {
        EXPECT_LT(error.average, constant) << method;
    }
    // Away from the measured directions too: finite.
    for (const glm::vec3& view : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(0.5f, -0.4f, 0.7f))})
        for (const glm::vec3& light : {glm::normalize(glm::vec3(0.2f, 0.1f, 1)),
                                       glm::normalize(glm::vec3(-0.7f, 0.3f, 0.4f))}) {
            const glm::vec3 value = material->evaluate(1, 2, view, light);
            EXPECT_TRUE(std::isfinite(value.x) && std::isfinite(value.y) && std::isfinite(value.z))
                << method << " at view (" << view.x << ", " << view.y << ", " << view.z << ")";
        }
}

TEST(FewDirections, OneMeasuredViewIsTheValueForEveryViewOfTheInterpolatingMethods) {
    // The methods whose view dependence is the measured views' data blended by
    // DirectionInterpolator: with one view, every view gets that view's data, weight exactly 1.
    for (const test::DirectionCase& directions :
         {test::directionCases()[0], test::directionCases()[4]})
        for (const std::string method : {"pca", "lpca", "fmf", "ptm"}) {
            const MethodInfo& info = findMethod(method);
            const std::string options =
                info.quickFitOptions + (method == "ptm" ? " views=all" : "");
            osg::ref_ptr<Material> material =
                info.fit(sampleWith(directions), FitOptions::parse(options));
            const glm::vec3 measured = directions.views.vector(0);
            for (const glm::vec3& view : {glm::normalize(glm::vec3(0.5f, -0.4f, 0.7f)),
                                          glm::normalize(glm::vec3(-0.1f, 0.9f, 0.2f))})
                for (std::size_t l = 0; l < directions.lights.size(); l += 7) {
                    const glm::vec3 light = directions.lights.vector(l);
                    EXPECT_EQ(material->evaluate(2, 1, view, light),
                              material->evaluate(2, 1, measured, light))
                        << method << " on " << directions.name << ", light " << l;
                }
        }
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, FewDirections,
                         ::testing::Combine(::testing::ValuesIn(methodNames()),
                                            ::testing::Range(0,
                                                             int(test::directionCases().size()))),
                         test::methodAndDirectionsName);

}  // namespace OSGBTF_TEST_FILE
