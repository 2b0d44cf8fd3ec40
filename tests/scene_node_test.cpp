// Tests for scene/: MaterialNode (material files, tangents) and its serializers, through osgDB's
// .osgt / .osgb readers and writers as applications use them. No OpenGL here (tests/gl/ renders).
#include <algorithm>
#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>

#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Notify>
#include <osgDB/ReadFile>
#include <osgDB/Registry>
#include <osgDB/WriteFile>

#include "core/Error.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/lambert/Lambert.h"
#include "scene/MaterialNode.h"
#include "scene/OpenMaterial.h"
#include "scene/ShadowTerminator.h"
#include "tests/NotifyCapture.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using osgBTF::test::TempDir;

namespace {

using test::ScopedNotifyCapture;

osg::ref_ptr<LambertMaterial> sampleMaterial() {
    SampleOptions options;
    options.width = 4;
    options.height = 3;
    return LambertMaterial::fit(makeSampleBtf(options), {});
}

/** A unit quad in the XY plane, normal +Z; texture s runs along +X, or along -X (mirrored). */
osg::ref_ptr<osg::Geometry> quad(bool mirrored) {
    osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec2Array> texCoords = new osg::Vec2Array;
    for (const osg::Vec2 corner :
         {osg::Vec2(0, 0), osg::Vec2(1, 0), osg::Vec2(1, 1), osg::Vec2(0, 1)}) {
        vertices->push_back(osg::Vec3(corner, 0));
        texCoords->push_back(osg::Vec2(mirrored ? 1 - corner.x() : corner.x(), corner.y()));
    }
    geometry->setVertexArray(vertices.get());
    geometry->setTexCoordArray(0, texCoords.get());
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array(1);
    (*normals)[0] = osg::Vec3(0, 0, 1);
    geometry->setNormalArray(normals.get(), osg::Array::BIND_OVERALL);
    geometry->addPrimitiveSet(new osg::DrawArrays(GL_QUADS, 0, 4));
    return geometry;
}

osg::Vec4 tangentOf(const osg::Geometry& geometry, unsigned vertex) {
    const auto* tangents = dynamic_cast<const osg::Vec4Array*>(geometry.getVertexAttribArray(6));
    return tangents && vertex < tangents->size() ? (*tangents)[vertex] : osg::Vec4(9, 9, 9, 9);
}

MaterialNode* findMaterialNode(osg::Node* node) {
    if (auto* m = dynamic_cast<MaterialNode*>(node)) return m;
    if (osg::Group* group = node ? node->asGroup() : nullptr)
        for (unsigned i = 0; i < group->getNumChildren(); ++i)
            if (MaterialNode* m = findMaterialNode(group->getChild(i))) return m;
    return nullptr;
}

osg::Geometry* firstGeometry(osg::Node* node) {
    if (osg::Geometry* g = node ? node->asGeometry() : nullptr) return g;
    if (osg::Group* group = node ? node->asGroup() : nullptr)
        for (unsigned i = 0; i < group->getNumChildren(); ++i)
            if (osg::Geometry* g = firstGeometry(group->getChild(i))) return g;
    return nullptr;
}

void expectSameMaterial(const Material& a, const Material& b) {
    ASSERT_EQ(a.methodName(), b.methodName());
    ASSERT_EQ(a.width(), b.width());
    ASSERT_EQ(a.height(), b.height());
    const glm::vec3 view(0.3f, -0.2f, 0.93f), light(-0.5f, 0.1f, 0.86f);
    for (int y = 0; y < a.height(); ++y)
        for (int x = 0; x < a.width(); ++x)
            EXPECT_EQ(a.evaluate(x, y, view, light), b.evaluate(x, y, view, light));
}

}  // namespace

// ---- failure cases first ---------------------------------------------------------------------

TEST(SceneMaterialNode, MissingMaterialFileWarnsNamingItAndKeepsTheChildren) {
    TempDir dir;
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->addChild(new osg::Geode);
    ScopedNotifyCapture capture;
    EXPECT_FALSE(node->setMaterialFile(dir.file("missing.btfmat")));
    EXPECT_EQ(node->getMaterialError(), dir.file("missing.btfmat") + ": no such file");
    EXPECT_NE(capture.text().find("osgBTF::MaterialNode: " + dir.file("missing.btfmat") +
                                  ": no such file (the node draws its children without the "
                                  "material)"),
              std::string::npos)
        << capture.text();
    EXPECT_EQ(node->getMaterial(), nullptr);
    EXPECT_EQ(node->getMaterialFile(), dir.file("missing.btfmat"));  // kept for writing back
    EXPECT_EQ(node->getNumChildren(), 1u);
}

