// BSVTF on the GPU: a streamed fmf material from a tile set in a folder, drawn under a
// StreamingGroup whose feedback pass drives the tile cache. Every frame the render equals the CPU
// evaluation of what has arrived (StreamedFmfMaterial::snapshot); once converged with a cache that
// holds every finest tile it equals the fmf material itself, at texel centres and filtered between
// them, across tile edges and the material's wrap edge; the feedback pass reports level
// L - k where 2^k texels fall in a pixel (Schwartz et al. 2013 eq. 1); minified, a fragment blends
// its deepest resident level with the parent level (trilinear) as StreamedFmfMaterial's CPU
// reference does.
#include <cmath>
#include <iostream>
#include <tuple>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <osg/Geode>
#include <osg/Uniform>
#include <osgViewer/CompositeViewer>
#include <osgViewer/View>

#include "harness/MaterialImage.h"
#include "harness/headless/HeadlessContext.h"
#include "materials/MaterialState.h"
#include "materials/MethodPrograms.h"
#include "materials/ShaderInterface.h"
#include "materials/fmf/Fmf.h"
#include "scene/MaterialNode.h"
#include "streaming/StreamingGroup.h"
#include "streaming/TileBuilder.h"
#include "tests/RandomFactors.h"
#include "tests/TestUtil.h"
#include "tests/gl/GlTestEnv.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

// 40 x 24 texels, 8 components (2 groups), tiles of 8 + 4: levels 5 x 3, 10 x 6, 20 x 12,
// 40 x 24 with 1, 2, 6 and 15 tiles: 24 tiles per group.
constexpr int kWidth = 40, kHeight = 24, kTile = 8, kPadding = 4, kFinest = 3;

osg::ref_ptr<FmfMaterial> original() {
    static const osg::ref_ptr<FmfMaterial> m =
        FmfMaterial::fromFactors(randomFactors(FactorModel::Fmf, {8, 0, 0}, kWidth, kHeight, 11));
    return m;
}

TileStreamerOptions streamerOptions(int slotsPerSide) {
    TileStreamerOptions o;
    o.tileSize = kTile;
    o.padding = kPadding;
    o.cacheSize = slotsPerSide * (kTile + 2 * kPadding);
    o.uploadsPerUpdate = 4;  // several frames to converge: the intermediate states are tested
    return o;
}

/** The patch with the material's state, one light, a fixed view, tiled `repeats` times; the
 *  nearest texel unless `filtered`. */
osg::ref_ptr<osg::Geode> patch(const Material& material, const glm::vec3& view,
                               const glm::vec3& light, float repeats = 1.0f,
                               bool filtered = false) {
    osg::ref_ptr<osg::StateSet> stateSet = material.createStateSet();
    stateSet->addUniform(new osg::Uniform(shader::kTextureScale, repeats));
    // One pixel per texel, at its centre, compares texel by texel with evaluate(): filtered, a
    // pixel centre on a texel centre would still blend in rounding shares (~1e-6) of the
    // neighbours (the interpolated coordinate is not exact), for the fmf material and the cache
    // alike, so both are read at the nearest texel there.
    if (!filtered) stateSet->addUniform(new osg::Uniform(shader::kBilinear, false));
    addRectifiedLighting(*stateSet, view, light);
    osg::ref_ptr<osg::Geode> geode = rectifiedPatch();
    geode->setStateSet(stateSet.get());
    return geode;
}

/** Largest |render - CPU evaluate| over the pixels (one per texel), relative to the value. */
double gpuVsCpu(const osg::Image& image, const Material& material, const glm::vec3& view,
                const glm::vec3& light) {
    double worst = 0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            const glm::vec3 cpu = material.evaluate(x, y, view, light);
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, std::abs(double(pixel(image, x, y, c)) - cpu[c]) /
                                            (1e-3 + std::abs(cpu[c])));
        }
    return worst;
}

/** An orthographic view of `texels` x `texels` finest texels around texel corner (x, y) of the
 *  patch tiled `repeats` times, over kPixels x kPixels pixels: magnified for texels < kPixels,
 *  minified (lod log2(texels / kPixels)) above. */
