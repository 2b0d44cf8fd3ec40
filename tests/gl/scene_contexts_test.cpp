// One MaterialNode scene drawn by two headless contexts at once; one context is closed the way
// osgViewer closes it (osg::GraphicsContext::close releases every camera's subgraph for that
// context), then its viewer goes. Its texture objects and program go with it, the other context
// keeps rendering the expected colours, and a context created afterwards (OSG hands it the freed
// context ID, where stale per-context objects would be taken for its own) renders correctly.
// Also: osgUtil::GLObjectsVisitor, as osgViewer's first frame runs it, compiles the material.
// Built twice (EGL and OSMesa) like every GL test.
#include <algorithm>
#include <cmath>
#include <memory>
#include <sstream>
#include <vector>

#include <gtest/gtest.h>

#include <osg/Geode>
#include <osg/LightSource>
#include <osg/Program>
#include <osg/State>
#include <osg/Texture>
#include <osgUtil/GLObjectsVisitor>

#include "core/Directions.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/pca/Pca.h"
#include "scene/MaterialNode.h"
#include "tests/gl/GlTestEnv.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

constexpr int kImageSize = 64;
constexpr double kHalfExtent = 0.8;

osg::ref_ptr<PcaMaterial> fitSample() {
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;
    return PcaMaterial::fit(makeSampleBtf(sample), FitOptions::parse("components=4 storage=float"));
}

using View = PatchView;

View viewFrom(float thetaDeg, float phiDeg) {
    return patchViewFrom(thetaDeg, phiDeg, kImageSize, kHalfExtent);
}

const osg::Vec3 kToLight = osg::Vec3(0.3f, -0.4f, 0.87f) / osg::Vec3(0.3f, -0.4f, 0.87f).length();
const osg::Vec3 kLightColor(0.9f, 0.8f, 0.7f);

/** A directional light and the unit patch (0,0)-(1,1), normal +Z, under `node`. */
osg::ref_ptr<osg::Group> litScene(MaterialNode* node) {
    osg::ref_ptr<osg::Light> light = new osg::Light(0);
    light->setPosition(osg::Vec4(kToLight, 0));
    light->setDiffuse(osg::Vec4(kLightColor, 1));
    osg::ref_ptr<osg::LightSource> source = new osg::LightSource;
    source->setLight(light.get());
    osg::ref_ptr<osg::Geode> patch = new osg::Geode;
    patch->addDrawable(createFullScreenQuadGeometry().get());
    node->addChild(patch.get());
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->addChild(source.get());
    root->addChild(node);
    return root;
}

/** Worst channel difference to the CPU evaluator over the pixels whose surface point is well
 *  inside a texel; "" or where it is worst. */
struct Comparison {
    int compared = 0;
    double worst = 0;
    std::string where;
};

Comparison compareWithCpu(const osg::Image& image, const Material& material, const View& view) {
    Comparison result;
    const osg::Matrixd eyeToWorld = osg::Matrixd::inverse(view.setup.view);
    const osg::Vec3d v(view.toEye.x, view.toEye.y, view.toEye.z);
    for (int j = 0; j < kImageSize; j += 2)
        for (int i = 0; i < kImageSize; i += 2) {
            const double ex = -kHalfExtent + (i + 0.5) / kImageSize * 2 * kHalfExtent;
            const double ey = -kHalfExtent + (j + 0.5) / kImageSize * 2 * kHalfExtent;
            const osg::Vec3d origin = osg::Vec3d(ex, ey, 0) * eyeToWorld;
            const osg::Vec3d p = origin - v * (origin.z() / v.z());
            if (p.x() <= 0 || p.x() >= 1 || p.y() <= 0 || p.y() >= 1) continue;
            const double fs = p.x() * material.width(), ft = p.y() * material.height();
            const double edge = 0.2;
            if (fs - std::floor(fs) < edge || std::ceil(fs) - fs < edge ||
                ft - std::floor(ft) < edge || std::ceil(ft) - ft < edge)
                continue;
            const glm::vec3 light(kToLight.x(), kToLight.y(), kToLight.z());
            // Filtered: the texels around the pixel's coordinate, blended.
            const glm::vec3 value =
                material.evaluateFiltered(float(p.x()), float(p.y()), 0.0f, view.toEye, light);
            for (int c = 0; c < 3; ++c) {
                const double expected = double(kLightColor[c]) * value[c];
                const double d = std::abs(double(pixel(image, i, j, c)) - expected);
                if (!(d <= result.worst)) {
                    result.worst = std::isnan(d) ? 1e30 : d;
                    std::ostringstream where;
                    where << "pixel (" << i << ", " << j << ") channel " << c << ": GPU "
                          << pixel(image, i, j, c) << " CPU " << expected;
                    result.where = where.str();
                }
            }
            ++result.compared;
        }
    return result;
}