TEST(SceneMaterialNode, UnknownMethodWarnsNamingTheFileAndTheMethod) {
    TempDir dir;
    FittedMaterial fitted = sampleMaterial()->toFittedMaterial();
    fitted.method = "no-such-method";
    saveFittedMaterial(fitted, dir.file("odd.btfmat"));
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    ScopedNotifyCapture capture;
    EXPECT_FALSE(node->setMaterialFile(dir.file("odd.btfmat")));
    const std::string expected = dir.file("odd.btfmat") + ": unknown method 'no-such-method'";
    EXPECT_EQ(node->getMaterialError().rfind(expected, 0), 0u) << node->getMaterialError();
    EXPECT_NE(capture.text().find(expected), std::string::npos) << capture.text();
}

TEST(SceneMaterialNode, SceneNamingAMissingMaterialStillReads) {
    TempDir dir;
    osg::ref_ptr<osg::Group> root = new osg::Group;
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    {
        ScopedNotifyCapture quiet;
        node->setMaterialFile("gone.btfmat");
    }
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(quad(false).get());
    node->addChild(geode.get());
    root->addChild(node.get());
    ASSERT_TRUE(osgDB::writeNodeFile(*root, dir.file("scene.osgt")));

    ScopedNotifyCapture capture;
    osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(dir.file("scene.osgt"));
    ASSERT_TRUE(read.valid());
    MaterialNode* readNode = findMaterialNode(read.get());
    ASSERT_NE(readNode, nullptr);
    EXPECT_EQ(readNode->getMaterial(), nullptr);
    EXPECT_EQ(readNode->getMaterialFile(), "gone.btfmat");
    EXPECT_NE(capture.text().find("osgBTF::MaterialNode: gone.btfmat: no such file"),
              std::string::npos)
        << capture.text();
    EXPECT_EQ(readNode->getNumChildren(), 1u);
}

// ---- tangents --------------------------------------------------------------------------------

TEST(SceneMaterialNode, TangentsFollowTextureSAndHandedness) {
    osg::ref_ptr<osg::Geometry> plain = quad(false), mirrored = quad(true);
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(plain.get());
    geode->addDrawable(mirrored.get());
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->addChild(geode.get());
    for (unsigned v = 0; v < 4; ++v) {
        const osg::Vec4 t = tangentOf(*plain, v), m = tangentOf(*mirrored, v);
        EXPECT_NEAR(t.x(), 1, 1e-6);
        EXPECT_NEAR(t.y(), 0, 1e-6);
        EXPECT_NEAR(t.z(), 0, 1e-6);
        EXPECT_EQ(t.w(), 1);
        // s runs along -X while t still runs along +Y: the frame is left-handed.
        EXPECT_NEAR(m.x(), -1, 1e-6);
        EXPECT_NEAR(m.y(), 0, 1e-6);
        EXPECT_EQ(m.w(), -1);
    }
}

TEST(SceneMaterialNode, TangentsAreGeneratedOnce) {
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(quad(false).get());
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->addChild(geode.get());
    osg::Geometry* geometry = firstGeometry(geode.get());
    const osg::Array* first = geometry->getVertexAttribArray(6);
    ASSERT_NE(first, nullptr);
    EXPECT_EQ(node->generateTangents(), 0u);
    osg::ref_ptr<MaterialNode> other = new MaterialNode(sampleMaterial().get());
    other->addChild(geode.get());
    EXPECT_EQ(geometry->getVertexAttribArray(6), first);
}

TEST(SceneMaterialNode, NoTangentsWithoutTextureCoordinates) {
    osg::ref_ptr<osg::Geometry> geometry = quad(false);
    geometry->setTexCoordArray(0, nullptr);
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(geometry.get());
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->addChild(geode.get());
    EXPECT_EQ(geometry->getVertexAttribArray(6), nullptr);
}

// ---- serializers -----------------------------------------------------------------------------

class SceneSerializer : public ::testing::TestWithParam<const char*> {};

TEST_P(SceneSerializer, MaterialFileAndTextureScaleRoundTrip) {
    TempDir dir;
    osg::ref_ptr<LambertMaterial> material = sampleMaterial();
    saveMaterial(*material, dir.file("wool.btfmat"));
    // The scene names the material relative to itself; it is read from another folder.
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options;
    options->getDatabasePathList().push_back(dir.path().string());
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    ASSERT_TRUE(node->setMaterialFile("wool.btfmat", options.get()));
    node->setTextureScale(2.5f);
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(quad(false).get());
    node->addChild(geode.get());
    const std::string scene = dir.file(std::string("scene.") + GetParam());
    ASSERT_TRUE(osgDB::writeNodeFile(*node, scene));

    osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(scene);
    MaterialNode* readNode = findMaterialNode(read.get());
    ASSERT_NE(readNode, nullptr);
    EXPECT_EQ(readNode->getMaterialFile(), "wool.btfmat");
    EXPECT_EQ(readNode->getTextureScale(), 2.5f);
    ASSERT_NE(readNode->getMaterial(), nullptr) << readNode->getMaterialError();
    expectSameMaterial(*material, *readNode->getMaterial());
    ASSERT_EQ(readNode->getNumChildren(), 1u);
    osg::Geometry* geometry = firstGeometry(readNode);
    ASSERT_NE(geometry, nullptr);
    EXPECT_NEAR(tangentOf(*geometry, 2).x(), 1, 1e-6);
}