struct TexelWindow {
    static constexpr int kPixels = 64;
    TexelWindow(double x, double y, double texels, float repeats_) : repeats(repeats_) {
        // Patch coordinates = texture coordinates / repeats.
        x0 = (x - 0.5 * texels) / (kWidth * repeats);
        x1 = (x + 0.5 * texels) / (kWidth * repeats);
        y0 = (y - 0.5 * texels) / (kHeight * repeats);
        y1 = (y + 0.5 * texels) / (kHeight * repeats);
        camera.projection = osg::Matrixd::ortho(x0, x1, y0, y1, -1.0, 1.0);
        camera.width = camera.height = kPixels;
    }
    /** The texture coordinates at pixel (i, j)'s centre. */
    glm::vec2 uv(int i, int j) const {
        return {float((x0 + (x1 - x0) * (i + 0.5) / kPixels) * repeats),
                float((y0 + (y1 - y0) * (j + 0.5) / kPixels) * repeats)};
    }
    CameraSetup camera;
    double x0, x1, y0, y1;
    float repeats;
};

/** The largest |value| of the fmf material's texels: the scale of fmf's filtered GPU == CPU
 *  tolerance (bilinear_filter_test.cpp). GL_LINEAR's weights may be fixed-point (8 bits on common
 *  GPUs), and the cache and the fmf texture see a pixel's coordinate rounded differently. */
double largestValue(const glm::vec3& view, const glm::vec3& light) {
    double scale = 0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x) {
            const glm::vec3 value = original()->evaluate(x, y, view, light);
            for (int c = 0; c < 3; ++c) scale = std::max(scale, double(std::abs(value[c])));
        }
    return scale;
}

struct BsvtfGpu : ::testing::Test {
    void SetUp() override {
        TileBuildOptions build;
        build.codec = "raw";
        build.tileSize = kTile;
        build.padding = kPadding;
        buildTileSet(*original(), dir.file("tiles"), build);
    }
    TempDir dir;
};

TEST_F(BsvtfGpu, RendersWhatHasArrivedEveryFrameAndConvergesToTheFmfMaterial) {
    // 49 slots hold all 48 tiles: converged, every finest tile is resident.
    osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(streamerOptions(7)));
    group->setFeedbackScale(1);
    const osg::ref_ptr<StreamedFmfMaterial> streamed = group->streamer()->open(dir.file("tiles"));
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    const glm::vec3 light = glm::normalize(glm::vec3(-0.4f, 0.1f, 0.8f));
    group->addChild(patch(*streamed, view, light));
    HeadlessRenderer& renderer = sharedRenderer();
    renderer.setScene(group.get());
    renderer.setCamera(orthoUnitSquare(kWidth, kHeight));
    int frames = 0, partialFramesChecked = 0;
    while (!group->settled() && frames < 200) {
        const osg::ref_ptr<osg::Image> image = renderer.render();
        ++frames;
        // What was drawn is what the CPU reference sees now (single-threaded viewer).
        const double difference = gpuVsCpu(*image, *streamed, view, light);
        ASSERT_LT(difference, 1e-4) << "frame " << frames;
        if (group->streamer()->stats().residentTiles < 48) ++partialFramesChecked;
    }
    ASSERT_TRUE(group->settled()) << "not converged after " << frames << " frames";
    EXPECT_GE(partialFramesChecked, 3) << "the intermediate states were not exercised";
    const StreamingStats stats = group->streamer()->stats();
    std::cout << "converged after " << frames << " frames: " << stats.residentTiles
              << " resident tiles, " << stats.uploads << " uploads, " << stats.bytesReceived
              << " bytes received\n";
    // Every finest tile resident (15 per group), with all their ancestors.
    for (int g = 0; g < 2; ++g)
        for (int ty = 0; ty < 3; ++ty)
            for (int tx = 0; tx < 5; ++tx)
                EXPECT_TRUE(group->streamer()->scheduler().resident(0, {g, kFinest, tx, ty}));

    // The converged render equals the fmf material's own render: same halves, same shader code.
    const osg::ref_ptr<osg::Image> streamedImage = renderer.render();
    const osg::ref_ptr<osg::Image> fmfImage =
        renderer.render(patch(*original(), view, light).get(), orthoUnitSquare(kWidth, kHeight));
    EXPECT_LT(maxDifference(*streamedImage, *fmfImage), 1e-6);
    EXPECT_LT(gpuVsCpu(*fmfImage, *original(), view, light), 1e-4);
}

