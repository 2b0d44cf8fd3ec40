// The test-only method "dummy" (tests/DummyMethod.{h,cpp}: value(x) * l_z, defined and registered
// in the test binary alone) rendered every way a built-in method is: mip-mapped and minified
// between two levels, through a coordinate map (magnified, across the wrap) and under folded
// environment lighting (its EnvironmentHooks and environment shader, also end to end under an
// EnvironmentLitGroup). Each render equals the dummy's CPU reference (evaluateFiltered,
// evaluateThroughMap, evaluateFoldedFiltered) to float rounding: the proof that MethodInfo's
// hooks are complete, since no library code names the dummy. The loops over every registered
// method (MipMapGpu, CoordinateMapGpu, GlErrorsEveryMethod) meet it too, with their bounds.
//
// Bounds: the dummy's value is a float texel times l_z (times one folded RGB value), blended
// with at most 8 float weights; GPU and CPU differ by the rounding of those few operations and of
// the weights (the GPU derives the level of detail from screen-space derivatives): a few float
// ulps of values below 1, 1e-6 here (MipMapGpu's bound for every method is 1e-3).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>

#include <gtest/gtest.h>
#include <osg/Geode>
#include <osg/Uniform>
#include <osgUtil/UpdateVisitor>

#include "environment/EnvironmentLitGroup.h"
#include "fit/MipMapping.h"
#include "harness/MaterialImage.h"
#include "harness/sample/BlockMap.h"
#include "harness/sample/SampleBtf.h"
#include "materials/BilinearTaps.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/EnvironmentLighting.h"
#include "materials/EnvironmentState.h"
#include "materials/MethodRegistry.h"
#include "materials/ShaderInterface.h"
#include "scene/EnvironmentLight.h"
#include "scene/MaterialNode.h"
#include "tests/DummyMethod.h"
#include "tests/SmallSample.h"
#include "tests/gl/GlTestEnv.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;
using osgBTFTest::DummyMaterial;

namespace {

constexpr double kFloatRounding = 1e-6;

osg::ref_ptr<DummyMaterial> fitDummy(const BtfSource& btf) {
    osg::ref_ptr<Material> m = findMethod("dummy").fit(btf, {});
    return dynamic_cast<DummyMaterial*>(m.get());
}

/** The largest |pixel - expected(u, v)| over a width x height render of the patch at texture
 *  scale `scale` (pixel centres at (i + 0.5) / width times the scale), and the largest value. */
template <typename Expected>
double worstDifference(const osg::Image& image, int width, int height, float scale,
                       const Expected& expected, double* largest) {
    double worst = 0;
    *largest = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            const float u = scale * (float(x) + 0.5f) / float(width);
            const float v = scale * (float(y) + 0.5f) / float(height);
            const glm::vec3 want = expected(u, v);
            for (int c = 0; c < 3; ++c) {
                worst = std::max(worst, double(std::abs(pixel(image, x, y, c) - want[c])));
                *largest = std::max(*largest, double(std::abs(want[c])));
            }
        }
    return worst;
}

/** The environment program of `material` on the patch (two triangles, every vertex the same
 *  folded data), texture scale `scale`, size x size pixels, the view fixed to `view`. */
osg::ref_ptr<osg::Image> renderFolded(const Material& material,
                                      const std::vector<std::vector<float>>& folded,
                                      const glm::vec3& view, float exposure, float scale,
                                      int size) {
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(trianglePatch());  // the environment program draws triangles
    geode->setStateSet(environmentStateSet(material, folded, exposure));
    geode->getStateSet()->addUniform(
        new osg::Uniform(shader::kFixedView, osg::Vec4(view.x, view.y, view.z, 1.0f)));
    geode->getStateSet()->addUniform(new osg::Uniform(shader::kTextureScale, scale));
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->setStateSet(material.sharedStateSet());
    root->addChild(geode.get());
    return sharedRenderer().render(root.get(), orthoUnitSquare(size, size));
}

/** A sky of 0.2 with a bright patch low in one direction, coloured. */
EnvironmentMap patchedSky() {
    EnvironmentMap sky;
    sky.width = 16;
    sky.height = 8;
    sky.rgb.assign(16 * 8 * 3, 0.2f);
    for (int c = 0; c < 4; ++c)
        for (int ch = 0; ch < 3; ++ch) sky.rgb[(6 * 16 + c) * 3 + ch] = 5.0f * float(ch + 1);
    return sky;
}

}  // namespace

