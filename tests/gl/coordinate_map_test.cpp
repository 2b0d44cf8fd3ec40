// Rendering through a coordinate map (materials/CoordinateMapRendering.h), every registered
// method: the GPU render through a random map equals the GPU render of the materialised material
// (its per-texel textures remapped on the CPU) and shows, at every pixel, the texel the map
// names in the plain render; the CPU evaluation at the mapped texels equals the materialised
// material's exactly. Magnified and across the map's wrap edge, a fragment shows the bilinear
// blend of the four map entries around it (evaluateThroughMap); minified over a mip-mapped
// material, the trilinear blend of two levels of the map's chain.
#include <algorithm>
#include <cmath>
#include <iostream>
#include <memory>

#include <gtest/gtest.h>
#include <osg/Uniform>

#include "fit/MipMapping.h"
#include "harness/MaterialImage.h"
#include "harness/sample/BlockMap.h"
#include "harness/sample/SampleBtf.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/MethodRegistry.h"
#include "materials/ShaderInterface.h"
#include "materials/fmf/Fmf.h"
#include "materials/pca/Pca.h"
#include "materials/ptm/Ptm.h"
#include "scene/MaterialNode.h"
#include "tests/RandomFactors.h"
#include "tests/gl/GlTestEnv.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

/** Every third Bonn direction: quick fits, interpolation still all over the hemisphere. */
DirectionSet fewDirections() {
    const DirectionSet bonn = DirectionSet::bonn81();
    std::vector<Direction> directions;
    for (std::size_t i = 0; i < bonn.size(); i += 3) directions.push_back(bonn[i]);
    return DirectionSet("bonn81/3", directions);
}

// The two renders run the same per-texel arithmetic on the same stored values in two programs
// (with and without the map's define); only the compiler's choices (contraction into FMA,
// reassociation) may differ between them: a few float ulps of values below 10.
constexpr double kSameArithmetic = 1e-6;

std::string testName(const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param;
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

}  // namespace

class CoordinateMapGpu : public ::testing::TestWithParam<std::string> {};

TEST_P(CoordinateMapGpu, RenderThroughTheMapEqualsTheMaterialisedMaterial) {
    SampleOptions options;
    options.width = 8;
    options.height = 6;  // not square: catches swapped axes
    options.views = options.lights = fewDirections();
    const MethodInfo& info = findMethod(GetParam());
    osg::ref_ptr<Material> material =
        info.fit(makeSampleBtf(options), FitOptions::parse(info.quickFitOptions));
    // Random texels on a grid unlike the sample's in both axes: a swapped axis, a flipped row or
    // the map's size taken for the sample's (osgBTF_size) shows almost everywhere.
    const CoordinateMap map = makeBlockCoordinateMap(12, 10, 8, 6, 1, 11);
    osg::ref_ptr<Material> remapped = remapMaterial(*material, map);
    const glm::vec3 view = Direction{31.7f, 77}.toVector(), light = Direction{52, 200}.toVector();

    HeadlessRenderer& renderer = test::sharedRenderer();
    const FloatImage gpuMapped = renderMaterialImage(renderer, *material, map, view, light);
    const FloatImage gpuRemapped = renderMaterialImage(renderer, *remapped, view, light);
    const FloatImage gpuPlain = renderMaterialImage(renderer, *material, view, light);
    const FloatImage cpuMapped = evaluateMaterialImage(*material, map, view, light);
    const FloatImage cpuRemapped = evaluateMaterialImage(*remapped, view, light);

    ASSERT_EQ(gpuMapped.width, 12);
    ASSERT_EQ(gpuMapped.height, 10);
    EXPECT_EQ(cpuMapped.pixels, cpuRemapped.pixels);  // exactly
    const double materialised = maxAbsDifference(gpuMapped, gpuRemapped);
    EXPECT_LE(materialised, kSameArithmetic);

    // Each pixel is the plain render's texel map(x, y) (image rows are top-down).
    double picked = 0, brightest = 0;
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x)
            for (int c = 0; c < 3; ++c) {
                const float got = gpuMapped.at(x, map.height - 1 - y, c);
                const float expected =
                    gpuPlain.at(map.sampleX(x, y), options.height - 1 - map.sampleY(x, y), c);
                picked = std::max(picked, double(std::abs(got - expected)));
                brightest = std::max(brightest, double(got));
            }
    EXPECT_LE(picked, kSameArithmetic);
    EXPECT_GT(brightest, 0.01) << "nothing rendered";
    const double gpuCpu = maxAbsDifference(gpuMapped, cpuMapped);
    std::cout << GetParam() << " through a 12x10 map: GPU vs materialised GPU " << materialised
              << ", vs plain render at the mapped texels " << picked << ", GPU vs CPU " << gpuCpu
              << " (plain: "
              << maxAbsDifference(gpuPlain, evaluateMaterialImage(*material, view, light)) << ")\n";
}