// Two contexts (two viewers, as two windows of one application) render one StreamingGroup: each
// context's texture object of the cache gets every tile, also a context that joins after the
// first converged (the cache gives a new texture object every slot, not only what arrives
// after it), and both render what has arrived, frames alternating while a second group streams
// from scratch.
TEST_F(BsvtfGpu, TwoContextsRenderOneStreamingGroup) {
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    const glm::vec3 light = glm::normalize(glm::vec3(-0.4f, 0.1f, 0.8f));
    const auto streamedGroup = [&](osg::ref_ptr<StreamedFmfMaterial>& streamed) {
        osg::ref_ptr<StreamingGroup> group =
            new StreamingGroup(new TileStreamer(streamerOptions(7)));
        group->setFeedbackScale(1);
        streamed = group->streamer()->open(dir.file("tiles"));
        group->addChild(patch(*streamed, view, light));
        return group;
    };
    HeadlessRenderer& first = sharedRenderer();
    HeadlessRenderer second(glTestBackend());
    osg::ref_ptr<StreamedFmfMaterial> streamed;
    osg::ref_ptr<StreamingGroup> group = streamedGroup(streamed);
    first.setScene(group.get());
    first.setCamera(orthoUnitSquare(kWidth, kHeight));
    for (int frames = 0; !group->settled() && frames < 200; ++frames) first.render();
    ASSERT_TRUE(group->settled());
    second.setScene(group.get());
    second.setCamera(orthoUnitSquare(kWidth, kHeight));
    EXPECT_LT(gpuVsCpu(*second.render(), *streamed, view, light), 1e-4) << "the late context";
    EXPECT_LT(gpuVsCpu(*first.render(), *streamed, view, light), 1e-4);

    group = streamedGroup(streamed);
    first.setScene(group.get());
    second.setScene(group.get());
    int frames = 0;
    for (; !group->settled() && frames < 400; ++frames) {
        HeadlessRenderer& renderer = frames % 2 == 0 ? first : second;
        ASSERT_LT(gpuVsCpu(*renderer.render(), *streamed, view, light), 1e-4)
            << (frames % 2 == 0 ? "first" : "second") << " context, frame " << frames;
    }
    ASSERT_TRUE(group->settled()) << "not converged after " << frames << " frames";
    EXPECT_LT(gpuVsCpu(*second.render(), *streamed, view, light), 1e-4);
    EXPECT_LT(gpuVsCpu(*first.render(), *streamed, view, light), 1e-4);
    EXPECT_LT(gpuVsCpu(*first.render(patch(*original(), view, light).get(),
                                     orthoUnitSquare(kWidth, kHeight)),
                       *original(), view, light),
              1e-4);
    second.setScene(nullptr);
    first.setScene(nullptr);
}

// A CompositeViewer with two views on one shared context (two cameras, as two viewports of one
// window), both showing one StreamingGroup: the group's feedback pass and read-back run once per
// view and frame; both views converge, each frame equal to the CPU reference.
TEST_F(BsvtfGpu, TwoViewsOnOneContextRenderOneStreamingGroup) {
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    const glm::vec3 light = glm::normalize(glm::vec3(-0.4f, 0.1f, 0.8f));
    osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(streamerOptions(7)));
    group->setFeedbackScale(1);
    const osg::ref_ptr<StreamedFmfMaterial> streamed = group->streamer()->open(dir.file("tiles"));
    group->addChild(patch(*streamed, view, light));

    osg::ref_ptr<HeadlessContext> context = createHeadlessContext(glTestBackend(), 64, 64);
    ASSERT_TRUE(context.valid());
    osg::ref_ptr<osgViewer::CompositeViewer> viewer = new osgViewer::CompositeViewer;
    viewer->setThreadingModel(osgViewer::ViewerBase::SingleThreaded);
    std::vector<osg::ref_ptr<osg::Image>> images;
    const CameraSetup setup = orthoUnitSquare(kWidth, kHeight);
    for (int i = 0; i < 2; ++i) {
        osg::ref_ptr<osgViewer::View> v = new osgViewer::View;
        osg::Camera* camera = v->getCamera();
        camera->setGraphicsContext(context.get());
        camera->setViewport(0, 0, kWidth, kHeight);
        camera->setViewMatrix(setup.view);
        camera->setProjectionMatrix(setup.projection);
        camera->setReferenceFrame(osg::Transform::ABSOLUTE_RF);
        camera->setComputeNearFarMode(osg::CullSettings::DO_NOT_COMPUTE_NEAR_FAR);
        camera->setClearColor(osg::Vec4(0, 0, 0, 0));
        camera->setRenderTargetImplementation(osg::Camera::FRAME_BUFFER_OBJECT);
        osg::ref_ptr<osg::Image> image = new osg::Image;
        image->allocateImage(kWidth, kHeight, 1, GL_RGBA, GL_FLOAT);
        image->setInternalTextureFormat(GL_RGBA32F_ARB);
        camera->attach(osg::Camera::COLOR_BUFFER0, image.get());
        camera->attach(osg::Camera::DEPTH_BUFFER, GL_DEPTH_COMPONENT24);
        v->setSceneData(group.get());
        viewer->addView(v.get());
        images.push_back(image);
    }
    viewer->realize();
    ASSERT_TRUE(viewer->isRealized());
    int frames = 0;
    for (; frames < 200 && !(frames > 0 && group->settled()); ++frames) {
        viewer->frame();
        for (int i = 0; i < 2; ++i)
            ASSERT_LT(gpuVsCpu(*images[std::size_t(i)], *streamed, view, light), 1e-4)
                << "view " << i << ", frame " << frames;
    }
    ASSERT_TRUE(group->settled()) << "not converged after " << frames << " frames";
    EXPECT_EQ(group->streamer()->stats().residentTiles, 48);
    viewer->frame();
    for (int i = 0; i < 2; ++i)
        EXPECT_LT(gpuVsCpu(*images[std::size_t(i)], *original(), view, light), 1e-4) << i;
    if (context->makeCurrent()) {
        releaseCachedPrograms(context->getState());
        context->releaseContext();
    }
}

