// BSVTF on the GPU (issue 13): a streamed fmf material from a tile set in a folder, drawn under a
// StreamingGroup whose feedback pass drives the tile cache. Every frame the render equals the CPU
// evaluation of what has arrived (StreamedFmfMaterial::snapshot); once converged with a cache that
// holds every finest tile it equals the fmf material itself; the feedback pass reports level
// L - k where 2^k texels fall in a pixel (seed 003 eq. 1).
#include <cmath>
#include <iostream>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <osg/Geode>
#include <osg/Uniform>

#include "harness/MaterialImage.h"
#include "materials/ShaderInterface.h"
#include "materials/fmf/Fmf.h"
#include "scene/MaterialNode.h"
#include "streaming/StreamingGroup.h"
#include "streaming/TileBuilder.h"
#include "tests/RandomFactors.h"
#include "tests/TestUtil.h"
#include "tests/gl/GlTestEnv.h"

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

/** The patch with the material's state, one light, a fixed view, tiled `repeats` times. */
osg::ref_ptr<osg::Geode> patch(const Material& material, const glm::vec3& view,
                               const glm::vec3& light, float repeats = 1.0f) {
    osg::ref_ptr<osg::StateSet> stateSet = material.createStateSet();
    stateSet->addUniform(new osg::Uniform(shader::kTextureScale, repeats));
    // BSVTF's tile cache reads the nearest texel; the fmf material it must converge to is read the
    // same way here. Filtered, a pixel centre on a texel centre would still blend in rounding
    // shares (~1e-6) of the neighbours: the interpolated coordinate is not exact.
    stateSet->addUniform(new osg::Uniform(shader::kBilinear, false));
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
    // Every finest tile resident (their parents covered and removed): 15 per group.
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
    streamedNode->addChild(rectifiedPatch().get());
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
    // The nearest texel, as BSVTF's tile cache reads it (see patch()).
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
