// Scenes with osgBTF::MaterialNode read through osgDB and rendered headless: the material region
// matches the CPU evaluator under four lights placed in different ways, an osgconv round trip
// renders the same, and bad materials or shaders leave the rest of the scene rendering.
// Built twice (EGL and OSMesa) like every GL test.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <sstream>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/LightSource>
#include <osg/MatrixTransform>
#include <osg/Notify>
#include <osgDB/ReadFile>
#include <osgDB/Registry>
#include <osgDB/WriteFile>
#include <osgViewer/Viewer>

#include "core/Directions.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodOptions.h"
#include "materials/pca/Pca.h"
#include "scene/MaterialNode.h"
#include "tests/NotifyCapture.h"
#include "tests/TestUtil.h"
#include "tests/gl/GlTestEnv.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using namespace osgBTF::test;

namespace {

constexpr int kImageSize = 96;
constexpr double kHalfExtent = 0.8;  // ortho window, around the patch centre

/** A fresh folder, removed at the end of the test. */
struct ScratchDir {
    fs::path path;
    ScratchDir() {
        std::random_device random;
        path = fs::temp_directory_path() / ("osgbtf-scene-" + std::to_string(random()));
        fs::create_directories(path);
    }
    ~ScratchDir() {
        std::error_code ignored;
        fs::remove_all(path, ignored);
    }
    std::string file(const std::string& name) const { return (path / name).string(); }
};

void usePluginsFromBuild() {
    static const bool done = [] {
        const std::string dir = buildDir() + "/lib";
        setenv("OSG_LIBRARY_PATH", dir.c_str(), 0);
        osgDB::FilePathList& paths = osgDB::Registry::instance()->getLibraryFilePathList();
        if (std::find(paths.begin(), paths.end(), dir) == paths.end()) paths.push_front(dir);
        return true;
    }();
    (void)done;
}

osg::ref_ptr<PcaMaterial> fitSample() {
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;  // not square: catches swapped axes
    return PcaMaterial::fit(makeSampleBtf(sample), FitOptions::parse("components=4 storage=float"));
}

/** The unit patch (0,0)-(1,1) at z = 0, normal +Z, s along +X, no tangents (the node adds
 *  them). */
osg::ref_ptr<osg::Geode> patch() {
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(createFullScreenQuadGeometry().get());
    return geode;
}

/** A fixed-colour square outside the materials, at x in [-0.45, -0.05]: the "rest of the
 *  scene". */
osg::ref_ptr<osg::Geode> coloredSquare(const osg::Vec3& rgb) {
    osg::ref_ptr<osg::StateSet> state =
        programStateSet("", "#version 330 compatibility\nvoid main() { gl_FragColor = vec4(" +
                                std::to_string(rgb.x()) + ", " + std::to_string(rgb.y()) + ", " +
                                std::to_string(rgb.z()) + ", 1.0); }\n");
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    osg::ref_ptr<osg::Geometry> quad = createFullScreenQuadGeometry();
    osg::ref_ptr<osg::Vec3Array> corners = new osg::Vec3Array;
    for (const osg::Vec3& v : *static_cast<osg::Vec3Array*>(quad->getVertexArray()))
        corners->push_back(osg::Vec3(-0.45f + 0.4f * v.x(), v.y(), 0));
    quad->setVertexArray(corners.get());
    geode->addDrawable(quad.get());
    geode->setStateSet(state.get());
    return geode;
}

/** One light as the test places it and as it should reach the shader, in world space. */
struct WorldLight {
    osg::Vec4d position;  // w = 0 direction toward the light, w = 1 point
    osg::Vec3 color;
};

osg::ref_ptr<osg::LightSource> lightSource(int number, const osg::Vec4& position,
                                           const osg::Vec3& color) {
    osg::ref_ptr<osg::Light> light = new osg::Light(number);
    light->setPosition(position);
    light->setDiffuse(osg::Vec4(color, 1));
    osg::ref_ptr<osg::LightSource> source = new osg::LightSource;
    source->setLight(light.get());
    return source;
}

using Camera = PatchView;

Camera cameraFrom(float thetaDeg, float phiDeg) {
    return patchViewFrom(thetaDeg, phiDeg, kImageSize, kHalfExtent);
}

/** The scene of the main test: four lights (directional at the root, directional under a
 *  rotation, point under a translation, directional in eye space), a MaterialNode naming the
 *  material file with the patch below it, and a coloured square outside it. */
struct LitScene {
    osg::ref_ptr<osg::Group> root;
    std::vector<WorldLight> lights;  // for the camera of cameraFrom(...) used with it
};

LitScene litScene(osg::Node* materialSubgraph, const Camera& camera) {
    LitScene scene;
    scene.root = new osg::Group;
    const osg::Vec3 colors[4] = {
        {0.9f, 0.8f, 0.7f}, {0.3f, 0.5f, 0.9f}, {0.7f, 0.7f, 0.2f}, {0.2f, 0.5f, 0.4f}};
    // 0: directional, at the root.
    const osg::Vec4 d0(0.3f, -0.4f, 0.87f, 0);
    scene.root->addChild(lightSource(0, d0, colors[0]).get());
    scene.lights.push_back({osg::Vec4d(d0), colors[0]});
    // 1: directional, under a rotation of 100 degrees about Z.
    const osg::Matrixd rotation = osg::Matrixd::rotate(osg::DegreesToRadians(100.0), 0, 0, 1);
    osg::ref_ptr<osg::MatrixTransform> rotate = new osg::MatrixTransform(rotation);
    const osg::Vec4 d1(0.8f, 0.0f, 0.6f, 0);
    rotate->addChild(lightSource(1, d1, colors[1]).get());
    scene.root->addChild(rotate.get());
    scene.lights.push_back(
        {osg::Vec4d(osg::Matrixd::transform3x3(osg::Vec3d(d1.x(), d1.y(), d1.z()), rotation), 0),
         colors[1]});
    // 2: point light, under a translation.
    const osg::Vec3d at(0.2, 0.9, 0.8);
    osg::ref_ptr<osg::MatrixTransform> translate =
        new osg::MatrixTransform(osg::Matrixd::translate(at));
    translate->addChild(lightSource(2, osg::Vec4(0, 0, 0, 1), colors[2]).get());
    scene.root->addChild(translate.get());
    scene.lights.push_back({osg::Vec4d(at, 1), colors[2]});
    // 3: directional, ABSOLUTE_RF: given in eye space, it turns with the camera.
    const osg::Vec3d eyeDirection(0.0, 0.4, 0.9);
    osg::ref_ptr<osg::LightSource> headlight =
        lightSource(3, osg::Vec4(osg::Vec3(eyeDirection), 0), colors[3]);
    headlight->setReferenceFrame(osg::LightSource::ABSOLUTE_RF);
    scene.root->addChild(headlight.get());
    const osg::Matrixd eyeToWorld = osg::Matrixd::inverse(camera.setup.view);
    scene.lights.push_back(
        {osg::Vec4d(osg::Matrixd::transform3x3(eyeDirection, eyeToWorld), 0), colors[3]});

    scene.root->addChild(materialSubgraph);
    scene.root->addChild(coloredSquare(osg::Vec3(0.25f, 0.5f, 0.75f)).get());
    return scene;
}

/** Where pixel (i, j) looks at the z = 0 plane, in world (= patch) coordinates. */
osg::Vec3d surfacePoint(const Camera& camera, int i, int j) {
    const double ex = -kHalfExtent + (i + 0.5) / kImageSize * 2 * kHalfExtent;
    const double ey = -kHalfExtent + (j + 0.5) / kImageSize * 2 * kHalfExtent;
    const osg::Vec3d origin = osg::Vec3d(ex, ey, 0) * osg::Matrixd::inverse(camera.setup.view);
    const osg::Vec3d v(camera.toEye.x, camera.toEye.y, camera.toEye.z);
    return origin - v * (origin.z() / v.z());
}

struct Comparison {
    int compared = 0;
    double worst = 0;
    std::string where;
};

/** Compares the pixels of the patch whose centre is well inside a texel with the CPU evaluator
 *  summed over the lights (the patch's frame is the world frame: tangent +X, normal +Z). */
Comparison compareWithCpu(const osg::Image& image, const Material& material, const Camera& camera,
                          const std::vector<WorldLight>& lights, double textureScale = 1.0) {
    Comparison result;
    for (int j = 0; j < kImageSize; j += 3)
        for (int i = 0; i < kImageSize; i += 3) {
            const osg::Vec3d p = surfacePoint(camera, i, j);
            if (p.x() <= 0 || p.x() >= 1 || p.y() <= 0 || p.y() >= 1) continue;
            const double s = p.x() * textureScale, t = p.y() * textureScale;
            const double fs = (s - std::floor(s)) * material.width();
            const double ft = (t - std::floor(t)) * material.height();
            const double edge = 0.2;
            if (fs - std::floor(fs) < edge || std::ceil(fs) - fs < edge ||
                ft - std::floor(ft) < edge || std::ceil(ft) - ft < edge)
                continue;
            glm::vec3 expected(0.0f);
            for (const WorldLight& light : lights) {
                osg::Vec3d toLight(light.position.x(), light.position.y(), light.position.z());
                if (light.position.w() != 0) toLight -= p;
                toLight.normalize();
                const glm::vec3 l(toLight.x(), toLight.y(), toLight.z());
                if (l.z <= 0) continue;
                // Filtered: the texels around the pixel's coordinate, blended.
                const glm::vec3 value =
                    material.evaluateFiltered(float(s), float(t), 0.0f, camera.toEye, l);
                expected += glm::vec3(light.color.x(), light.color.y(), light.color.z()) * value;
            }
            for (int c = 0; c < 3; ++c) {
                const double d = std::abs(double(pixel(image, i, j, c)) - expected[c]);
                if (!(d <= result.worst)) {
                    result.worst = std::isnan(d) ? 1e30 : d;
                    std::ostringstream where;
                    where << "pixel (" << i << ", " << j << ") texel (" << int(fs) << ", "
                          << int(ft) << ") channel " << c << ": GPU " << pixel(image, i, j, c)
                          << " CPU " << expected[c];
                    result.where = where.str();
                }
            }
            ++result.compared;
        }
    return result;
}

/** A pixel of the coloured square (x = -0.25, y = 0.5 on the z = 0 plane). */
osg::Vec3 squarePixel(const osg::Image& image, const Camera& camera) {
    for (int j = 0; j < kImageSize; ++j)
        for (int i = 0; i < kImageSize; ++i) {
            const osg::Vec3d p = surfacePoint(camera, i, j);
            if (std::abs(p.x() + 0.25) < 0.05 && std::abs(p.y() - 0.5) < 0.05)
                return osg::Vec3(pixel(image, i, j, 0), pixel(image, i, j, 1),
                                 pixel(image, i, j, 2));
        }
    return osg::Vec3(-1, -1, -1);
}

osg::ref_ptr<MaterialNode> materialNodeNaming(const std::string& file) {
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->setMaterialFile(file);
    node->addChild(patch().get());
    return node;
}

}  // namespace