TEST_F(BsvtfGpu, ConvergedMagnifiedRenderIsFilteredAsTheFmfMaterialAcrossTileAndWrapEdges) {
    // Every finest tile resident (as above), then magnified views: 4 x 4 texels over 64 x 64
    // pixels, so every pixel centre lies between texel centres (at odd multiples of 1/32 texel).
    osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(streamerOptions(7)));
    group->setFeedbackScale(1);
    const osg::ref_ptr<StreamedFmfMaterial> streamed = group->streamer()->open(dir.file("tiles"));
    ASSERT_EQ(streamed->texelFilter(), Material::TexelFilter::Parameters);
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    group->addChild(patch(*streamed, view, glm::vec3(0, 0, 1)));
    HeadlessRenderer& renderer = sharedRenderer();
    renderer.setScene(group.get());
    renderer.setCamera(orthoUnitSquare(kWidth, kHeight));
    for (int frames = 0; !group->settled() && frames < 200; ++frames) renderer.render();
    ASSERT_TRUE(group->settled());
    for (int g = 0; g < 2; ++g)
        for (int ty = 0; ty < 3; ++ty)
            for (int tx = 0; tx < 5; ++tx)
                ASSERT_TRUE(group->streamer()->scheduler().resident(0, {g, kFinest, tx, ty}));

    // (texel corner at the window's centre, texture repeats): the corner of finest tiles (0, 0),
    // (1, 0), (0, 1), (1, 1) at texel (8, 8), where each fragment's footprint reaches into the
    // next tile's texels through its tile's padding; the material's border at (40, 24) seen with
    // the texture repeated twice, where the footprint wraps to the first column and row.
    struct Case {
        int x, y;
        float repeats;
        const char* name;
    };
    for (const Case& w : {Case{8, 8, 1.0f, "tile corner"}, Case{40, 24, 2.0f, "wrap"}})
        for (const glm::vec3& light : {glm::normalize(glm::vec3(-0.4f, 0.1f, 0.8f)),
                                       glm::normalize(glm::vec3(0.5f, 0.6f, 0.6f))}) {
            const TexelWindow window(w.x, w.y, 4, w.repeats);
            const osg::ref_ptr<osg::Image> streamedImage = renderer.render(
                patch(*streamed, view, light, w.repeats, true).get(), window.camera);
            const osg::ref_ptr<osg::Image> fmfImage = renderer.render(
                patch(*original(), view, light, w.repeats, true).get(), window.camera);
            // GPU against GPU, and against the CPU reference of the filter (the fmf material's,
            // and the streamed material's own), relative to the largest value.
            const double scale = largestValue(view, light);
            double streamedVsFmf = 0, streamedVsCpu = 0, ownCpu = 0, filteredVsNearest = 0;
            for (int j = 0; j < TexelWindow::kPixels; ++j)
                for (int i = 0; i < TexelWindow::kPixels; ++i) {
                    const glm::vec2 uv = window.uv(i, j);
                    const glm::vec3 cpu =
                        original()->evaluateFiltered(uv.x, uv.y, 0.0f, view, light);
                    const glm::vec3 own = streamed->evaluateFiltered(uv.x, uv.y, 0.0f, view, light);
                    const int tx = int(std::floor((uv.x - std::floor(uv.x)) * kWidth));
                    const int ty = int(std::floor((uv.y - std::floor(uv.y)) * kHeight));
                    const glm::vec3 nearest = original()->evaluate(tx, ty, view, light);
                    for (int c = 0; c < 3; ++c) {
                        const double gpu = pixel(*streamedImage, i, j, c);
                        streamedVsFmf = std::max(streamedVsFmf,
                                                 std::abs(gpu - pixel(*fmfImage, i, j, c)) / scale);
                        streamedVsCpu = std::max(streamedVsCpu, std::abs(gpu - cpu[c]) / scale);
                        ownCpu = std::max(ownCpu, std::abs(gpu - own[c]) / scale);
                        filteredVsNearest =
                            std::max(filteredVsNearest, std::abs(cpu[c] - nearest[c]) / scale);
                    }
                }
            std::cout << w.name << ": streamed vs fmf " << streamedVsFmf << ", vs CPU filtered "
                      << streamedVsCpu << " (own " << ownCpu << "); filtered vs nearest "
                      << filteredVsNearest << "\n";
            EXPECT_LT(streamedVsFmf, 1e-3) << w.name;
            EXPECT_LT(streamedVsCpu, 1e-3) << w.name;
            EXPECT_LT(ownCpu, 1e-3) << w.name;
            // The blend is far from the nearest texel's value: nearest lookups would fail above.
            EXPECT_GT(filteredVsNearest, 1e-1) << w.name;
        }
}

