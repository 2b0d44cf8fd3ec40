// MaterialNode as OSG's GL-object passes see it, without OpenGL: resizeGLObjectBuffers and
// releaseGLObjects reach the StateSets the node applies outside the scene graph, OSG's compile
// visitors collect the material's textures and program, and the per-camera light state of a
// deleted camera goes away. tests/gl/scene_contexts_test.cpp shows the same with real contexts.
#include <algorithm>
#include <vector>

#include <gtest/gtest.h>

#include <osg/Geode>
#include <osg/Program>
#include <osg/State>
#include <osg/Texture2D>
#include <osgUtil/GLObjectsVisitor>
#include <osgUtil/IncrementalCompileOperation>
#include <osgUtil/SceneView>

#include "harness/sample/SampleBtf.h"
#include "materials/lambert/Lambert.h"
#include "scene/MaterialNode.h"
#include "scene/ShadowTerminator.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

osg::ref_ptr<LambertMaterial> sampleMaterial() {
    SampleOptions options;
    options.width = 4;
    options.height = 3;
    return LambertMaterial::fit(makeSampleBtf(options), {});
}

/** A texture that records what OSG's GL-object calls reach it. */
class SpyTexture : public osg::Texture2D {
public:
    void resizeGLObjectBuffers(unsigned int maxSize) override {
        osg::Texture2D::resizeGLObjectBuffers(maxSize);
        resizedTo = maxSize;
    }
    void releaseGLObjects(osg::State* state) const override {
        osg::Texture2D::releaseGLObjects(state);
        releasedFor.push_back(state);
    }
    unsigned resizedTo = 0;
    mutable std::vector<const osg::State*> releasedFor;

protected:
    ~SpyTexture() override = default;
};

/** Gives the test the node's own StateSets, which are not in the scene graph. */
class InspectableNode : public MaterialNode {
public:
    using MaterialNode::MaterialNode;
    osg::StateSet* nodeStateSet() { return _nodeStateSet.get(); }
    osg::StateSet* lightStateSetOf(const osg::Camera* camera) {
        const auto it = _lightsPerCamera.find(camera);
        return it == _lightsPerCamera.end() ? nullptr : it->second.stateSet.get();
    }

protected:
    ~InspectableNode() override = default;
};

/** A cull of `scene` by the SceneView's own camera, as osgViewer's renderer does it (no GL). */
void cull(osgUtil::SceneView& view, unsigned frame) {
    view.getFrameStamp()->setFrameNumber(frame);
    view.cull();
}

osg::ref_ptr<osgUtil::SceneView> sceneView(osg::Node* scene) {
    osg::ref_ptr<osgUtil::SceneView> view = new osgUtil::SceneView;
    view->setDefaults();
    view->setViewport(0, 0, 16, 16);
    view->setProjectionMatrixAsOrtho(-1, 1, -1, 1, -1, 1);
    view->setSceneData(scene);
    return view;
}

}  // namespace

TEST(SceneMaterialNodeGLObjects, ResizeAndReleaseReachEveryStateSetTheNodeApplies) {
    osg::ref_ptr<LambertMaterial> material = sampleMaterial();
    osg::ref_ptr<InspectableNode> node = new InspectableNode(material.get());
    osg::ref_ptr<osg::Geode> child = new osg::Geode;
    node->addChild(child.get());
    osg::ref_ptr<osgUtil::SceneView> view = sceneView(node.get());
    cull(*view, 1);
    osg::StateSet* lights = node->lightStateSetOf(view->getCamera());
    ASSERT_NE(lights, nullptr);

    // One spy in each StateSet: the material's (shared), the node's, the camera's lights, and
    // a child's (osg::Group's own forwarding, kept).
    std::vector<osg::ref_ptr<SpyTexture>> spies;
    for (osg::StateSet* stateSet :
         {material->sharedStateSet(), node->nodeStateSet(), lights, child->getOrCreateStateSet()}) {
        spies.push_back(new SpyTexture);
        stateSet->setTextureAttribute(15, spies.back().get());
    }
    node->resizeGLObjectBuffers(7);
    osg::ref_ptr<osg::State> state = new osg::State;
    node->releaseGLObjects(state.get());
    const char* names[] = {"material", "node", "lights", "child"};
    for (std::size_t i = 0; i < spies.size(); ++i) {
        EXPECT_EQ(spies[i]->resizedTo, 7u) << names[i];
        EXPECT_EQ(spies[i]->releasedFor, std::vector<const osg::State*>{state.get()}) << names[i];
    }
}