std::vector<osg::Texture*> texturesOf(osg::StateSet& stateSet) {
    std::vector<osg::Texture*> textures;
    for (unsigned unit = 0; unit < stateSet.getTextureAttributeList().size(); ++unit)
        if (auto* texture = dynamic_cast<osg::Texture*>(
                stateSet.getTextureAttribute(unit, osg::StateAttribute::TEXTURE)))
            textures.push_back(texture);
    return textures;
}

osg::Program& programOf(osg::StateSet& stateSet) {
    auto* program =
        dynamic_cast<osg::Program*>(stateSet.getAttribute(osg::StateAttribute::PROGRAM));
    if (!program) throw std::runtime_error("the material's StateSet has no program");
    return *program;
}

unsigned contextId(HeadlessRenderer& renderer) {
    return renderer.context().getState()->getContextID();
}

}  // namespace

TEST(SceneContexts, ClosingOneContextReleasesItsObjectsAndTheOtherKeepsRendering) {
    osg::ref_ptr<PcaMaterial> material = fitSample();
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
    osg::ref_ptr<osg::Group> scene = litScene(node.get());
    osg::StateSet& shared = *material->sharedStateSet();
    const std::vector<osg::Texture*> textures = texturesOf(shared);
    ASSERT_FALSE(textures.empty());
    osg::Program& program = programOf(shared);
    const View view = viewFrom(35, 60);

    auto first = std::make_unique<HeadlessRenderer>(glTestBackend());
    auto second = std::make_unique<HeadlessRenderer>(glTestBackend());
    const unsigned firstId = contextId(*first), secondId = contextId(*second);
    ASSERT_NE(firstId, secondId);
    const osg::ref_ptr<osg::Image> before = first->render(scene.get(), view.setup);
    const osg::ref_ptr<osg::Image> other = second->render(scene.get(), view.setup);
    for (const osg::Image* image : {before.get(), other.get()}) {
        const Comparison r = compareWithCpu(*image, *material, view);
        EXPECT_GT(r.compared, 40);
        EXPECT_LE(r.worst, 4e-3) << r.where;
    }
    EXPECT_EQ(node->getNumCameraLightStates(), 2u);
    for (const osg::Texture* texture : textures) {
        EXPECT_NE(texture->getTextureObject(firstId), nullptr);
        EXPECT_NE(texture->getTextureObject(secondId), nullptr);
    }
    // The program as the second context drew with it (getPCP finds the PCP the draw made).
    osg::observer_ptr<osg::Program::PerContextProgram> secondPcp =
        program.getPCP(*second->context().getState());
    ASSERT_TRUE(secondPcp.valid());
    EXPECT_TRUE(secondPcp->isLinked());
    osg::observer_ptr<osg::Program::PerContextProgram> firstPcp =
        program.getPCP(*first->context().getState());
    // The second context's last frames look away from the patch. Closing also releases the
    // StateSets of the render graphs osgViewer's renderer keeps from its last two frames, which
    // would hide a missing forwarding when those showed the material.
    CameraSetup away = view.setup;
    away.view =  // beside the patch: OSG culls by the frustum's sides, not its near plane
        osg::Matrixd::lookAt(osg::Vec3d(10, 10, 2), osg::Vec3d(10, 10, 0), osg::Vec3d(0, 1, 0));
    for (int frame = 0; frame < 2; ++frame) {
        const osg::ref_ptr<osg::Image> empty = second->render(scene.get(), away);
        EXPECT_EQ(pixel(*empty, kImageSize / 2, kImageSize / 2, 0), 0.0f);
    }

    // What the viewer's destructor does first: GraphicsContext::close releases every camera's
    // subgraph for that context, deletes its GL objects and frees its context ID.
    second->context().close();
    // OSG 3.6.5 then deletes the camera, and its GraphicsContext::removeCamera releases what is
    // below it with the closed context's null State, i.e. for every context: a scene shared with
    // a live context has to leave the camera first (else the live context draws with stale
    // vertex buffer bindings; llvmpipe crashes, with or without MaterialNode).
    second->setScene(nullptr);
    second.reset();

    for (const osg::Texture* texture : textures) {
        EXPECT_EQ(texture->getTextureObject(secondId), nullptr);
        EXPECT_NE(texture->getTextureObject(firstId), nullptr);
    }
    EXPECT_FALSE(secondPcp.valid()) << "the closed context's program objects are still held";
    EXPECT_TRUE(firstPcp.valid());

    const osg::ref_ptr<osg::Image> after = first->render();
    EXPECT_EQ(maxDifference(*before, *after), 0.0);
    EXPECT_EQ(node->getNumCameraLightStates(), 1u) << "the deleted camera's light state is kept";

    // OSG gives the freed ID to the next context: stale objects for it would be taken as its own.
    auto third = std::make_unique<HeadlessRenderer>(glTestBackend());
    EXPECT_EQ(contextId(*third), secondId);
    const osg::ref_ptr<osg::Image> fresh = third->render(scene.get(), view.setup);
    const Comparison r = compareWithCpu(*fresh, *material, view);
    EXPECT_GT(r.compared, 40);
    EXPECT_LE(r.worst, 4e-3) << r.where;
    EXPECT_LE(maxDifference(*before, *fresh), 1e-5);
    EXPECT_EQ(node->getNumCameraLightStates(), 2u);
}

