// Zero OpenGL errors: every example scene btf-examples writes, as read back
// through osgDB, alone and lit by an environment as `btfviewer --env` lights it; every registered
// method on its sphere scene (plain, lit by an environment, under a ShadowMap, through a
// coordinate map, mip-mapped, without texture storage, in the texture objects OSG recycles from
// a deleted material); a streamed material. OSG checks for a GL error after every attribute it
// applies and after every object its compile pass builds (osgUtil::GLObjectsVisitor, which a
// viewer runs before its first frame: draws happen there too, osgText's among them), and any
// error it reports fails the test. Built twice (EGL and OSMesa) like every GL test.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <memory>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <osg/Drawable>
#include <osg/GLExtensions>
#include <osg/Geode>
#include <osg/Group>
#include <osg/Notify>
#include <osg/State>
#include <osgDB/ReadFile>
#include <osgShadow/ShadowMap>
#include <osgShadow/ShadowedScene>
#include <osgText/TextBase>
#include <osgViewer/Renderer>

#include "environment/EnvironmentLitGroup.h"
#include "fit/MipMapping.h"
#include "harness/sample/BlockMap.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "materials/fmf/Fmf.h"
#include "scene/EnvironmentLight.h"
#include "scene/MaterialNode.h"
#include "streaming/StreamingGroup.h"
#include "streaming/TileBuilder.h"
#include "tests/NotifyCapture.h"
#include "tests/PluginTestUtil.h"
#include "tests/RandomFactors.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"
#include "tests/gl/GlErrorWatch.h"
#include "tests/gl/GlTestEnv.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

constexpr int kImageSize = 64;

/** A perspective camera (30 degrees) from the front (-Y) and above, the node's bound filling the
 *  view: roughly a viewer's home view. */
CameraSetup cameraOnto(osg::Node& node) {
    const osg::BoundingSphere bound = node.getBound();
    const double radius = bound.valid() && bound.radius() > 0 ? bound.radius() : 1.0;
    const osg::Vec3d centre = bound.valid() ? osg::Vec3d(bound.center()) : osg::Vec3d();
    const double distance = radius / std::sin(osg::DegreesToRadians(15.0));
    osg::Vec3d toEye(0.0, -1.0, 0.45);
    toEye.normalize();
    CameraSetup setup;
    setup.view = osg::Matrixd::lookAt(centre + toEye * distance, centre, osg::Vec3d(0, 0, 1));
    setup.projection = osg::Matrixd::perspective(
        30.0, 1.0, std::max(0.01 * distance, distance - 1.1 * radius), distance + 1.1 * radius);
    setup.width = setup.height = kImageSize;
    return setup;
}

/** Renders `frames` frames of `scene`, the first one after osgViewer's compile pass as a
 *  viewer's first frame of a scene; returns the last one. */
osg::ref_ptr<osg::Image> drawFrames(osg::Node* scene, int frames = 2) {
    HeadlessRenderer& renderer = sharedRenderer();
    renderer.setScene(scene);
    renderer.setCamera(cameraOnto(*scene));
    auto* viewerRenderer = dynamic_cast<osgViewer::Renderer*>(renderer.camera().getRenderer());
    if (viewerRenderer) viewerRenderer->setCompileOnNextDraw(true);
    osg::ref_ptr<osg::Image> image;
    for (int i = 0; i < frames; ++i) image = renderer.render();
    renderer.setScene(nullptr);
    return image;
}

/** Pixels something was drawn on (the clear colour is transparent black). */
int drawnPixels(const osg::Image& image) {
    int drawn = 0;
    for (int y = 0; y < image.t(); ++y)
        for (int x = 0; x < image.s(); ++x) drawn += pixel(image, x, y, 3) > 0.0f;
    return drawn;
}

/** btf-examples' output (an 8 x 8 sample; lambert, then pca), written once per process. */
const TempDir& examples() {
    static const TempDir dir;
    static const bool written = [] {
        const CommandResult result =
            runCommand(shellQuote(builtTool("btf-examples")) + " --out " + shellQuote(dir.path()) +
                       " --size 8 --methods lambert,pca --no-progress");
        if (result.exitCode != 0) throw std::runtime_error("btf-examples failed: " + result.output);
        return true;
    }();
    (void)written;
    return dir;
}