// ---- failure cases first ---------------------------------------------------------------------

TEST(SceneRender, BadMaterialsWarnAndTheRestOfTheSceneRenders) {
    usePluginsFromBuild();
    ScratchDir dir;
    FittedMaterial odd = fitSample()->toFittedMaterial();
    odd.method = "mystery";
    saveFittedMaterial(odd, dir.file("mystery.btfmat"));
    const Camera camera = cameraFrom(20, 30);
    osg::ref_ptr<osg::Group> group = new osg::Group;
    {
        ScopedNotifyCapture quiet(true);
        group->addChild(materialNodeNaming("missing.btfmat").get());
        group->addChild(materialNodeNaming(dir.file("mystery.btfmat")).get());
    }
    LitScene scene = litScene(group.get(), camera);
    ASSERT_TRUE(osgDB::writeNodeFile(*scene.root, dir.file("bad.osgt")));

    ScopedNotifyCapture capture(true);
    osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(dir.file("bad.osgt"));
    ASSERT_TRUE(read.valid());
    EXPECT_NE(capture.text().find("osgBTF::MaterialNode: missing.btfmat: no such file"),
              std::string::npos)
        << capture.text();
    EXPECT_NE(capture.text().find("osgBTF::MaterialNode: " + dir.file("mystery.btfmat") +
                                  ": unknown method 'mystery'"),
              std::string::npos)
        << capture.text();
    osg::ref_ptr<osg::Image> image = sharedRenderer().render(read.get(), camera.setup);
    const osg::Vec3 square = squarePixel(*image, camera);
    EXPECT_NEAR(square.x(), 0.25f, 1e-3);
    EXPECT_NEAR(square.y(), 0.5f, 1e-3);
    EXPECT_NEAR(square.z(), 0.75f, 1e-3);
}

