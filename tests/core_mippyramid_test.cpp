// Mip-mapped BTFs: the atlas layout, worked out by hand from its definition
// (core/MipPyramid.h: level 0 at the origin, levels >= 1 of ceil-halved sizes stacked from the
// bottom in the column right of it), the box-filtered values against averages taken here from
// the measured values, and a mip-mapped material's file and CPU lookup.
#include <cmath>

#include <gtest/gtest.h>

#include "core/Error.h"
#include "core/MipPyramid.h"
#include "fit/MipMapping.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

std::vector<std::tuple<int, int, int, int>> rectangles(const MipLayout& layout) {
    std::vector<std::tuple<int, int, int, int>> out;
    for (const MipLevel& l : layout.levels()) out.emplace_back(l.x, l.y, l.width, l.height);
    return out;
}

}  // namespace

TEST(MipLayout, RefusesAnEmptyOrTooLargeBase) {
    EXPECT_EQ(errorOf([] { MipLayout::forBase(0, 4); }),
              "a mip pyramid needs a positive base size, got 0x4");
    // 32768 = 2^15 has 16 levels, 32769 one more.
    EXPECT_EQ(MipLayout::forBase(32768, 1).levelCount(), 16);
    EXPECT_EQ(errorOf([] { MipLayout::forBase(32769, 1); }),
              "a mip pyramid of 32769x1 texels has more than 16 levels");
}

TEST(MipLayout, PowerOfTwoBase) {
    const MipLayout layout = MipLayout::forBase(64, 64);
    EXPECT_TRUE(layout.mipMapped());
    const std::vector<std::tuple<int, int, int, int>> expected = {
        {0, 0, 64, 64}, {64, 0, 32, 32}, {64, 32, 16, 16}, {64, 48, 8, 8},
        {64, 56, 4, 4}, {64, 60, 2, 2},  {64, 62, 1, 1}};
    EXPECT_EQ(rectangles(layout), expected);
    EXPECT_EQ(layout.atlasWidth(), 96);
    EXPECT_EQ(layout.atlasHeight(), 64);
}

TEST(MipLayout, NonPowerOfTwoBasesRoundUpAndMayGrowTheAtlas) {
    // 400: 200 100 50 25 13 7 4 2 1; the column holds 405 - 3 = 402 rows, more than the base.
    const MipLayout square = MipLayout::forBase(400, 400);
    EXPECT_EQ(square.levelCount(), 10);
    EXPECT_EQ(square.atlasWidth(), 600);
    EXPECT_EQ(square.atlasHeight(), 402);
    EXPECT_EQ(square.levels()[5].y, 200 + 100 + 50 + 25);
    EXPECT_EQ(square.levels()[5].width, 13);
    // 5x1: widths 3, 2, 1, each one row high.
    const std::vector<std::tuple<int, int, int, int>> strip = {
        {0, 0, 5, 1}, {5, 0, 3, 1}, {5, 1, 2, 1}, {5, 2, 1, 1}};
    EXPECT_EQ(rectangles(MipLayout::forBase(5, 1)), strip);
    EXPECT_EQ(MipLayout::forBase(5, 1).atlasWidth(), 8);
    EXPECT_EQ(MipLayout::forBase(5, 1).atlasHeight(), 3);
    EXPECT_FALSE(MipLayout::forBase(1, 1).mipMapped());
}