const std::vector<std::string> kExampleScenes = {"vase.osgt",          "spheres.osgt",
                                                 "cloth.osgt",         "vases.osgt",
                                                 "cloth-shadows.osgt", "cloth-sky.osgt"};

osg::ref_ptr<osg::Node> readExampleScene(const std::string& name) {
    usePluginsFromBuild();
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options;
    options->getDatabasePathList().push_back(examples().path().string());
    osg::ref_ptr<osg::Node> scene = osgDB::readRefNodeFile(examples().file(name), options.get());
    if (!scene) throw std::runtime_error(name + ": osgDB could not read it");
    return scene;
}

template <class T>
struct Collector : osg::NodeVisitor {
    Collector() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
    void apply(osg::Group& group) override {
        if (auto* found = dynamic_cast<T*>(&group)) nodes.push_back(found);
        traverse(group);
    }
    std::vector<osg::ref_ptr<T>> nodes;
};

template <class T>
std::vector<osg::ref_ptr<T>> collect(osg::Node& node) {
    Collector<T> collector;
    node.accept(collector);
    return collector.nodes;
}

/** spheres.osgt with `material` on every node, as btfviewer's material keys put it. */
osg::ref_ptr<osg::Node> spheresWith(Material* material) {
    osg::ref_ptr<osg::Node> scene = readExampleScene("spheres.osgt");
    for (const auto& node : collect<MaterialNode>(*scene)) node->setMaterial(material);
    return scene;
}

/** Computes the lighting of every EnvironmentLitGroup below `scene` and installs it, as
 *  btfviewer's --frames runs do before their first frame. 64 columns instead of 128: the same GL
 *  calls, a little less work (the horizon is resolved as finely whatever the width). */
void finishEnvironmentLighting(osg::Node& scene) {
    for (const auto& group : collect<EnvironmentLitGroup>(scene)) {
        if (group->getLight()) group->getLight()->setProjectionWidth(64);
        group->finish();
        if (!group->getError().empty()) throw std::runtime_error(group->getError());
    }
}

/** `scene` under an EnvironmentLitGroup lit by the examples' sky, as `btfviewer --env` puts it. */
osg::ref_ptr<osg::Group> litBySky(osg::Node* scene) {
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    light->setFile(examples().file("sky.hdr"));
    if (!light->hasMap()) throw std::runtime_error(light->getError());
    osg::ref_ptr<EnvironmentLitGroup> group = new EnvironmentLitGroup;
    group->setLight(light.get());
    group->addChild(scene);
    finishEnvironmentLighting(*group);
    return group;
}

/** `scene` in an osgShadow::ShadowedScene with a ShadowMap, as `btfviewer --shadows` puts it. */
osg::ref_ptr<osg::Group> underShadowMap(osg::Node* scene) {
    osg::ref_ptr<osgShadow::ShadowedScene> shadowed = new osgShadow::ShadowedScene;
    osg::ref_ptr<osgShadow::ShadowMap> technique = new osgShadow::ShadowMap;
    technique->setTextureSize(osg::Vec2s(256, 256));
    shadowed->setShadowTechnique(technique.get());
    shadowed->addChild(scene);
    return shadowed;
}

/** "lpca-revised" -> "lpca_revised", "cloth-sky.osgt" -> "cloth_sky". */
std::string testName(const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param.substr(0, info.param.find('.'));
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

}  // namespace

// The watch itself: a GL error made while drawing is reported.
TEST(GlErrors, TheWatchReportsAGlErrorMadeWhileDrawing) {
    struct InvalidEnum : osg::Drawable::DrawCallback {
        void drawImplementation(osg::RenderInfo& info,
                                const osg::Drawable* drawable) const override {
            glEnable(GL_RGBA);  // not a capability
            drawable->drawImplementation(info);
        }
    };
    osg::ref_ptr<osg::Geode> quad = createFullScreenQuad();
    quad->getDrawable(0)->setDrawCallback(new InvalidEnum);
    GlErrorWatch watch;
    drawFrames(quad.get(), 1);
    EXPECT_NE(watch.take(), "");
    EXPECT_EQ(watch.take(), "") << "take() empties the report";
}