TEST(SceneRender, ShaderThatFailsToCompileIsReportedByFileAndTheRestRenders) {
    usePluginsFromBuild();
    ScratchDir dir;
    fs::create_directories(dir.path / "shaders");
    const std::string broken = dir.file("shaders/pca.frag");
    {
        FILE* out = std::fopen(broken.c_str(), "w");
        ASSERT_NE(out, nullptr);
        std::fputs("#version 330 compatibility\nthis is not GLSL;\n", out);
        std::fclose(out);
    }
    osgDB::FilePathList& data = osgDB::Registry::instance()->getDataFilePathList();
    data.push_front(dir.path.string());
    osg::ref_ptr<PcaMaterial> material = fitSample();
    const osg::Program* program = dynamic_cast<const osg::Program*>(
        material->sharedStateSet()->getAttribute(osg::StateAttribute::PROGRAM));
    data.pop_front();
    ASSERT_NE(program, nullptr);
    if (program->getShader(1)->getName() != broken)
        GTEST_SKIP() << "the pca program was built before the override (run this test alone)";

    const Camera camera = cameraFrom(20, 30);
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
    node->addChild(patch().get());
    LitScene scene = litScene(node.get(), camera);
    ScopedNotifyCapture capture(true);
    osg::ref_ptr<osg::Image> image = sharedRenderer().render(scene.root.get(), camera.setup);
    EXPECT_NE(capture.text().find("glCompileShader \"" + broken + "\" FAILED"), std::string::npos)
        << capture.text();
    const osg::Vec3 square = squarePixel(*image, camera);
    EXPECT_NEAR(square.x(), 0.25f, 1e-3);
    EXPECT_NEAR(square.z(), 0.75f, 1e-3);
}