TEST_P(SceneSerializer, MaterialWithoutFileIsEmbeddedExactly) {
    TempDir dir;
    osg::ref_ptr<LambertMaterial> material = sampleMaterial();
    ASSERT_TRUE(material->sourceFile.empty());
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
    const std::string scene = dir.file(std::string("embedded.") + GetParam());
    ASSERT_TRUE(osgDB::writeNodeFile(*node, scene));
    osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(scene);
    MaterialNode* readNode = findMaterialNode(read.get());
    ASSERT_NE(readNode, nullptr);
    ASSERT_NE(readNode->getMaterial(), nullptr);
    EXPECT_EQ(readNode->getMaterialFile(), "");
    EXPECT_EQ(readNode->getTextureScale(), 1.0f);
    expectSameMaterial(*material, *readNode->getMaterial());
}

INSTANTIATE_TEST_SUITE_P(SceneFormats, SceneSerializer, ::testing::Values("osgt", "osgb"));

TEST(SceneMaterialSerializer, AssigningAnotherMethodIsRefusedByName) {
    osg::ref_ptr<LambertMaterial> lambert = sampleMaterial();
    osg::ref_ptr<Material> pca = findMethod("pca").fit(makeSampleBtf([] {
                                                           SampleOptions o;
                                                           o.width = o.height = 4;
                                                           return o;
                                                       }()),
                                                       FitOptions::parse("components=2"));
    EXPECT_EQ(test::errorOf([&] { lambert->assignFrom(*pca); }),
              "cannot assign a pca material to a lambert material");
    EXPECT_EQ(lambert->methodName(), "lambert");
}

// Every registered method's material as a stand-alone object through osgDB (the object wrapper
// registerMethod made for its class): the object read back is of the same class and evaluates
// exactly like the original. The list is the registry's, so a new method is tested here without
// being named.
class MaterialObjectSerializer
    : public ::testing::TestWithParam<std::tuple<std::string, const char*>> {};

TEST_P(MaterialObjectSerializer, RoundTripsExactly) {
    const std::string method = std::get<0>(GetParam());
    const char* format = std::get<1>(GetParam());
    SampleOptions sample;
    sample.width = 5;
    sample.height = 4;
    const MethodInfo& info = findMethod(method);
    osg::ref_ptr<Material> material =
        info.fit(makeSampleBtf(sample), FitOptions::parse(info.quickFitOptions));
    TempDir dir;
    const std::string file = dir.file(std::string("material.") + format);
    ASSERT_TRUE(osgDB::writeObjectFile(*material, file));
    osg::ref_ptr<osg::Object> read = osgDB::readRefObjectFile(file);
    ASSERT_NE(read, nullptr);
    EXPECT_STREQ(read->className(), material->className());
    auto* readMaterial = dynamic_cast<Material*>(read.get());
    ASSERT_NE(readMaterial, nullptr);
    expectSameMaterial(*material, *readMaterial);
    const FittedMaterial a = material->toFittedMaterial(), b = readMaterial->toFittedMaterial();
    ASSERT_EQ(a.textures.size(), b.textures.size());
    for (std::size_t i = 0; i < a.textures.size(); ++i) {
        // Held as floats or (8-bit PCA) as bytes: the values, whichever way each side holds them.
        const MaterialTexture &ta = a.textures[i], &tb = b.textures[i];
        ASSERT_EQ(ta.storedCount(), ta.valueCount()) << ta.name;
        ASSERT_EQ(tb.storedCount(), tb.valueCount()) << tb.name;
        ASSERT_EQ(ta.valueCount(), tb.valueCount()) << ta.name;
        for (std::size_t v = 0; v < ta.valueCount(); ++v)
            ASSERT_EQ(ta.value(v), tb.value(v)) << ta.name << " value " << v;
    }
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, MaterialObjectSerializer,
                         ::testing::Combine(::testing::ValuesIn(methodNames()),
                                            ::testing::Values("osgt", "osgb")),
                         [](const auto& info) {
                             std::string name =
                                 std::get<0>(info.param) + "_" + std::get<1>(info.param);
                             std::replace(name.begin(), name.end(), '-', '_');
                             return name;
                         });