// btfviewer --env on spheres.osgt reported "invalid operation after compileGLObjects": the
// compile pass drew the second label with the pca object's environment program current, which
// then had only its own uniforms, so all its samplers read unit 0 (two sampler types on one unit
// make a draw invalid).
TEST(GlErrors, APcaObjectAfterALambertOneLitByAnEnvironmentCompilesWithoutAGlError) {
    GlErrorWatch watch;
    osg::ref_ptr<osg::Node> spheres = readExampleScene("spheres.osgt");
    const auto nodes = collect<MaterialNode>(*spheres);
    ASSERT_EQ(nodes.size(), 2u);
    ASSERT_EQ(nodes[0]->getMaterial()->methodName(), "lambert");
    ASSERT_EQ(nodes[1]->getMaterial()->methodName(), "pca");
    EXPECT_GT(drawnPixels(*drawFrames(litBySky(spheres.get()).get())), 0);
    EXPECT_EQ(watch.take(), "");
}

namespace {

/** `method` fitted on `sample` with its quick test options. */
osg::ref_ptr<Material> quickFit(const std::string& method, const MeasuredBtf& sample) {
    const MethodInfo& info = findMethod(method);
    return info.fit(sample, FitOptions::parse(info.quickFitOptions));
}

}  // namespace

// OSG gives the texture objects of a deleted texture to the next one of the same size and format,
// storage and all (OSG 3.6.5 then specified a texture array's immutable storage again).
TEST(GlErrors, EveryMethodDrawsTheSameInTheTexturesOfADeletedEqualMaterialWithoutAGlError) {
    const MeasuredBtf sample = smallSampleBtf(8);
    GlErrorWatch watch;
    for (const std::string& name : methodNames()) {
        SCOPED_TRACE(name);
        // The scene and its material are deleted after each draw.
        const osg::ref_ptr<osg::Image> first =
            drawFrames(spheresWith(quickFit(name, sample).get()).get());
        const osg::ref_ptr<osg::Image> second =
            drawFrames(spheresWith(quickFit(name, sample).get()).get());
        EXPECT_EQ(watch.take(), "");
        EXPECT_GT(drawnPixels(*second), 0);
        EXPECT_EQ(maxDifference(*first, *second), 0.0);
    }
}

// A context closed after its scene was taken out (as HeadlessRenderer does after every render)
// released nothing of the process-wide method programs, which then still held its program
// objects; the next context given the same context ID drew with those dead objects
// (GL_INVALID_VALUE at every draw): `btf-examples --gallery`, rendering after `btf compare`'s
// renderer had closed. A context of its own per round: the second gets the first one's ID.
TEST(GlErrors, EveryMethodDrawsTheSameInAContextOpenedAfterAnotherClosed) {
    const MeasuredBtf sample = smallSampleBtf(8);
    std::vector<osg::ref_ptr<osg::Node>> scenes;
    for (const std::string& name : methodNames()) {
        // Without the labels: osgText's glyph textures are not osgBTF's to release.
        osg::ref_ptr<osg::Node> scene = spheresWith(quickFit(name, sample).get());
        for (const auto& geode : collect<osg::Geode>(*scene))
            for (unsigned i = geode->getNumDrawables(); i-- > 0;)
                if (dynamic_cast<osgText::TextBase*>(geode->getDrawable(i)))
                    geode->removeDrawables(i, 1);
        scenes.push_back(scene);
    }
    GlErrorWatch watch;
    std::vector<osg::ref_ptr<osg::Image>> rounds[2];
    unsigned contextIds[2] = {0, 0};
    for (int round = 0; round < 2; ++round) {
        HeadlessRenderer renderer(sharedRenderer().backend());
        renderer.context().getState()->setCheckForGLErrors(osg::State::ONCE_PER_ATTRIBUTE);
        contextIds[round] = renderer.context().getState()->getContextID();
        for (const osg::ref_ptr<osg::Node>& scene : scenes) {
            renderer.setScene(scene.get());
            renderer.setCamera(cameraOnto(*scene));
            renderer.render();
            rounds[round].push_back(renderer.render());
            renderer.setScene(nullptr);
        }
    }
    ASSERT_EQ(contextIds[0], contextIds[1]) << "the second context did not reuse the first's ID";
    EXPECT_EQ(watch.take(), "");
    const std::vector<std::string> names = methodNames();
    for (std::size_t i = 0; i < names.size(); ++i) {
        SCOPED_TRACE(names[i]);
        EXPECT_GT(drawnPixels(*rounds[1][i]), 0);
        EXPECT_EQ(maxDifference(*rounds[0][i], *rounds[1][i]), 0.0);
    }
}