TEST(MipLayout, TexelsAndFootprints) {
    const MipLayout layout = MipLayout::forBase(8, 8);  // levels (8,0,4,4) (8,4,2,2) (8,6,1,1)
    int x, y;
    layout.texelAt(0.30f, 0.80f, 0, x, y);
    EXPECT_EQ(std::make_pair(x, y), std::make_pair(2, 6));
    layout.texelAt(0.30f, 0.80f, 1, x, y);  // 0.3 * 4 = 1.2, 0.8 * 4 = 3.2
    EXPECT_EQ(std::make_pair(x, y), std::make_pair(9, 3));
    layout.texelAt(-0.70f, 2.80f, 2, x, y);  // wraps to (0.3, 0.8): 0.6, 1.6 of 2
    EXPECT_EQ(std::make_pair(x, y), std::make_pair(8, 5));
    int x0, y0, x1, y1;
    layout.footprint(9, 3, x0, y0, x1, y1);
    EXPECT_EQ(std::make_tuple(x0, y0, x1, y1), std::make_tuple(2, 6, 4, 8));
    layout.footprint(8, 6, x0, y0, x1, y1);  // 1x1 level: everything
    EXPECT_EQ(std::make_tuple(x0, y0, x1, y1), std::make_tuple(0, 0, 8, 8));
    layout.footprint(11, 7, x0, y0, x1, y1);  // unused corner: base texel (3, 7)
    EXPECT_EQ(std::make_tuple(x0, y0, x1, y1), std::make_tuple(3, 7, 4, 8));
}

TEST(MipAtlasSource, ValuesAreTheMeanOfTheMeasuredTexelsTheyCover) {
    const MeasuredBtf btf = smallSampleBtf(8);
    const MipAtlasSource atlas(btf);
    ASSERT_EQ(atlas.width(), 12);
    ASSERT_EQ(atlas.height(), 8);
    const std::size_t values = atlas.imageCount() * 3;
    // Atlas texel -> the base texels it averages, written out for three of them.
    const std::vector<std::pair<int, std::vector<std::pair<int, int>>>> cases = {
        {1 * 12 + 9, {{2, 2}, {3, 2}, {2, 3}, {3, 3}}},  // level 1 (1, 1)
        {7 * 12 + 11, {{3, 7}}},                         // the unused corner
        {5 * 12 + 9, {}}};                               // level 2 (1, 1): texels 4..7 x 4..7
    for (const auto& [atlasTexel, listed] : cases) {
        std::vector<std::pair<int, int>> base = listed;
        if (base.empty())
            for (int y = 4; y < 8; ++y)
                for (int x = 4; x < 8; ++x) base.emplace_back(x, y);
        std::vector<float> got(values);
        const std::size_t index = std::size_t(atlasTexel);
        atlas.readAbrdfs(&index, 1, got.data());
        double worst = 0;
        for (std::size_t v = 0; v < btf.viewCount(); ++v)
            for (std::size_t l = 0; l < btf.lightCount(); ++l)
                for (int c = 0; c < 3; ++c) {
                    double mean = 0;
                    for (const auto& [x, y] : base)
                        mean += btf.value(v, l, std::size_t(y) * 8 + x, c);
                    mean /= double(base.size());
                    const double read = got[(v * btf.lightCount() + l) * 3 + c];
                    worst = std::max(worst, std::abs(read - mean));
                }
        EXPECT_LT(worst, 1e-6) << "atlas texel " << atlasTexel;
    }
    // Images and ABRDFs are two readings of one array.
    std::vector<float> images(atlas.imageCount() * atlas.texelCount() * 3);
    atlas.readImages(0, atlas.imageCount(), images.data());
    std::vector<float> abrdfs(atlas.texelCount() * values);
    atlas.readAbrdfRange(0, atlas.texelCount(), abrdfs.data());
    double worst = 0;
    for (std::size_t t = 0; t < atlas.texelCount(); ++t)
        for (std::size_t i = 0; i < atlas.imageCount(); ++i)
            for (int c = 0; c < 3; ++c)
                worst =
                    std::max(worst, double(std::abs(images[(i * atlas.texelCount() + t) * 3 + c] -
                                                    abrdfs[t * values + i * 3 + c])));
    EXPECT_LT(worst, 1e-6);
}

