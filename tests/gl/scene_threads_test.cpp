// MaterialNodes under osgViewer's CullThreadPerCameraDrawThreadPerContext model: two cameras on
// two headless contexts, so two cull threads traverse the same MaterialNodes (their per-camera
// light states) and two draw threads apply the shared material StateSets at once, while the main
// thread swaps materials and adds and removes MaterialNodes between frames, as an application's
// update does. The last frames (no more changes) must match what the same
// viewer draws single-threaded. Built twice (EGL and OSMesa) like every GL test.
#include <algorithm>
#include <cmath>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/global_control.h>

#include <osg/Geode>
#include <osg/LightSource>
#include <osg/MatrixTransform>
#include <osgViewer/Viewer>

#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "scene/MaterialNode.h"
#include "tests/gl/GlTestEnv.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

#if defined(__SANITIZE_THREAD__)
// As in tests/concurrency_test.cpp: Debian's TBB hands work between its threads in ways
// ThreadSanitizer does not see; one TBB thread leaves the races between OSG's threads to find.
const tbb::global_control oneTbbThread(tbb::global_control::max_allowed_parallelism, 1);
#endif

constexpr int kImageSize = 48;
constexpr int kQuadrants = 4;

struct Materials {
    osg::ref_ptr<Material> lambert, pca;
    Materials() {
        SampleOptions sample;
        sample.width = 8;
        sample.height = 6;
        const MeasuredBtf btf = makeSampleBtf(sample);
        lambert = findMethod("lambert").fit(btf, {});
        pca = findMethod("pca").fit(btf, FitOptions::parse("components=4 storage=float"));
    }
    Material* pick(int i) const { return i % 2 ? pca.get() : lambert.get(); }
};

/** A patch (the unit square) in quadrant `q` of the unit square, drawn with `material`. */
osg::ref_ptr<osg::Node> patchIn(int q, Material* material) {
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material);
    osg::ref_ptr<osg::Geode> patch = new osg::Geode;
    patch->addDrawable(createFullScreenQuadGeometry().get());
    node->addChild(patch.get());
    osg::ref_ptr<osg::MatrixTransform> place = new osg::MatrixTransform(
        osg::Matrix::scale(0.5, 0.5, 1) * osg::Matrix::translate(0.5 * (q % 2), 0.5 * (q / 2), 0));
    place->addChild(node.get());
    return place;
}

/** A light and four patches, quadrant q with material pick(q + shift). */
osg::ref_ptr<osg::Group> scene(const Materials& materials, int shift) {
    osg::ref_ptr<osg::Light> light = new osg::Light(0);
    const osg::Vec3 toLight =
        osg::Vec3(0.3f, -0.4f, 0.87f) / osg::Vec3(0.3f, -0.4f, 0.87f).length();
    light->setPosition(osg::Vec4(toLight, 0));
    light->setDiffuse(osg::Vec4(0.9f, 0.8f, 0.7f, 1));
    osg::ref_ptr<osg::LightSource> source = new osg::LightSource;
    source->setLight(light.get());
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->addChild(source.get());
    for (int q = 0; q < kQuadrants; ++q) root->addChild(patchIn(q, materials.pick(q + shift)));
    return root;
}

MaterialNode* materialNodeOf(osg::Group& root, int q) {
    auto* place = root.getChild(unsigned(q + 1))->asGroup();
    return dynamic_cast<MaterialNode*>(place->getChild(0));
}

struct Rendered {
    std::vector<osg::ref_ptr<osg::Image>> images;
};

/** Renders with two slave cameras on two contexts under `model`. `churn` frames first change the
 *  scene every frame (materials swapped on nodes, one patch replaced by a new node), then three
 *  frames of the final scene (shift 0) are drawn. */
Rendered render(osgViewer::ViewerBase::ThreadingModel model, int churn,
                const Materials& materials) {
    const PatchView view = patchViewFrom(35, 60, kImageSize, 0.8);
    osgViewer::Viewer viewer;
    viewer.setThreadingModel(model);
    viewer.setKeyEventSetsDone(0);
    viewer.setQuitEventSetsDone(false);
    osg::Camera* master = viewer.getCamera();
    master->setViewMatrix(view.setup.view);
    master->setProjectionMatrix(view.setup.projection);
    Rendered out;
    for (int c = 0; c < 2; ++c) {
        osg::ref_ptr<HeadlessContext> context =
            createHeadlessContext(glTestBackend(), kImageSize, kImageSize);
        osg::ref_ptr<osg::Camera> camera = new osg::Camera;
        camera->setGraphicsContext(context.get());
        camera->setViewport(0, 0, kImageSize, kImageSize);
        camera->setComputeNearFarMode(osg::CullSettings::DO_NOT_COMPUTE_NEAR_FAR);
        camera->setClearMask(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
        camera->setClearColor(osg::Vec4(0, 0, 0, 0));
        camera->setRenderTargetImplementation(osg::Camera::FRAME_BUFFER_OBJECT);
        osg::ref_ptr<osg::Image> image = new osg::Image;
        image->allocateImage(kImageSize, kImageSize, 1, GL_RGBA, GL_FLOAT);
        image->setInternalTextureFormat(GL_RGBA32F_ARB);
        camera->attach(osg::Camera::COLOR_BUFFER0, image.get());
        camera->attach(osg::Camera::DEPTH_BUFFER, GL_DEPTH_COMPONENT24);
        viewer.addSlave(camera.get(), osg::Matrixd(), osg::Matrixd(), true);
        out.images.push_back(image);
    }
    osg::ref_ptr<osg::Group> root = scene(materials, churn);
    viewer.setSceneData(root.get());
    viewer.realize();
    EXPECT_TRUE(viewer.isRealized());
    for (int frame = churn; frame > 0; --frame) {
        viewer.frame();
        // Between frames, as an update callback would: the draw threads may still be drawing
        // the previous frame.
        for (int q = 1; q < kQuadrants; ++q)
            materialNodeOf(*root, q)->setMaterial(materials.pick(q + frame - 1));
        root->replaceChild(root->getChild(1), patchIn(0, materials.pick(frame - 1)));
    }
    for (int frame = 0; frame < 3; ++frame) viewer.frame();
    viewer.stopThreading();  // the draw threads' last read-backs are complete
    return out;
}

int litPixels(const osg::Image& image) {
    int lit = 0;
    for (int y = 0; y < image.t(); ++y)
        for (int x = 0; x < image.s(); ++x) lit += pixel(image, x, y, 0) > 0.01f ? 1 : 0;
    return lit;
}

}  // namespace

TEST(SceneThreads, CullThreadPerCameraDrawThreadPerContextDrawsWhatOneThreadDraws) {
    const Materials materials;
    const Rendered reference = render(osgViewer::ViewerBase::SingleThreaded, 0, materials);
    const Rendered threaded =
        render(osgViewer::ViewerBase::CullThreadPerCameraDrawThreadPerContext, 40, materials);
    // The unit square seen 35 degrees off its normal covers cos(35) / 1.6^2 = 32 % of the
    // picture (orthographic, 1.6 units across), all of it lit.
    EXPECT_GT(litPixels(*reference.images[0]), kImageSize * kImageSize / 5);
    // Same GL implementation, same state, same geometry: the same pixels, bit for bit.
    EXPECT_EQ(maxDifference(*reference.images[0], *reference.images[1]), 0.0);
    for (const auto& image : threaded.images)
        EXPECT_EQ(maxDifference(*reference.images[0], *image), 0.0);
}

}  // namespace OSGBTF_TEST_FILE
