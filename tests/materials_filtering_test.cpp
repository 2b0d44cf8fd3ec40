// Material::evaluateFiltered's bilinear filter: which methods filter their
// parameters and which blend texel values (Material::TexelFilter); either way texel centres give
// the texel itself, between them the blend of the four neighbours, with wrap-around; mip-mapped
// materials blend two levels, each bilinearly and wrapped inside its rectangle of the atlas.
#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include "fit/MipMapping.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "materials/lambert/Lambert.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

constexpr int kWidth = 8, kHeight = 4;

MeasuredBtf sample() {
    SampleOptions options;
    options.width = kWidth;
    options.height = kHeight;
    return makeSampleBtf(options);
}

/** Every third Bonn direction for both views and lights: what filtering concerns is the texel
 *  layout, and a ninth of the samples keeps the fits of every method quick (under the sanitizers
 *  the full sample's 18 fits took half a minute). */
MeasuredBtf sampleWithFewerDirections() {
    const DirectionSet all = DirectionSet::bonn81();
    std::vector<Direction> third;
    for (std::size_t i = 0; i < all.size(); i += 3) third.push_back(all[i]);
    SampleOptions options;
    options.width = kWidth;
    options.height = kHeight;
    options.views = options.lights = DirectionSet("bonn81/3", third);
    return makeSampleBtf(options);
}

}  // namespace

TEST(MaterialFiltering, MethodsLinearInTheirParametersFilterThemTheOthersBlendValues) {
    for (const char* name : {"lambert", "pca", "ptm", "fmf"})
        EXPECT_TRUE(findMethod(name).filtersParameters) << name;
    // Exponents, cluster ids: not linear in their parameters.
    for (const char* name : {"laf", "slaf", "rf", "lpca", "lpca-revised"})
        EXPECT_FALSE(findMethod(name).filtersParameters) << name;
    // Every method filters one way or the other; a mip-mapped material blends values whatever its
    // method (its levels sit in an atlas: the hardware filter would not wrap inside a level).
    const MeasuredBtf btf = sampleWithFewerDirections();
    for (const std::string& name : methodNamesInOrder()) {
        const MethodInfo& method = findMethod(name);
        const osg::ref_ptr<Material> m = method.fit(btf, FitOptions::parse(method.quickFitOptions));
        // A method that blends its inputs itself does so at every level.
        EXPECT_EQ(m->texelFilter(), method.blendsInputs        ? Material::TexelFilter::Inputs
                                    : method.filtersParameters ? Material::TexelFilter::Parameters
                                                               : Material::TexelFilter::Values)
            << name;
        const osg::ref_ptr<Material> mip =
            fitMipMapped(method, btf, FitOptions::parse(method.quickFitOptions));
        EXPECT_EQ(mip->texelFilter(), method.blendsInputs ? Material::TexelFilter::Inputs
                                                          : Material::TexelFilter::Values)
            << name;
    }
}

TEST(MaterialFiltering, TexelCentresGiveTheTexelAndBetweenThemTheBlendWithWrapAround) {
    osg::ref_ptr<LambertMaterial> m = LambertMaterial::fit(sample(), {});
    ASSERT_TRUE(m->filtersParameters());
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

TEST(MaterialFiltering, MethodsNotLinearInTheirParametersBlendTheFourTexelsValues) {
    // lpca: a cluster id per texel, which no filter may blend; its four texels' values blend.
    const osg::ref_ptr<Material> m =
        findMethod("lpca").fit(sample(), FitOptions::parse(findMethod("lpca").quickFitOptions));
    ASSERT_EQ(m->texelFilter(), Material::TexelFilter::Values);
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
            EXPECT_EQ(filtered(x + 0.5f - 3 * kWidth, y + 0.5f + kHeight), at(x, y));
        }
    const auto near = [](const glm::vec3& a, const glm::vec3& b) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-6f * (1.0f + std::abs(b[c])));
    };
    // Texel (2, 1) towards (3, 2): 0.4 of the way along u, 0.8 along v (texel units).
    near(filtered(2.9f, 2.3f), 0.6f * 0.2f * at(2, 1) + 0.4f * 0.2f * at(3, 1) +
                                   0.6f * 0.8f * at(2, 2) + 0.4f * 0.8f * at(3, 2));
    // Across the wrap edge in both axes: the last column and row blend with the first.
    near(filtered(0.25f, 0.0f),
         0.25f * 0.5f * (at(-1, -1) + at(-1, 0)) + 0.75f * 0.5f * (at(0, -1) + at(0, 0)));
    near(filtered(kWidth, 3.75f),
         0.5f * 0.75f * (at(-1, 3) + at(0, 3)) + 0.5f * 0.25f * (at(-1, 4) + at(0, 4)));
    // Half-way between four texels: none of them (no nearest texel read).
    const glm::vec3 between = filtered(3.0f, 2.0f);
    for (const glm::vec3& t : {at(2, 1), at(3, 1), at(2, 2), at(3, 2)})
        EXPECT_GT(glm::length(between - t), 1e-4f);
}

TEST(MaterialFiltering, MipMappedMaterialsBlendTwoLevelsEachBilinearInsideItsRectangle) {
    // Base 8 x 4: level 1 is 4 x 2 at (8, 0), level 2 is 2 x 1 at (8, 2) (MipLayout).
    const MethodInfo& method = findMethod("lpca");
    const osg::ref_ptr<Material> m =
        fitMipMapped(method, sample(), FitOptions::parse(method.quickFitOptions));
    ASSERT_EQ(m->mipLayout().levelCount(), 4);
    ASSERT_EQ(m->mipLayout().levels()[1].x, 8);
    ASSERT_EQ(m->mipLayout().levels()[2].y, 2);
    const glm::vec3 view(0, 0, 1), light = Direction{30, 200}.toVector();
    const auto at = [&](int x, int y) { return m->evaluate(x, y, view, light); };
    const auto near = [](const glm::vec3& a, const glm::vec3& b) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(a[c], b[c], 1e-6f * (1.0f + std::abs(b[c])));
    };
    // uv (0.3125, 0.875). Level 1: column 0.3125 * 4 - 0.5 = 0.75, row 0.875 * 2 - 0.5 = 1.25:
    // columns 0, 1 (atlas 8, 9), rows 1 and 0 (wrapped inside the level: atlas rows 1, 0, not
    // row 2 above it, which is level 2).
    const float u = 0.3125f, v = 0.875f;
    const glm::vec3 level1 = 0.25f * 0.75f * at(8, 1) + 0.75f * 0.75f * at(9, 1) +
                             0.25f * 0.25f * at(8, 0) + 0.75f * 0.25f * at(9, 0);
    // Level 2: column 0.3125 * 2 - 0.5 = 0.125, row 0.875 - 0.5 = 0.375 of a one-row level.
    const glm::vec3 level2 = 0.875f * at(8, 2) + 0.125f * at(9, 2);
    near(m->evaluateFiltered(u, v, 1.0f, view, light), level1);
    near(m->evaluateFiltered(u, v, 2.0f, view, light), level2);
    // lod 1.75: a quarter of level 1, three quarters of level 2 (GL_LINEAR_MIPMAP_LINEAR).
    near(m->evaluateFiltered(u, v, 1.75f, view, light), 0.25f * level1 + 0.75f * level2);
}

}  // namespace OSGBTF_TEST_FILE