TEST(MipMappedMaterial, SavesItsLevelsAndLooksUpLikeTheShader) {
    const MeasuredBtf btf = smallSampleBtf(8);
    const osg::ref_ptr<Material> material = fitMipMapped(findMethod("lambert"), btf, FitOptions());
    ASSERT_EQ(material->width(), 12);
    ASSERT_EQ(material->mipLayout().levelCount(), 4);
    TempDir dir;
    saveMaterial(*material, dir.file("mip.btfmat"));
    const osg::ref_ptr<Material> loaded = loadMaterial(dir.file("mip.btfmat"));
    ASSERT_EQ(rectangles(loaded->mipLayout()), rectangles(material->mipLayout()));

    const glm::vec3 view = btf.views().vector(3), light = btf.lights().vector(5);
    const auto at = [&](int x, int y) { return loaded->evaluate(x, y, view, light); };
    const auto near = [](const glm::vec3& got, const glm::vec3& expected) {
        for (int c = 0; c < 3; ++c) EXPECT_NEAR(got[c], expected[c], 1e-6f) << c;
    };
    // uv (0.375, 0.875): the centre of level 1's texel (1, 3), atlas (9, 3); in level 2 (2 x 2
    // at (8, 4)) a quarter of a texel right of column 0's centre, a quarter above row 1's, so
    // row 1 blends with row 0 (wrapped inside the level, not the atlas row above it).
    const float u = 0.375f, v = 0.875f;
    const glm::vec3 level1 = at(9, 3);
    const glm::vec3 level2 =
        0.5625f * at(8, 5) + 0.1875f * at(9, 5) + 0.1875f * at(8, 4) + 0.0625f * at(9, 4);
    EXPECT_EQ(loaded->evaluateFiltered(u, v, 1.0f, view, light), level1);
    near(loaded->evaluateFiltered(u, v, 2.0f, view, light), level2);
    near(loaded->evaluateFiltered(u, v, 1.25f, view, light), 0.75f * level1 + 0.25f * level2);
    // Magnification and NaN: the base, half-way between columns 2, 3 and rows 6, 7.
    const glm::vec3 base = 0.25f * (at(2, 6) + at(3, 6) + at(2, 7) + at(3, 7));
    near(loaded->evaluateFiltered(u, v, -2.0f, view, light), base);
    near(loaded->evaluateFiltered(u, v, NAN, view, light), base);
    // Past the last level: the last, one texel (8, 6), whatever the weights.
    near(loaded->evaluateFiltered(u, v, 9.0f, view, light), at(8, 6));
}

TEST(MipMappedMaterial, BadLevelsAreRefusedWithTheirReason) {
    const osg::ref_ptr<Material> material =
        fitMipMapped(findMethod("lambert"), smallSampleBtf(8), FitOptions());
    FittedMaterial file = material->toFittedMaterial();
    file.source = "m.btfmat";
    for (const std::string bad : {"8", "8x", "0x8", "8x8x", "16x8", "axb"}) {
        file.parameters["mip.base"] = bad;
        EXPECT_EQ(
            errorOf([&] { materialFromFile(file); }),
            "m.btfmat: mip.base '" + bad + "' is not a base size WxH within the material's texels")
            << bad;
    }
    file.parameters["mip.base"] = "6x8";  // a 6x8 base makes a 9x8 atlas, not 12x8
    EXPECT_EQ(errorOf([&] { materialFromFile(file); }),
              "m.btfmat: a mip pyramid of a 6x8 base needs 9x8 texels, the material has 12x8");
    const osg::ref_ptr<Material> plain = findMethod("lambert").fit(smallSampleBtf(8), {});
    EXPECT_EQ(errorOf([&] { plain->setMipLayout(MipLayout::forBase(8, 8)); }),
              "a mip pyramid of a 8x8 base needs 12x8 texels, the material has 8x8");
    CoordinateMap map;
    map.sampleWidth = map.sampleHeight = 8;
    EXPECT_EQ(errorOf([&] { remapMaterial(*material, map); }),
              "coordinate map: material 'lambert' is mip-mapped; only a material without mip "
              "levels can be remapped through a map (a render through the map filters its "
              "levels)");
}

}  // namespace OSGBTF_TEST_FILE