namespace {

using test::checkThroughMap;
using test::ThroughMapCheck;

}  // namespace

TEST_P(CoordinateMapGpu, MagnifiedAndAcrossTheWrapBlendsTheFourEntries) {
    SampleOptions options;
    options.width = 8;
    options.height = 6;
    options.views = options.lights = fewDirections();
    const MethodInfo& info = findMethod(GetParam());
    osg::ref_ptr<Material> material =
        info.fit(makeSampleBtf(options), FitOptions::parse(info.quickFitOptions));
    // Every entry its own random texel: neighbouring entries name unrelated texels.
    const CoordinateMap map = makeBlockCoordinateMap(12, 10, 8, 6, 1, 11);
    osg::ref_ptr<Material> remapped = remapMaterial(*material, map);
    const glm::vec3 view = Direction{31.7f, 77}.toVector();
    double worstGpuCpu = 0, worstBound = 0, worstMaterialisedCpu = 0, worstMaterialisedGpu = 0;
    for (const Direction& l : {Direction{52, 200}, Direction{30, 60}}) {
        const glm::vec3 light = l.toVector();
        const double bound = test::methodGpuBound(*material, view, light);
        const ThroughMapCheck r = checkThroughMap(*material, *remapped, map, view, light);
        EXPECT_LE(r.gpuCpu, bound) << GetParam() << " light " << l.theta << "/" << l.phi;
        // The reference blends: a render of the nearest entries would miss it by far more.
        EXPECT_GT(r.fromNearest, 10 * bound) << GetParam();
        // The materialised material's own filtered reference is the same blend of the same
        // values in the same order where it blends values. Where it filters parameters and
        // finishes the blend (ptm's clamp, fmf's decoding) it equals it while the finishing is
        // linear over the four entries, as for these fits (not with fmf's exp decoding:
        // FmfExpDecodingThroughAMapBlendsDecodedValues below).
        if (remapped->texelFilter() == Material::TexelFilter::Values) {
            EXPECT_EQ(r.materialisedCpu, 0.0) << GetParam();
        } else {
            EXPECT_LE(r.materialisedCpu, bound) << GetParam();
        }
        worstGpuCpu = std::max(worstGpuCpu, r.gpuCpu);
        worstBound = std::max(worstBound, bound);
        worstMaterialisedCpu = std::max(worstMaterialisedCpu, r.materialisedCpu);
        worstMaterialisedGpu = std::max(worstMaterialisedGpu, r.materialisedGpu);
    }
    std::cout << GetParam() << " through a 12x10 map, magnified x4 across the wrap: GPU vs CPU "
              << worstGpuCpu << " (bound " << worstBound
              << "); materialised material: CPU filtered " << worstMaterialisedCpu << ", GPU "
              << worstMaterialisedGpu << " ("
              << (remapped->filtersParameters() ? "filters parameters" : "blends values") << ")\n";
}