TEST(MaterialRegistryList, CoversTheBuiltInMethods) {
    // The list above comes from the registry; it must not come out empty or short.
    const std::vector<std::string> names = methodNames();
    for (const char* method : {"lambert", "laf", "slaf", "rf", "pca", "lpca", "lpca-revised"})
        EXPECT_NE(std::find(names.begin(), names.end(), method), names.end()) << method;
}

TEST(SceneMaterialNode, NodesNamingOneFileShareOneMaterialAndStateSet) {
    TempDir dir;
    saveMaterial(*sampleMaterial(), dir.file("shared.btfmat"));
    osg::ref_ptr<MaterialNode> a = new MaterialNode, b = new MaterialNode;
    ASSERT_TRUE(a->setMaterialFile(dir.file("shared.btfmat")));
    ASSERT_TRUE(b->setMaterialFile(dir.file("shared.btfmat")));
    EXPECT_EQ(a->getMaterial(), b->getMaterial());
    EXPECT_EQ(a->getMaterial()->sharedStateSet(), b->getMaterial()->sharedStateSet());
    EXPECT_NE(a->getMaterial()->sharedStateSet()->getAttribute(osg::StateAttribute::PROGRAM),
              nullptr);
}

// The shared-material cache holds its materials with ref_ptrs (observing them raced
// under ThreadSanitizer) but still lets a material go with the last node drawing it.
TEST(SceneMaterialNode, SharedMaterialIsDeletedWithTheLastNodeDrawingIt) {
    TempDir dir;
    saveMaterial(*sampleMaterial(), dir.file("last.btfmat"));
    osg::ref_ptr<MaterialNode> a = new MaterialNode, b = new MaterialNode;
    ASSERT_TRUE(a->setMaterialFile(dir.file("last.btfmat")));
    ASSERT_TRUE(b->setMaterialFile(dir.file("last.btfmat")));
    const osg::observer_ptr<Material> watched = a->getMaterial();
    a = nullptr;
    EXPECT_TRUE(watched.valid()) << "b still draws it";
    b = nullptr;
    EXPECT_FALSE(watched.valid());
}

// A material the application loaded and dropped itself stays in the cache until the next open
// of any material or releaseUnusedSharedObjects(), which delete it.
TEST(SceneMaterialNode, DroppedSharedMaterialIsReleasedOnRequestOrByTheNextOpen) {
    TempDir dir;
    const std::string file = dir.file("dropped.btfmat"), other = dir.file("other.btfmat");
    saveMaterial(*sampleMaterial(), file);
    saveMaterial(*sampleMaterial(), other);
    osg::ref_ptr<Material> material = loadSharedMaterial(file);
    osg::observer_ptr<Material> watched = material.get();
    material = nullptr;
    EXPECT_TRUE(watched.valid()) << "held by the cache until asked";
    EXPECT_GE(releaseUnusedSharedObjects(), 1u);
    EXPECT_FALSE(watched.valid());
    EXPECT_EQ(releaseUnusedSharedObjects(), 0u);

    material = loadSharedMaterial(file);
    watched = material.get();
    material = nullptr;
    const osg::ref_ptr<Material> second = loadSharedMaterial(other);
    EXPECT_FALSE(watched.valid());
}

// OSG keeps a StateAttribute's parent StateSets in a plain vector, changed by every StateSet that
// binds or drops it; nodes are made and deleted on any thread (a DatabasePager's), so the shared
// terminator texture is bound once, in its own shared StateSet, which the nodes push at cull
// (with the texture in each node's StateSet, two threads changed that vector at once).
TEST(SceneMaterialNode, NodesShareOneTerminatorStateSetWhoseTextureHasOneParent) {
    const osg::ref_ptr<Material> material = sampleMaterial();
    osg::ref_ptr<MaterialNode> a = new MaterialNode(material.get());
    osg::ref_ptr<MaterialNode> b = new MaterialNode(material.get());
    osg::ref_ptr<MaterialNode> copy = new MaterialNode(*a, osg::CopyOp::SHALLOW_COPY);
    const osg::ref_ptr<osg::StateSet> shared = terminatorStateSet(a->getTerminatorSoftness());
    osg::Texture1D* texture = terminatorTexture(*shared);
    ASSERT_NE(texture, nullptr);
    EXPECT_EQ(texture->getNumParents(), 1u);
    EXPECT_EQ(shared->getNumParents(), 0u) << "pushed at cull, never attached";
    // Three nodes and this test hold it, the cache once more.
    EXPECT_EQ(shared->referenceCount(), 5);
    b->setShadowTerminator(false);
    copy = nullptr;
    EXPECT_EQ(shared->referenceCount(), 3);
    EXPECT_EQ(texture->getNumParents(), 1u);
}

}  // namespace OSGBTF_TEST_FILE