TEST(MethodPluginGpu, MipMappedMinifiedBetweenTwoLevelsEqualsTheCpuLookup) {
    // fitMipMapped fits the dummy on the atlas of every level's averaged data through its
    // registered fit alone. 32 texels, shown 6 times over 32 pixels: 6 texels per pixel, lod
    // log2(6) = 2.58 between levels 2 and 3, every pixel centre between texel centres of both
    // (mip_map_test.cpp's MinifiedBetweenLevels...), so a pixel blends eight texels.
    const MeasuredBtf sample = smallSampleBtf(32);
    const osg::ref_ptr<Material> material = fitMipMapped(findMethod("dummy"), sample, {});
    ASSERT_EQ(material->methodName(), "dummy");
    ASSERT_TRUE(material->mipLayout().mipMapped());
    ASSERT_GE(material->mipLayout().levelCount(), 4);
    RectifiedPatchRender render;
    render.view = Direction{60, 45}.toVector();
    render.light = Direction{30, 120}.toVector();
    render.textureScale = 6.0f;
    render.width = render.height = 32;
    const float lod = std::log2(render.textureScale * 32.0f / float(render.width));
    const osg::ref_ptr<osg::Image> gpu = renderRectifiedPatch(*material, render);
    render.mipLevels = 1;  // the base level alone: what the lookup would show without levels
    const osg::ref_ptr<osg::Image> base = renderRectifiedPatch(*material, render);
    double largest = 0;
    const double worst = worstDifference(
        *gpu, render.width, render.height, render.textureScale,
        [&](float u, float v) {
            return material->evaluateFiltered(u, v, lod, render.view, render.light);
        },
        &largest);
    const double fromBase = maxDifference(*gpu, *base);
    std::cout << "dummy mip-mapped, lod " << lod << ": GPU vs CPU " << worst << " of largest "
              << largest << " (the base level alone differs by " << fromBase << ")\n";
    EXPECT_GT(largest, 0.01) << "nothing rendered";
    EXPECT_LE(worst, kFloatRounding);
    // The levels are used: the base level's render is another image.
    EXPECT_GT(fromBase, 100 * kFloatRounding);
}

TEST(MethodPluginGpu, ThroughACoordinateMapEqualsTheCpuAndTheMaterialisedMaterial) {
    // remapFittedMaterial knows the dummy's "value" texture only as a per-texel texture (the
    // dummy declares no shared textures): the materialised material holds texel map(x, y) of it
    // at (x, y), exactly. Magnified x4 across the map's wrap, the render through the map (the
    // dummy's shader compiled with the map's define) equals evaluateThroughMap and the render of
    // the materialised material.
    SampleOptions options;
    options.width = 8;
    options.height = 6;  // not square: catches swapped axes
    const osg::ref_ptr<DummyMaterial> material = fitDummy(makeSampleBtf(options));
    ASSERT_NE(material, nullptr);
    const CoordinateMap map = makeBlockCoordinateMap(12, 10, 8, 6, 1, 11);
    const osg::ref_ptr<Material> remapped = remapMaterial(*material, map);
    const auto* dummy = dynamic_cast<const DummyMaterial*>(remapped.get());
    ASSERT_NE(dummy, nullptr);
    ASSERT_EQ(dummy->width(), 12);
    ASSERT_EQ(dummy->height(), 10);
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x)
            ASSERT_EQ(dummy->texel(x, y), material->texel(map.sampleX(x, y), map.sampleY(x, y)))
                << x << ", " << y;
    const glm::vec3 view = Direction{31.7f, 77}.toVector(), light = Direction{52, 200}.toVector();
    const ThroughMapCheck r = checkThroughMap(*material, *remapped, map, view, light);
    std::cout << "dummy through a 12x10 map, magnified x4 across the wrap: GPU vs CPU " << r.gpuCpu
              << ", vs the materialised material's render " << r.materialisedGpu
              << " (the entry under a pixel alone differs by " << r.fromNearest << ")\n";
    EXPECT_LE(r.gpuCpu, kFloatRounding);
    EXPECT_LE(r.materialisedGpu, kFloatRounding);
    EXPECT_EQ(r.materialisedCpu, 0.0);  // both blend the same values in the same order
    EXPECT_GT(r.fromNearest, 100 * kFloatRounding) << "the reference must blend";
}