// ---- what works ------------------------------------------------------------------------------

TEST(SceneRender, SceneReadThroughOsgDBMatchesTheCpuUnderFourLights) {
    usePluginsFromBuild();
    ScratchDir dir;
    osg::ref_ptr<PcaMaterial> material = fitSample();
    saveMaterial(*material, dir.file("wool.btfmat"));
    for (const auto& [theta, phi] : {std::pair{30.0f, 40.0f}, std::pair{55.0f, 200.0f}}) {
        const Camera camera = cameraFrom(theta, phi);
        LitScene scene = litScene(materialNodeNaming(dir.file("wool.btfmat")).get(), camera);
        ASSERT_TRUE(osgDB::writeNodeFile(*scene.root, dir.file("scene.osgt")));
        osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(dir.file("scene.osgt"));
        ASSERT_TRUE(read.valid());
        osg::ref_ptr<osg::Image> image = sharedRenderer().render(read.get(), camera.setup);

        const Comparison r = compareWithCpu(*image, *material, camera, scene.lights);
        EXPECT_GT(r.compared, 60);
        EXPECT_LE(r.worst, 4e-3) << "view " << theta << "/" << phi << ": " << r.where;
        // Non-trivial: the material region is neither black nor uniform.
        float lo = 1e9f, hi = -1e9f;
        for (int j = 0; j < kImageSize; ++j)
            for (int i = 0; i < kImageSize; ++i) {
                const osg::Vec3d p = surfacePoint(camera, i, j);
                if (p.x() <= 0.05 || p.x() >= 0.95 || p.y() <= 0.05 || p.y() >= 0.95) continue;
                lo = std::min(lo, pixel(*image, i, j, 1));
                hi = std::max(hi, pixel(*image, i, j, 1));
            }
        EXPECT_GT(lo, 0.0f);
        EXPECT_GT(hi - lo, 0.02f);
        const osg::Vec3 square = squarePixel(*image, camera);
        EXPECT_NEAR(square.y(), 0.5f, 1e-3);
    }
}