TEST(SceneMaterialNodeGLObjects, ReleaseVisitorReachesTheMaterial) {
    osg::ref_ptr<LambertMaterial> material = sampleMaterial();
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
    osg::ref_ptr<SpyTexture> spy = new SpyTexture;
    material->sharedStateSet()->setTextureAttribute(15, spy.get());
    osgUtil::GLObjectsVisitor release(osgUtil::GLObjectsVisitor::RELEASE_STATE_ATTRIBUTES);
    release.setCheckForGLErrors(osg::State::NEVER_CHECK_GL_ERRORS);  // no State: no GL here
    node->accept(release);
    EXPECT_EQ(spy->releasedFor, std::vector<const osg::State*>{nullptr});
}

TEST(SceneMaterialNodeGLObjects, IncrementalCompileCollectsTheMaterialsTexturesAndProgram) {
    osg::ref_ptr<LambertMaterial> material = sampleMaterial();
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
    node->addChild(new osg::Geode);
    osgUtil::StateToCompile collect(osgUtil::GLObjectsVisitor::COMPILE_STATE_ATTRIBUTES, nullptr);
    node->accept(collect);

    osg::StateSet* shared = material->sharedStateSet();
    auto* program = dynamic_cast<osg::Program*>(shared->getAttribute(osg::StateAttribute::PROGRAM));
    ASSERT_NE(program, nullptr);
    EXPECT_EQ(collect._programs, osgUtil::StateToCompile::ProgramSet{program});
    osgUtil::StateToCompile::TextureSet textures;
    for (unsigned unit = 0; unit < shared->getTextureAttributeList().size(); ++unit)
        if (auto* texture = dynamic_cast<osg::Texture*>(
                shared->getTextureAttribute(unit, osg::StateAttribute::TEXTURE)))
            textures.insert(texture);
    ASSERT_FALSE(textures.empty());
    // And the node's own: the smooth terminator's step texture (shared while anything holds it).
    textures.insert(terminatorTexture(*terminatorStateSet(kDefaultTerminatorSoftness)));
    EXPECT_EQ(collect._textures, textures);
}

TEST(SceneMaterialNodeGLObjects, LightStateOfADeletedCameraIsPruned) {
    osg::ref_ptr<MaterialNode> node = new MaterialNode(sampleMaterial().get());
    node->addChild(new osg::Geode);
    osg::ref_ptr<osgUtil::SceneView> first = sceneView(node.get());
    osg::ref_ptr<osgUtil::SceneView> second = sceneView(node.get());
    osg::observer_ptr<osg::Camera> secondCamera = second->getCamera();
    cull(*first, 1);
    cull(*second, 1);
    EXPECT_EQ(node->getNumCameraLightStates(), 2u);

    second = nullptr;  // its camera goes with it
    ASSERT_FALSE(secondCamera.valid());
    EXPECT_EQ(node->getNumCameraLightStates(), 2u);  // nothing has culled since
    cull(*first, 2);
    EXPECT_EQ(node->getNumCameraLightStates(), 1u);

    // A camera created afterwards (maybe at the deleted one's address) gets state of its own.
    osg::ref_ptr<osgUtil::SceneView> third = sceneView(node.get());
    cull(*third, 2);
    EXPECT_EQ(node->getNumCameraLightStates(), 2u);
    third = nullptr;
    node->releaseGLObjects(nullptr);  // also prunes
    EXPECT_EQ(node->getNumCameraLightStates(), 1u);
}

}  // namespace OSGBTF_TEST_FILE