TEST(MethodPluginGpu, MaterialNodeThroughACoordinateMapEqualsTheMaterialisedMaterial) {
    // The scene path: MaterialNode::setCoordinateMap with the dummy (its shared StateSet, the
    // node's map StateSet and headlight), one pixel per map entry, against the node drawing the
    // materialised material.
    SampleOptions options;
    options.width = 8;
    options.height = 6;
    const osg::ref_ptr<DummyMaterial> material = fitDummy(makeSampleBtf(options));
    auto map = std::make_shared<const CoordinateMap>(makeBlockCoordinateMap(24, 20, 8, 6, 1, 5));
    const osg::ref_ptr<Material> remapped = remapMaterial(*material, *map);
    const auto render = [&](Material* m, std::shared_ptr<const CoordinateMap> through) {
        osg::ref_ptr<MaterialNode> node = new MaterialNode(m);
        EXPECT_TRUE(node->setCoordinateMap(through)) << node->getCoordinateMapError();
        node->addChild(createFullScreenQuad().get());
        return sharedRenderer().render(node.get(), orthoUnitSquare(24, 20));
    };
    const osg::ref_ptr<osg::Image> mapped = render(material.get(), map);
    const osg::ref_ptr<osg::Image> materialised = render(remapped.get(), nullptr);
    const osg::ref_ptr<osg::Image> plain = render(material.get(), nullptr);
    const double worst = maxDifference(*mapped, *materialised);
    std::cout << "dummy MaterialNode through a 24x20 map: vs the materialised material " << worst
              << " (vs the plain material " << maxDifference(*mapped, *plain) << ")\n";
    EXPECT_LE(worst, kFloatRounding);
    EXPECT_GT(maxDifference(*mapped, *plain), 100 * kFloatRounding) << "the map was not used";
}

TEST(MethodPluginGpu, FoldedEnvironmentLightingEqualsTheCpu) {
    // The dummy's EnvironmentHooks and environment shader (environment/dummy.frag, added by its
    // registration): the folded program on the patch, magnified x4 and across the wrap (texture
    // scale 2 on a 4 x 4 material, 32 x 32 pixels), against evaluateFoldedFiltered; and the
    // patch image of `btf eval --env` against the CPU's sum_i g_i BTF(x, v, l_i), which holds
    // only if the fold is the point-light rendering's.
    SampleOptions options;
    options.width = options.height = 4;
    const osg::ref_ptr<DummyMaterial> material = fitDummy(makeSampleBtf(options));
    ASSERT_TRUE(hasFoldedEnvironment("dummy"));
    ASSERT_TRUE(foldsEnvironment(*material));
    const std::vector<glm::vec3> g = projectPatchEnvironment(*material, patchedSky());
    const std::vector<std::vector<float>> folded(4, foldEnvironment(*material, g));
    ASSERT_EQ(folded[0].size(), foldedStride(*material));
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.8f));
    const float exposure = 0.5f, scale = 2.0f;
    const int size = 32;
    // Magnified: 8 pixels per texel at scale 1, 4 here (lod -2, the base texels).
    const float lod = std::log2(4.0f * scale / float(size));

    const osg::ref_ptr<osg::Image> image =
        renderFolded(*material, folded, view, exposure, scale, size);
    double largest = 0, fromNearest = 0;
    const double worst = worstDifference(
        *image, size, size, scale,
        [&](float u, float v) {
            const glm::vec3 value =
                exposure * evaluateFoldedFiltered(*material, folded[0], u, v, lod, view);
            const glm::vec3 nearest =
                exposure *
                evaluateFolded(*material, folded[0], int(u * 4) % 4, int(v * 4) % 4, view);
            for (int c = 0; c < 3; ++c)
                fromNearest = std::max(fromNearest, double(std::abs(nearest[c] - value[c])));
            return value;
        },
        &largest);
    const FloatImage cpu = evaluateEnvironmentImage(*material, g, view, exposure);
    const FloatImage gpu = renderEnvironmentImage(sharedRenderer(), *material, g, view, exposure);
    const double patch = maxAbsDifference(gpu, cpu);
    std::cout << "dummy folded environment, magnified x4 across the wrap: GPU vs CPU " << worst
              << " of largest " << largest << " (nearest texel off by " << fromNearest
              << "); patch image vs sum_i g_i BTF " << patch << "\n";
    EXPECT_GT(largest, 0.01) << "nothing rendered";
    EXPECT_LE(worst, kFloatRounding);
    EXPECT_GT(fromNearest, 100 * kFloatRounding) << "the reference must blend";
    // The fold sums g_i l_i,z over the lights in another order than evaluateProjected.
    EXPECT_LE(patch, kFloatRounding * (1.0 + largest));
}