TEST(SceneContexts, GLObjectsVisitorCompilesTheMaterialAheadOfTheFirstFrame) {
    osg::ref_ptr<PcaMaterial> material = fitSample();
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
    osg::ref_ptr<osg::Group> scene = litScene(node.get());
    osg::StateSet& shared = *material->sharedStateSet();
    const std::vector<osg::Texture*> textures = texturesOf(shared);
    ASSERT_FALSE(textures.empty());
    const View view = viewFrom(50, 200);

    HeadlessRenderer renderer(glTestBackend());
    renderer.render(nullptr, view.setup);  // realizes the context; the material is not drawn
    const unsigned id = contextId(renderer);
    for (const osg::Texture* texture : textures) ASSERT_EQ(texture->getTextureObject(id), nullptr);

    osg::GraphicsContext& context = renderer.context();
    ASSERT_TRUE(context.makeCurrent());
    osgUtil::GLObjectsVisitor compile;
    compile.setState(context.getState());
    compile.compile(*scene);
    osg::Program::PerContextProgram* pcp = programOf(shared).getPCP(*context.getState());
    const bool linked = pcp && pcp->isLinked();
    context.releaseContext();
    for (const osg::Texture* texture : textures) EXPECT_NE(texture->getTextureObject(id), nullptr);
    EXPECT_TRUE(linked);

    const osg::ref_ptr<osg::Image> image = renderer.render(scene.get(), view.setup);
    const Comparison r = compareWithCpu(*image, *material, view);
    EXPECT_GT(r.compared, 40);
    EXPECT_LE(r.worst, 4e-3) << r.where;
}

}  // namespace OSGBTF_TEST_FILE