TEST(CoordinateMapGpu, FmfExpDecodingThroughAMapBlendsDecodedValues) {
    // fmf with dynamic-range reduction filters its parameters without a map and decodes (exp)
    // the blend. Through a map it cannot (neighbouring entries name unrelated sample texels)
    // and blends the four entries' decoded values like every method: the render equals
    // evaluateThroughMap, and between entries differs from the materialised material's
    // evaluateFiltered (exp of the blend), which the test shows is a real difference here.
    FactoredBtf drr = test::randomFactors(FactorModel::Fmf, {6, 6, 6}, 8, 4, 2);
    drr.dynamicRangeReduction = 1;
    drr.cosine = true;
    osg::ref_ptr<FmfMaterial> material = FmfMaterial::fromFactors(drr, MaterialTexture::Float);
    const CoordinateMap map = makeBlockCoordinateMap(12, 10, 8, 4, 1, 13);
    osg::ref_ptr<Material> remapped = remapMaterial(*material, map);
    ASSERT_TRUE(remapped->filtersParameters());
    const glm::vec3 view = Direction{31.7f, 77}.toVector(), light = Direction{45, 20}.toVector();
    const double bound = test::methodGpuBound(*material, view, light);
    const ThroughMapCheck r = checkThroughMap(*material, *remapped, map, view, light);
    EXPECT_LE(r.gpuCpu, bound);
    EXPECT_GT(r.fromNearest, 10 * bound);
    EXPECT_GT(r.materialisedCpu, 10 * bound) << "exp of the blend is not the blend of exp";
    std::cout << "fmf drr through a 12x10 map, magnified x4 across the wrap: GPU vs CPU "
              << r.gpuCpu << " (bound " << bound << "); materialised material: CPU filtered "
              << r.materialisedCpu << ", GPU " << r.materialisedGpu << "\n";
}

TEST_P(CoordinateMapGpu, MinifiedOverAMipMappedMaterialBlendsTwoLevelsOfTheMapsChain) {
    // A mip-mapped fit of an 8 x 8 sample (levels 8, 4, 2, 1) through a 32 x 32 patchwork of
    // 4 x 4 blocks, 6 map entries per pixel: lod log2(6) = 2.58, map levels 2 (8 x 8 entries,
    // naming the sample's 2 x 2 level) and 3 (4 x 4, its 1 x 1 level), pixel centres between the
    // entries of both. The render equals evaluateThroughMap through the map's chain; the map's
    // base level alone (what a map without a chain shows) is far from it.
    SampleOptions options;
    options.width = options.height = 8;
    options.views = options.lights = fewDirections();
    const MethodInfo& info = findMethod(GetParam());
    const osg::ref_ptr<Material> material =
        fitMipMapped(info, makeSampleBtf(options), FitOptions::parse(info.quickFitOptions));
    const CoordinateMap map = makeBlockCoordinateMap(32, 32, 8, 8, 4, 5);
    const std::vector<CoordinateMap> chain = coordinateMapChain(map, material->mipLayout());
    constexpr int kPixels = 32;
    constexpr float kScale = 6.0f;
    const float lod = std::log2(kScale * float(map.width) / float(kPixels));
    const glm::vec3 view = Direction{31.7f, 77}.toVector(), light = Direction{52, 200}.toVector();
    test::RectifiedPatchRender r;
    r.view = view;
    r.light = light;
    r.textureScale = kScale;
    r.width = r.height = kPixels;
    r.map = &map;
    const osg::ref_ptr<osg::Image> gpu = test::renderRectifiedPatch(*material, r);
    r.mipLevels = 1;  // the material's base level: the map's base level alone
    const osg::ref_ptr<osg::Image> baseOnly = test::renderRectifiedPatch(*material, r);
    double worst = 0, mean = 0, fromBase = 0;
    for (int j = 0; j < kPixels; ++j)
        for (int i = 0; i < kPixels; ++i) {
            const float u = (float(i) + 0.5f) / kPixels * kScale;
            const float v = (float(j) + 0.5f) / kPixels * kScale;
            const glm::vec3 cpu = evaluateThroughMap(*material, chain, u, v, lod, view, light);
            for (int c = 0; c < 3; ++c) {
                const double got = test::pixel(*gpu, i, j, c);
                worst = std::max(worst, std::abs(got - double(cpu[c])));
                fromBase = std::max(
                    fromBase, std::abs(double(test::pixel(*baseOnly, i, j, c)) - double(cpu[c])));
                mean += double(cpu[c]) / (3.0 * kPixels * kPixels);
            }
        }
    // The bound of tests/gl/mip_map_test.cpp (8-bit and half storage of some methods).
    const double bound = 1e-3 * (1.0 + mean) + 2e-3 * mean;
    std::cout << GetParam() << " minified through a 32x32 map's chain (lod " << lod
              << "): GPU vs CPU " << worst << " (bound " << bound
              << "), the map's base level alone " << fromBase << ", mean " << mean << "\n";
    EXPECT_LE(worst, bound) << GetParam();
    EXPECT_GT(mean, 0.01) << "nothing rendered";
    EXPECT_GT(fromBase, 10 * bound) << GetParam();

    // The identity map: through its chain the render is the material's own trilinear render
    // (the same texels and weights at every level; 1.5 map entries per pixel, levels 0 and 1).
    CoordinateMap identity(8, 8, 8, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            identity.sampleX(x, y) = x;
            identity.sampleY(x, y) = y;
        }
    r.mipLevels = -1;
    r.map = &identity;
    const osg::ref_ptr<osg::Image> throughIdentity = test::renderRectifiedPatch(*material, r);
    r.map = nullptr;
    const osg::ref_ptr<osg::Image> own = test::renderRectifiedPatch(*material, r);
    double identityDifference = 0;
    for (int j = 0; j < kPixels; ++j)
        for (int i = 0; i < kPixels; ++i)
            for (int c = 0; c < 3; ++c)
                identityDifference = std::max(
                    identityDifference, std::abs(double(test::pixel(*throughIdentity, i, j, c)) -
                                                 double(test::pixel(*own, i, j, c))));
    EXPECT_LE(identityDifference, kSameArithmetic) << GetParam();
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, CoordinateMapGpu, ::testing::ValuesIn(methodNames()),
                         testName);