TEST(MethodPluginGpu, FoldedEnvironmentLightingOfAMipMappedFitEqualsTheCpuBetweenTwoLevels) {
    // The environment program blends two levels' lookups when minified, as point lights do
    // (MipMappedMinifiedBetweenTwoLevels... above): 6 texels per pixel, lod log2(6), against
    // evaluateFoldedFiltered at that lod.
    const MeasuredBtf sample = smallSampleBtf(32);
    const osg::ref_ptr<Material> material = fitMipMapped(findMethod("dummy"), sample, {});
    ASSERT_TRUE(material->mipLayout().mipMapped());
    const std::vector<glm::vec3> g = projectPatchEnvironment(*material, patchedSky());
    const std::vector<std::vector<float>> folded(4, foldEnvironment(*material, g));
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.8f));
    const float scale = 6.0f;
    const int size = 32;
    const float lod = std::log2(32.0f * scale / float(size));
    const osg::ref_ptr<osg::Image> image = renderFolded(*material, folded, view, 1.0f, scale, size);
    double largest = 0, fromBase = 0;
    const double worst = worstDifference(
        *image, size, size, scale,
        [&](float u, float v) {
            const glm::vec3 value = evaluateFoldedFiltered(*material, folded[0], u, v, lod, view);
            const glm::vec3 base = evaluateFoldedFiltered(*material, folded[0], u, v, 0.0f, view);
            for (int c = 0; c < 3; ++c)
                fromBase = std::max(fromBase, double(std::abs(base[c] - value[c])));
            return value;
        },
        &largest);
    std::cout << "dummy folded environment, mip-mapped, lod " << lod << ": GPU vs CPU " << worst
              << " of largest " << largest << " (the base level alone differs by " << fromBase
              << ")\n";
    EXPECT_GT(largest, 0.01) << "nothing rendered";
    EXPECT_LE(worst, kFloatRounding);
    EXPECT_GT(fromBase, 100 * kFloatRounding) << "the levels must be used";
}

TEST(MethodPluginGpu, EnvironmentLitGroupLightsTheDummyByItsFold) {
    // End to end, no call into the library: a MaterialNode with the dummy under an
    // EnvironmentLitGroup with a white environment, nothing occluding. The group projects the
    // environment per vertex (ray-cast visibility), folds it with the dummy's hooks and installs
    // its program; seen from above, every pixel equals the filtered sum_i g_i BTF(x, v, l_i) of
    // the unoccluded patch's projection (evaluateProjected), within 1e-5 of the largest value
    // (the group's projection, computed by its own ray-cast path, sums in another order). Not the
    // brute-force integral (environmentReference, printed): the dummy's l_z at a direction between
    // measured lights is not the interpolation of their l_i,z, so the projection onto the measured
    // lights approximates it, as for the methods that do not interpolate lights (scene/README.md).
    SampleOptions options;
    options.width = options.height = 4;
    const osg::ref_ptr<DummyMaterial> material = fitDummy(makeSampleBtf(options));
    EnvironmentMap white;
    white.width = 64;
    white.height = 32;
    white.rgb.assign(64 * 32 * 3, 1.0f);
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    light->setMap(white);
    osg::ref_ptr<EnvironmentLitGroup> group = new EnvironmentLitGroup;
    group->setLight(light.get());
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(trianglePatch());  // the environment program draws triangles
    node->addChild(geode.get());
    group->addChild(node.get());
    osgUtil::UpdateVisitor update;
    group->accept(update);
    group->finish();
    ASSERT_EQ(group->getError(), "");
    ASSERT_NE(geode->getDrawable(0)->getStateSet(), nullptr) << "no environment state installed";
    const int size = 32;
    const osg::ref_ptr<osg::Image> image =
        sharedRenderer().render(group.get(), orthoUnitSquare(size, size));
    const glm::vec3 view(0, 0, 1);
    const std::vector<glm::vec3> g = projectPatchEnvironment(*material, white);
    const std::vector<EnvironmentSample> samples = visibleEnvironment(white, SurfaceFrame{});
    std::vector<glm::vec3> projected(16), integrals(16);
    for (int ty = 0; ty < 4; ++ty)
        for (int tx = 0; tx < 4; ++tx) {
            projected[std::size_t(ty * 4 + tx)] = evaluateProjected(*material, tx, ty, view, g);
            integrals[std::size_t(ty * 4 + tx)] =
                environmentReference(*material, tx, ty, view, samples);
        }
    // A pixel shows the blend of the four texels around it (GL_LINEAR's weights, wrapping).
    const auto filtered = [](const std::vector<glm::vec3>& texels, float u, float v) {
        const BilinearTaps taps(u, v, 4, 4);
        glm::vec3 value(0.0f);
        for (int k = 0; k < 4; ++k)
            value += taps.weight[k] * texels[std::size_t(taps.y[k] * 4 + taps.x[k])];
        return value;
    };
    double largest = 0, largestIntegral = 0;
    const double worst = worstDifference(
        *image, size, size, 1.0f, [&](float u, float v) { return filtered(projected, u, v); },
        &largest);
    const double fromIntegral = worstDifference(
        *image, size, size, 1.0f, [&](float u, float v) { return filtered(integrals, u, v); },
        &largestIntegral);
    std::cout << "dummy under an EnvironmentLitGroup (white): GPU vs the CPU projection " << worst
              << " of largest " << largest << " (vs the brute-force integral " << fromIntegral
              << ")\n";
    EXPECT_GT(largest, 0.01) << "nothing rendered";
    EXPECT_LE(worst, 1e-5 * largest);
}

}  // namespace OSGBTF_TEST_FILE