// Without texture storage (GL before 4.2 without ARB_texture_storage, or
// OSG_GL_TEXTURE_STORAGE=OFF) OSG allocates a texture by glTexImage* with no data in the texture's
// source format.
TEST(GlErrors, EveryMethodDrawsTheSameWithoutTextureStorageAndWithoutAGlError) {
    osg::GLExtensions* extensions = sharedState().get<osg::GLExtensions>();
    ASSERT_TRUE(extensions);
    struct Restore {
        osg::GLExtensions* extensions;
        bool enabled;
        ~Restore() { extensions->isTextureStorageEnabled = enabled; }
    } restore{extensions, extensions->isTextureStorageEnabled};
    const MeasuredBtf sample = smallSampleBtf(8);
    GlErrorWatch watch;
    for (const std::string& name : methodNames()) {
        SCOPED_TRACE(name);
        // Two materials, both alive: a texture is allocated once per context, and the texture
        // objects of a deleted one would be taken over allocated.
        const osg::ref_ptr<Material> first = quickFit(name, sample);
        const osg::ref_ptr<Material> second = quickFit(name, sample);
        extensions->isTextureStorageEnabled = restore.enabled;
        const osg::ref_ptr<osg::Image> stored = drawFrames(spheresWith(first.get()).get());
        extensions->isTextureStorageEnabled = false;
        const osg::ref_ptr<osg::Image> plain = drawFrames(spheresWith(second.get()).get());
        EXPECT_EQ(watch.take(), "");
        EXPECT_GT(drawnPixels(*plain), 0);
        EXPECT_EQ(maxDifference(*stored, *plain), 0.0);
    }
}

TEST(GlErrors, EveryExampleSceneDrawsWithoutAGlError) {
    std::vector<std::string> written;
    for (const auto& entry : std::filesystem::directory_iterator(examples().path()))
        if (entry.path().extension() == ".osgt")
            written.push_back(entry.path().filename().string());
    std::sort(written.begin(), written.end());
    std::vector<std::string> listed = kExampleScenes;
    std::sort(listed.begin(), listed.end());
    // The environment-lit tests below take their scenes from the list.
    EXPECT_EQ(written, listed) << "btf-examples writes other scenes than kExampleScenes lists";
    GlErrorWatch watch;
    for (const std::string& name : written) {
        SCOPED_TRACE(name);
        osg::ref_ptr<osg::Node> scene = readExampleScene(name);
        finishEnvironmentLighting(*scene);  // cloth-sky.osgt's own group
        EXPECT_GT(drawnPixels(*drawFrames(scene.get())), 0);
        EXPECT_EQ(watch.take(), "");
    }
}

// Disabled until createCoordinateMapStateSet (materials/CoordinateMapRendering.cpp) gives the map
// program's other samplers their units with addSamplerUnits, as environmentStateSet does: the map
// StateSet holds the map program and the map's sampler alone, and the compile pass draws the
// second label with the pca node's map program current (a map StateSet is shared per method).
TEST(GlErrors, ObjectsOfTwoMethodsThroughACoordinateMapCompileWithoutAGlError) {
    osg::ref_ptr<osg::Node> spheres = readExampleScene("spheres.osgt");
    const auto map =
        std::make_shared<const CoordinateMap>(makeBlockCoordinateMap(16, 16, 8, 8, 2, 7));
    for (const auto& node : collect<MaterialNode>(*spheres))
        EXPECT_TRUE(node->setCoordinateMap(map)) << node->getCoordinateMapError();
    GlErrorWatch watch;
    EXPECT_GT(drawnPixels(*drawFrames(spheres.get())), 0);
    EXPECT_EQ(watch.take(), "");
}

class GlErrorsExampleScene : public ::testing::TestWithParam<std::string> {};