TEST_F(BsvtfGpu, TilesWithoutPaddingBlendTheValuesOfFourTexels) {
    // P = 0 leaves the cache nothing to filter from inside a slot: btf_main.glsl blends the four
    // texels' values instead (TexelFilter::Values), each fetched through its own LUT entry.
    TileBuildOptions build;
    build.codec = "raw";
    build.tileSize = kTile;
    build.padding = 0;
    buildTileSet(*original(), dir.file("unpadded"), build);
    TileStreamerOptions options = streamerOptions(7);
    options.padding = 0;
    options.cacheSize = 7 * kTile;
    osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(options));
    group->setFeedbackScale(1);
    const osg::ref_ptr<StreamedFmfMaterial> streamed =
        group->streamer()->open(dir.file("unpadded"));
    ASSERT_EQ(streamed->texelFilter(), Material::TexelFilter::Values);
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    const glm::vec3 light = glm::normalize(glm::vec3(-0.4f, 0.1f, 0.8f));
    group->addChild(patch(*streamed, view, light));
    HeadlessRenderer& renderer = sharedRenderer();
    renderer.setScene(group.get());
    renderer.setCamera(orthoUnitSquare(kWidth, kHeight));
    for (int frames = 0; !group->settled() && frames < 200; ++frames) renderer.render();
    ASSERT_TRUE(group->settled());
    for (int g = 0; g < 2; ++g)
        for (int ty = 0; ty < 3; ++ty)
            for (int tx = 0; tx < 5; ++tx)
                ASSERT_TRUE(group->streamer()->scheduler().resident(0, {g, kFinest, tx, ty}));
    const double scale = largestValue(view, light);
    for (const auto& [x, y, repeats] : {std::tuple{8, 8, 1.0f}, {40, 24, 2.0f}}) {
        const TexelWindow window(x, y, 4, repeats);
        const osg::ref_ptr<osg::Image> image =
            renderer.render(patch(*streamed, view, light, repeats, true).get(), window.camera);
        double worst = 0;
        for (int j = 0; j < TexelWindow::kPixels; ++j)
            for (int i = 0; i < TexelWindow::kPixels; ++i) {
                const glm::vec2 uv = window.uv(i, j);
                const glm::vec3 cpu = original()->evaluateFiltered(uv.x, uv.y, 0.0f, view, light);
                for (int c = 0; c < 3; ++c)
                    worst = std::max(worst, std::abs(pixel(*image, i, j, c) - cpu[c]) / scale);
            }
        std::cout << "unpadded around (" << x << ", " << y << "): GPU vs CPU " << worst << "\n";
        EXPECT_LT(worst, 1e-3) << x << ", " << y;
    }
}