// The scene path: a MaterialNode drawing a material through a map (its shared StateSet, its
// own StateSet, the map StateSet, its lights) renders what the node draws for the materialised
// material.
TEST(CoordinateMapGpu, MaterialNodeThroughAMapEqualsTheMaterialisedMaterial) {
    SampleOptions options;
    options.width = 8;
    options.height = 6;
    options.views = options.lights = fewDirections();
    osg::ref_ptr<Material> material =
        PcaMaterial::fit(makeSampleBtf(options), FitOptions::parse("components=3"));
    auto map = std::make_shared<const CoordinateMap>(makeBlockCoordinateMap(24, 20, 8, 6, 1, 5));
    osg::ref_ptr<Material> remapped = remapMaterial(*material, *map);
    HeadlessRenderer& renderer = test::sharedRenderer();
    // One pixel per map texel; no LightSource and no view: the node's white headlight.
    const auto render = [&](Material* m, std::shared_ptr<const CoordinateMap> through) {
        osg::ref_ptr<MaterialNode> node = new MaterialNode(m);
        EXPECT_TRUE(node->setCoordinateMap(through));
        EXPECT_EQ(node->usesCoordinateMap(), through != nullptr);
        node->addChild(createFullScreenQuad().get());
        osg::ref_ptr<osg::Image> image = renderer.render(node.get(), orthoUnitSquare(24, 20));
        const float* rgba = reinterpret_cast<const float*>(image->data());
        return std::vector<float>(rgba, rgba + 24 * 20 * 4);
    };
    const std::vector<float> mapped = render(material.get(), map);
    const std::vector<float> materialised = render(remapped.get(), nullptr);
    double worst = 0, brightest = 0;
    for (std::size_t i = 0; i < mapped.size(); ++i) {
        worst = std::max(worst, double(std::abs(mapped[i] - materialised[i])));
        if (i % 4 != 3) brightest = std::max(brightest, double(mapped[i]));
    }
    EXPECT_LE(worst, kSameArithmetic);
    EXPECT_GT(brightest, 0.01) << "nothing rendered";
}

}  // namespace OSGBTF_TEST_FILE