// As `btfviewer --env sky.hdr SCENE` lights it.
TEST_P(GlErrorsExampleScene, LitByAnEnvironmentDrawsWithoutAGlError) {
    GlErrorWatch watch;
    osg::ref_ptr<osg::Node> scene = readExampleScene(GetParam());
    EXPECT_GT(drawnPixels(*drawFrames(litBySky(scene.get()).get())), 0);
    EXPECT_EQ(watch.take(), "");
}

INSTANTIATE_TEST_SUITE_P(EveryExampleScene, GlErrorsExampleScene,
                         ::testing::ValuesIn(kExampleScenes), testName);

TEST(GlErrors, AStreamedMaterialOnTheSphereSceneDrawsWithoutAGlError) {
    TempDir tiles;
    TileBuildOptions build;
    build.codec = "raw";
    build.tileSize = 8;
    build.padding = 4;
    const osg::ref_ptr<FmfMaterial> fmf =
        FmfMaterial::fromFactors(randomFactors(FactorModel::Fmf, {4, 0, 0}, 16, 16, 3));
    buildTileSet(*fmf, tiles.file("tiles"), build);
    TileStreamerOptions streaming;
    streaming.tileSize = 8;
    streaming.padding = 4;
    streaming.cacheSize = 4 * (8 + 2 * 4);
    osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(streaming));
    const osg::ref_ptr<StreamedFmfMaterial> streamed = group->streamer()->open(tiles.file("tiles"));
    osg::ref_ptr<osg::Node> spheres = readExampleScene("spheres.osgt");
    for (const auto& node : collect<MaterialNode>(*spheres)) node->setMaterial(streamed.get());
    group->addChild(spheres.get());
    GlErrorWatch watch;
    // Frames until the tiles have arrived: uploads into the cache happen in between.
    EXPECT_GT(drawnPixels(*drawFrames(group.get(), 6)), 0);
    EXPECT_EQ(watch.take(), "");
}

class GlErrorsEveryMethod : public ::testing::TestWithParam<std::string> {};

// Every way a scene can draw the method's material.
TEST_P(GlErrorsEveryMethod,
       SphereSceneDrawsWithoutAGlErrorPlainLitShadowedThroughAMapAndMipMapped) {
    const MethodInfo& method = findMethod(GetParam());
    const MeasuredBtf sample = smallSampleBtf(8);
    const FitOptions options = FitOptions::parse(method.quickFitOptions);
    const osg::ref_ptr<Material> plain = method.fit(sample, options);
    const osg::ref_ptr<Material> mipMapped = fitMipMapped(method, sample, options);
    const auto map = std::make_shared<const CoordinateMap>(
        makeBlockCoordinateMap(16, 16, plain->width(), plain->height(), 2, 7));
    const auto throughTheMap = [&](osg::Node& scene) {
        for (const auto& node : collect<MaterialNode>(scene))
            EXPECT_TRUE(node->setCoordinateMap(map)) << node->getCoordinateMapError();
    };
    GlErrorWatch watch;
    const auto check = [&](const std::string& variant, osg::Node* scene) {
        SCOPED_TRACE(GetParam() + " " + variant);
        EXPECT_GT(drawnPixels(*drawFrames(scene)), 0);
        EXPECT_EQ(watch.take(), "");
    };
    // A scene is drawn again in other settings: its environment lighting stays valid as long as
    // its materials do, and computing it is what takes the time here.
    osg::ref_ptr<osg::Node> spheres = spheresWith(plain.get());
    check("plain", spheres.get());
    check("under a ShadowMap", underShadowMap(spheres.get()).get());
    throughTheMap(*spheres);
    check("through a coordinate map", spheres.get());
    check("through a coordinate map under a ShadowMap", underShadowMap(spheres.get()).get());

    osg::ref_ptr<osg::Node> lit = litBySky(spheresWith(plain.get()).get());
    check("lit by an environment", lit.get());
    check("lit by an environment under a ShadowMap", underShadowMap(lit.get()).get());
    throughTheMap(*lit);
    check("through a coordinate map lit by an environment", lit.get());

    osg::ref_ptr<osg::Node> mip = spheresWith(mipMapped.get());
    check("mip-mapped", mip.get());
    check("mip-mapped under a ShadowMap", underShadowMap(mip.get()).get());
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, GlErrorsEveryMethod, ::testing::ValuesIn(methodNames()),
                         testName);

}  // namespace OSGBTF_TEST_FILE