TEST_F(BsvtfGpu, AFragmentIsFilteredAtItsTilesResidentLevel) {
    // The patch tiled 8 times over 40 x 24 pixels: 8 texels per pixel, so the feedback asks for
    // level 0 (5 x 3 texels, one tile of 8 whose columns 5-7 and rows 3-7 repeat the level) and
    // nothing finer arrives. Then magnified: each fragment blends the four level-0 texels around
    // its coordinate / 8, wrapped at the level's edge, from that one tile and its padding.
    osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(streamerOptions(7)));
    group->setFeedbackScale(1);
    const osg::ref_ptr<StreamedFmfMaterial> streamed = group->streamer()->open(dir.file("tiles"));
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    group->addChild(patch(*streamed, view, glm::vec3(0, 0, 1), 8.0f));
    HeadlessRenderer& renderer = sharedRenderer();
    renderer.setScene(group.get());
    renderer.setCamera(orthoUnitSquare(kWidth, kHeight));
    for (int frames = 0; !group->settled() && frames < 200; ++frames) renderer.render();
    ASSERT_TRUE(group->settled());
    for (int g = 0; g < 2; ++g) {
        ASSERT_TRUE(group->streamer()->scheduler().resident(0, {g, 0, 0, 0}));
        ASSERT_FALSE(group->streamer()->scheduler().resident(0, {g, 1, 0, 0}));
        ASSERT_FALSE(group->streamer()->scheduler().resident(0, {g, 1, 1, 0}));
    }
    // The reference blends evaluate()'s values: the random factors decode linearly (no exp).
    ASSERT_EQ(original()->factors().dynamicRangeReduction, 0u);
    const glm::vec3 light = glm::normalize(glm::vec3(-0.4f, 0.1f, 0.8f));
    const double scale = largestValue(view, light);
    // 4 x 4 level-0 texels around level-0 texel corner (2, 2), and around (5, 3), the level's
    // border (the patch tiled twice: the coordinates pass 1 there).
    for (const auto& [x, y] : {std::pair{16, 16}, {40, 24}}) {
        const TexelWindow window(x, y, 32, 2.0f);
        const osg::ref_ptr<osg::Image> image =
            renderer.render(patch(*streamed, view, light, 2.0f, true).get(), window.camera);
        double worst = 0, filteredVsNearest = 0;
        for (int j = 0; j < TexelWindow::kPixels; ++j)
            for (int i = 0; i < TexelWindow::kPixels; ++i) {
                const glm::vec2 uv = window.uv(i, j);
                // GL_LINEAR on the 5 x 3 level with wrap-around; level-0 texel (a, b) is what
                // the streamed material (its snapshot) shows at finest texel (8a, 8b).
                const auto axis = [](float t, int size, int& i0, int& i1, float& w) {
                    const float s = (t - std::floor(t)) * float(size) - 0.5f;
                    i0 = int(std::floor(s));
                    w = s - float(i0);
                    i0 = (i0 + size) % size;
                    i1 = (i0 + 1) % size;
                };
                int a0, a1, b0, b1;
                float wa, wb;
                axis(uv.x, 5, a0, a1, wa);
                axis(uv.y, 3, b0, b1, wb);
                const auto level0 = [&](int a, int b) {
                    return streamed->evaluate(8 * a, 8 * b, view, light);
                };
                const glm::vec3 cpu = (1 - wa) * (1 - wb) * level0(a0, b0) +
                                      wa * (1 - wb) * level0(a1, b0) +
                                      (1 - wa) * wb * level0(a0, b1) + wa * wb * level0(a1, b1);
                const glm::vec3 nearest = level0(int(std::floor((uv.x - std::floor(uv.x)) * 5)),
                                                 int(std::floor((uv.y - std::floor(uv.y)) * 3)));
                for (int c = 0; c < 3; ++c) {
                    worst = std::max(worst, std::abs(pixel(*image, i, j, c) - cpu[c]) / scale);
                    filteredVsNearest =
                        std::max(filteredVsNearest, std::abs(cpu[c] - nearest[c]) / scale);
                }
            }
        std::cout << "level 0 around (" << x << ", " << y << "): GPU vs CPU " << worst
                  << "; filtered vs nearest " << filteredVsNearest << "\n";
        EXPECT_LT(worst, 1e-3) << x << ", " << y;
        EXPECT_GT(filteredVsNearest, 1e-2) << x << ", " << y;
    }
}

