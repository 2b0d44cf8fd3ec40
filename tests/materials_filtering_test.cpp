// Material::evaluateFiltered's bilinear filter (issue 29 section 1): which methods filter, texel
// centres give the texel itself, between them the blend of the four neighbours, with wrap-around.
#include <gtest/gtest.h>

#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/lambert/Lambert.h"

using namespace osgBTF;

namespace {

constexpr int kWidth = 8, kHeight = 4;

MeasuredBtf sample() {
    SampleOptions options;
    options.width = kWidth;
    options.height = kHeight;
    return makeSampleBtf(options);
}

}  // namespace

TEST(MaterialFiltering, MethodsLinearInTheirParametersFilter) {
    for (const char* name : {"lambert", "pca", "ptm", "fmf"})
        EXPECT_TRUE(findMethod(name).filtersLinearly) << name;
    // Exponents, cluster ids: not linear in their parameters.
    for (const char* name : {"laf", "slaf", "rf", "lpca", "lpca-revised"})
        EXPECT_FALSE(findMethod(name).filtersLinearly) << name;
}

TEST(MaterialFiltering, TexelCentresGiveTheTexelAndBetweenThemTheBlendWithWrapAround) {
    osg::ref_ptr<LambertMaterial> m = LambertMaterial::fit(sample(), {});
    ASSERT_TRUE(m->filtersBilinearly());
    const glm::vec3 view(0, 0, 1), light = Direction{45, 20}.toVector();
    const auto at = [&](int x, int y) {
        return m->evaluate((x + kWidth) % kWidth, (y + kHeight) % kHeight, view, light);
    };
    const auto filtered = [&](float x, float y) {
        return m->evaluateFiltered(x / kWidth, y / kHeight, 0.0f, view, light);
    };
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            EXPECT_EQ(filtered(x + 0.5f, y + 0.5f), at(x, y));
            // Texture coordinates beyond [0, 1] repeat.
            EXPECT_EQ(filtered(x + 0.5f + 2 * kWidth, y + 0.5f - kHeight), at(x, y));
        }
    const auto near = [](const glm::vec3& a, const glm::vec3& b) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-6f);
    };
    // A quarter of the way from texel (2, 3) to (3, 4).
    near(filtered(2.75f, 3.75f),
         0.5625f * at(2, 3) + 0.1875f * at(3, 3) + 0.1875f * at(2, 4) + 0.0625f * at(3, 4));
    // The corner of the texture: the last texel of each row and column blends with the first.
    near(filtered(0.0f, 0.0f), 0.25f * (at(-1, -1) + at(0, -1) + at(-1, 0) + at(0, 0)));
    near(filtered(kWidth, 2.5f), 0.5f * (at(-1, 2) + at(0, 2)));
}

TEST(MaterialFiltering, OtherMethodsReadTheNearestTexel) {
    const osg::ref_ptr<Material> m =
        findMethod("lpca").fit(sample(), FitOptions::parse(findMethod("lpca").quickFitOptions));
    ASSERT_FALSE(m->filtersBilinearly());
    const glm::vec3 view(0, 0, 1), light = Direction{45, 20}.toVector();
    EXPECT_EQ(m->evaluateFiltered(2.9f / kWidth, 3.1f / kHeight, 0.0f, view, light),
              m->evaluate(2, 3, view, light));
}