TEST(SceneRender, PseudoLoaderAndOsgconvRoundTripRenderTheSame) {
    usePluginsFromBuild();
    ScratchDir dir;
    osg::ref_ptr<PcaMaterial> material = fitSample();
    saveMaterial(*material, dir.file("wool.btfmat"));
    ASSERT_TRUE(osgDB::writeNodeFile(*patch(), dir.file("patch.osgt")));
    const Camera camera = cameraFrom(35, 120);

    // The material subgraph from the pseudo-loader, found as a plugin on OSG_LIBRARY_PATH.
    osg::ref_ptr<osg::Node> subgraph = osgDB::readRefNodeFile(
        dir.file("patch.osgt") + ".(" + dir.file("wool.btfmat") + ",scale=2).btfmaterial");
    ASSERT_TRUE(subgraph.valid());
    LitScene scene = litScene(subgraph.get(), camera);
    osg::ref_ptr<osg::Image> before = sharedRenderer().render(scene.root.get(), camera.setup);
    const Comparison r = compareWithCpu(*before, *material, camera, scene.lights, 2.0);
    EXPECT_GT(r.compared, 40);
    EXPECT_LE(r.worst, 4e-3) << r.where;

    ASSERT_TRUE(osgDB::writeNodeFile(*scene.root, dir.file("scene.osgt")));
    const std::string command = "OSG_LIBRARY_PATH=" + buildDir() + "/lib osgconv " +
                                dir.file("scene.osgt") + " " + dir.file("converted.osgb") + " > " +
                                dir.file("osgconv.log") + " 2>&1";
    ASSERT_EQ(std::system(command.c_str()), 0) << command;
    osg::ref_ptr<osg::Node> converted = osgDB::readRefNodeFile(dir.file("converted.osgb"));
    ASSERT_TRUE(converted.valid());
    osg::ref_ptr<osg::Image> after = sharedRenderer().render(converted.get(), camera.setup);
    // The same up to float rounding: .osgt text does not keep every bit of a float (re-reading
    // scene.osgt without osgconv differs as much), and the exact direction interpolation is
    // continuous, so a last-bit change of a frame or light vector moves a pixel by ~1e-7 where
    // the old nearest-cell table hid it.
    EXPECT_LE(maxDifference(*before, *after), 1e-6);
}

TEST(SceneRender, WithoutLightSourcesTheViewersHeadlightLights) {
    osg::ref_ptr<PcaMaterial> material = fitSample();
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
    node->addChild(patch().get());
    const Camera camera = cameraFrom(40, 250);
    // osgViewer's default: HEADLIGHT, a directional light along the view, diffuse 0.8.
    const osg::Light* headlight = sharedRenderer().viewer().getLight();
    ASSERT_NE(headlight, nullptr);
    ASSERT_EQ(sharedRenderer().viewer().getLightingMode(), osg::View::HEADLIGHT);
    const osg::Vec4 diffuse = headlight->getDiffuse();
    const std::vector<WorldLight> lights = {
        {osg::Vec4d(camera.toEye.x, camera.toEye.y, camera.toEye.z, 0),
         osg::Vec3(diffuse.r(), diffuse.g(), diffuse.b())}};
    osg::ref_ptr<osg::Image> image = sharedRenderer().render(node.get(), camera.setup);
    const Comparison r = compareWithCpu(*image, *material, camera, lights);
    EXPECT_GT(r.compared, 60);
    EXPECT_LE(r.worst, 2e-3) << r.where;
}

}  // namespace OSGBTF_TEST_FILE