TEST_F(BsvtfGpu, MinifiedFragmentsBlendTheDeepestResidentLevelWithItsParent) {
    // Trilinear (bsvtf.frag): the GL_LINEAR value at the fragment's deepest resident level d,
    // mixed with the one at d's parent level by lod - (L - d) clamped to [0, 1]. 64 x 64 pixels
    // against StreamedFmfMaterial::evaluateResidentFiltered at each pixel centre and the view's
    // lod, and against the single-level blend (lod 0: d alone, the filter before trilinear),
    // from which the render must differ. Cases (texels per pixel; what is resident):
    //  - 1.5, converged there: every finest tile; levels L (share 0.415) and L - 1 (0.585);
    //  - 3, the same cache: d = L is finer than the footprint needs, its parent alone (share 1);
    //  - 3, converged there: the feedback asks for L - 1, which is d: L - 1 and L - 2 (0.585).
    // While the first converges, every frame too: tiles at different levels side by side, level-0
    // tiles still zero, U packets missing.
    // Tolerance: 1e-3 of the largest value, as the magnified filtered tests (GL_LINEAR's weights
    // may be 8-bit fixed point on GPUs); the texture coordinates the GPU interpolates and the CPU
    // computes differ by float rounding (~1e-6 at uv ~ 10, ~4e-5 of a finest texel), the lods
    // by ~1e-7.
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    const glm::vec3 light = glm::normalize(glm::vec3(-0.4f, 0.1f, 0.8f));
    const double scale = largestValue(view, light);
    struct Case {
        double texels;  // finest texels across the 64 pixels
        float repeats;
        bool converge;  // a fresh streamer converged for this view, else the previous one's cache
        int deepest;    // the level every finest tile position shows
        const char* name;
    };
    const Case cases[] = {{96, 8.0f, true, kFinest, "1.5 texels per pixel"},
                          {192, 16.0f, false, kFinest, "3 texels per pixel, every tile resident"},
                          {192, 16.0f, true, kFinest - 1, "3 texels per pixel, converged there"}};
    HeadlessRenderer& renderer = sharedRenderer();
    osg::ref_ptr<StreamingGroup> group;
    osg::ref_ptr<StreamedFmfMaterial> streamed;
    /** Largest |GPU - CPU| / scale over the pixels, and of |CPU - CPU at lod 0| / scale. */
    const auto compare = [&](const osg::Image& image, const TexelWindow& window, float lod,
                             double& gpuVsCpu, double& trilinearVsSingle) {
        gpuVsCpu = trilinearVsSingle = 0;
        for (int j = 0; j < TexelWindow::kPixels; ++j)
            for (int i = 0; i < TexelWindow::kPixels; ++i) {
                const glm::vec2 uv = window.uv(i, j);
                const glm::vec3 cpu =
                    streamed->evaluateResidentFiltered(uv.x, uv.y, lod, view, light);
                const glm::vec3 single =
                    streamed->evaluateResidentFiltered(uv.x, uv.y, 0.0f, view, light);
                for (int k = 0; k < 3; ++k) {
                    gpuVsCpu = std::max(gpuVsCpu, std::abs(pixel(image, i, j, k) - cpu[k]) / scale);
                    trilinearVsSingle =
                        std::max(trilinearVsSingle, std::abs(double(cpu[k] - single[k])) / scale);
                }
            }
    };
    for (const Case& c : cases) {
        const TexelWindow window(kWidth * c.repeats / 2, kHeight * c.repeats / 2, c.texels,
                                 c.repeats);
        const float lod = float(std::log2(c.texels / TexelWindow::kPixels));
        if (c.converge) {
            group = new StreamingGroup(new TileStreamer(streamerOptions(7)));
            group->setFeedbackScale(1);
            streamed = group->streamer()->open(dir.file("tiles"));
            group->addChild(patch(*streamed, view, light, c.repeats, true));
            renderer.setScene(group.get());
            renderer.setCamera(window.camera);
            int frames = 0, partial = 0;
            double worst = 0;
            for (; !group->settled() && frames < 200; ++frames) {
                const osg::ref_ptr<osg::Image> image = renderer.render();
                if (&c != &cases[0]) continue;
                // The frame showed what the CPU reference sees now (single-threaded viewer).
                double gpuVsCpu = 0, unused = 0;
                compare(*image, window, lod, gpuVsCpu, unused);
                ASSERT_LT(gpuVsCpu, 1e-3) << c.name << ", frame " << frames;
                worst = std::max(worst, gpuVsCpu);
                if (group->streamer()->stats().residentTiles < 48) ++partial;
            }
            ASSERT_TRUE(group->settled()) << c.name;
            if (&c == &cases[0]) {
                std::cout << c.name << ": " << frames << " frames while tiles arrive (" << partial
                          << " partial), GPU vs CPU " << worst << "\n";
                EXPECT_GE(partial, 3) << "the intermediate states were not exercised";
            }
        }
        const TileScheduler& scheduler = group->streamer()->scheduler();
        const TileLayout& layout = scheduler.layout(0);
        for (int g = 0; g < 2; ++g)
            for (int ty = 0; ty < layout.tilesY(kFinest); ++ty)
                for (int tx = 0; tx < layout.tilesX(kFinest); ++tx)
                    ASSERT_EQ(scheduler.lookup(0, g, tx, ty).level, c.deepest) << c.name;
        const osg::ref_ptr<osg::Image> image =
            renderer.render(patch(*streamed, view, light, c.repeats, true).get(), window.camera);
        double gpuVsCpu = 0, trilinearVsSingle = 0;
        compare(*image, window, lod, gpuVsCpu, trilinearVsSingle);
        std::cout << c.name << " (lod " << lod << "): GPU vs CPU " << gpuVsCpu
                  << "; trilinear vs one level " << trilinearVsSingle << "\n";
        EXPECT_LT(gpuVsCpu, 1e-3) << c.name;
        EXPECT_GT(trilinearVsSingle, 1e-2) << c.name;
    }
}

TEST_F(BsvtfGpu, FeedbackLevelIsTheFinestMinusLog2OfTexelsPerPixel) {
    osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(streamerOptions(7)));
    group->setFeedbackScale(1);
    const osg::ref_ptr<StreamedFmfMaterial> streamed = group->streamer()->open(dir.file("tiles"));
    HeadlessRenderer& renderer = sharedRenderer();
    for (int k = 0; k <= kFinest; ++k) {
        // 40 pixels across the patch tiled 2^k times: 2^k texels per pixel along each axis.
        group->removeChildren(0, group->getNumChildren());
        group->addChild(patch(*streamed, {0, 0, 1}, {0, 0, 1}, float(1 << k)));
        renderer.setScene(group.get());
        renderer.setCamera(orthoUnitSquare(kWidth, kHeight));
        // The read-back is asynchronous: the second frame delivers the first one's feedback.
        renderer.render();
        renderer.render();
        const osg::ref_ptr<osg::Image> feedback = group->lastFeedback();
        ASSERT_TRUE(feedback);
        ASSERT_EQ(feedback->s(), kWidth);
        for (int y = 0; y < kHeight; ++y)
            for (int x = 0; x < kWidth; ++x) {
                const unsigned char* p = feedback->data(x, y);
                ASSERT_EQ(int(p[3]), 1) << "material id + 1 at " << x << "," << y;
                ASSERT_EQ(int(p[2]), kFinest - k) << "level at " << x << "," << y << ", k " << k;
                // Pixel x's centre shows finest texel (x + 0.5) 2^k mod 40; its tile at the
                // level is that texel >> k over 8.
                const int tx = int(std::floor((x + 0.5) * (1 << k))) % kWidth;
                const int ty = int(std::floor((y + 0.5) * (1 << k))) % kHeight;
                ASSERT_EQ(int(p[0]), (tx >> k) / kTile) << x << "," << y << ", k " << k;
                ASSERT_EQ(int(p[1]), (ty >> k) / kTile) << x << "," << y << ", k " << k;
            }
    }
}

TEST_F(BsvtfGpu, AMaterialNodeTakesAStreamedMaterialLikeAnyOther) {
    // The same patch under a MaterialNode (tangents, the viewer's headlight, its uniforms), once
    // with the streamed material and once with the fmf material itself: equal once converged.
    osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(streamerOptions(7)));
    group->setFeedbackScale(1);
    osg::ref_ptr<MaterialNode> streamedNode =
        new MaterialNode(group->streamer()->open(dir.file("tiles")).get());
    osg::ref_ptr<osg::Geode> streamedPatch = rectifiedPatch();
    // Both at the nearest texel, as patch() reads them: one pixel per texel.
    streamedPatch->getOrCreateStateSet()->addUniform(new osg::Uniform(shader::kBilinear, false));
    streamedNode->addChild(streamedPatch.get());
    group->addChild(streamedNode.get());
    HeadlessRenderer& renderer = sharedRenderer();
    renderer.setScene(group.get());
    renderer.setCamera(orthoUnitSquare(kWidth, kHeight));
    int frames = 0;
    while (!group->settled() && frames < 200) {
        renderer.render();
        ++frames;
    }
    ASSERT_TRUE(group->settled()) << "not converged after " << frames << " frames";
    const osg::ref_ptr<osg::Image> streamedImage = renderer.render();
    osg::ref_ptr<MaterialNode> fmfNode = new MaterialNode(original().get());
    osg::ref_ptr<osg::Geode> fmfPatch = rectifiedPatch();
    fmfPatch->getOrCreateStateSet()->addUniform(new osg::Uniform(shader::kBilinear, false));
    fmfNode->addChild(fmfPatch.get());
    const osg::ref_ptr<osg::Image> fmfImage =
        renderer.render(fmfNode.get(), orthoUnitSquare(kWidth, kHeight));
    double largest = 0;
    for (int y = 0; y < kHeight; ++y)
        for (int x = 0; x < kWidth; ++x)
            largest = std::max(largest, double(pixel(*fmfImage, x, y, 0)));
    EXPECT_GT(largest, 0.0) << "the headlight lit nothing";
    EXPECT_LT(maxDifference(*streamedImage, *fmfImage), 1e-6);
}

}  // namespace

}  // namespace OSGBTF_TEST_FILE
