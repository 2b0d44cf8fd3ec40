// Coordinate maps in scenes: MaterialNode::setCoordinateMap[File] (refusals with their exact
// messages), the CoordinateMapFile serializer property, and the plugins' option map=FILE. No
// OpenGL here (tests/gl/coordinate_map_test.cpp renders).
#include <memory>

#include <gtest/gtest.h>

#include <osg/Geode>
#include <osgDB/ReadFile>
#include <osgDB/WriteFile>
#include <osgUtil/IncrementalCompileOperation>

#include "harness/sample/BlockMap.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/lambert/Lambert.h"
#include "scene/MaterialNode.h"
#include "tests/NotifyCapture.h"
#include "tests/PluginTestUtil.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::ScopedNotifyCapture;
using osgBTF::test::TempDir;
using ReadResult = osgDB::ReaderWriter::ReadResult;

namespace {

/** A 4x3 lambert material saved as DIR/wool.btfmat, a 10x8 map into it as DIR/map.exr and a
 *  map into an 8x8 sample as DIR/other.exr. */
struct Files {
    TempDir dir;
    std::string material = dir.file("wool.btfmat");
    std::string map = dir.file("map.exr");
    std::string otherMap = dir.file("other.exr");
    Files() {
        SampleOptions options;
        options.width = 4;
        options.height = 3;
        saveMaterial(*LambertMaterial::fit(makeSampleBtf(options), {}), material);
        writeCoordinateMap(makeBlockCoordinateMap(10, 8, 4, 3, 2, 5), map);
        writeCoordinateMap(makeBlockCoordinateMap(10, 8, 8, 8, 2, 5), otherMap);
    }
};

MaterialNode* findMaterialNode(osg::Node* node) {
    if (auto* material = dynamic_cast<MaterialNode*>(node)) return material;
    if (osg::Group* group = node ? node->asGroup() : nullptr)
        for (unsigned i = 0; i < group->getNumChildren(); ++i)
            if (MaterialNode* found = findMaterialNode(group->getChild(i))) return found;
    return nullptr;
}

}  // namespace

TEST(MaterialNodeCoordinateMap, MissingMapFile) {
    Files files;
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    ASSERT_TRUE(node->setMaterialFile(files.material));
    ScopedNotifyCapture notify;
    EXPECT_FALSE(node->setCoordinateMapFile(files.dir.file("nosuch.exr")));
    EXPECT_EQ(node->getCoordinateMapError(), files.dir.file("nosuch.exr") + ": no such file");
    EXPECT_EQ(notify.text(), "osgBTF::MaterialNode: " + files.dir.file("nosuch.exr") +
                                 ": no such file (the node draws the material without the map)\n");
    EXPECT_EQ(node->getCoordinateMapFile(), files.dir.file("nosuch.exr"));
    EXPECT_FALSE(node->usesCoordinateMap());
    EXPECT_NE(node->getMaterial(), nullptr);  // the material itself is still drawn
}

TEST(MaterialNodeCoordinateMap, NotAMapFile) {
    Files files;
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    ScopedNotifyCapture notify;
    EXPECT_FALSE(node->setCoordinateMapFile(files.material));  // an EXR, but a fitted material
    EXPECT_EQ(
        node->getCoordinateMapError(),
        files.material + ": not an osgBTF coordinate map (no osgBTF.coordinateMap attribute)");
    EXPECT_FALSE(node->usesCoordinateMap());
}

TEST(MaterialNodeCoordinateMap, MapForAnotherSampleSizeIsRefusedWhicheverComesFirst) {
    Files files;
    const std::string expected =
        files.otherMap + ": made for a 8x8 sample, but material '" + files.material + "' is 4x3";
    {
        osg::ref_ptr<MaterialNode> node = new MaterialNode;
        ASSERT_TRUE(node->setMaterialFile(files.material));
        ScopedNotifyCapture notify;
        EXPECT_FALSE(node->setCoordinateMapFile(files.otherMap));
        EXPECT_EQ(node->getCoordinateMapError(), expected);
        EXPECT_EQ(notify.text(), "osgBTF::MaterialNode: " + expected +
                                     " (the node draws the material without the map)\n");
        EXPECT_FALSE(node->usesCoordinateMap());
    }
    {
        osg::ref_ptr<MaterialNode> node = new MaterialNode;
        ScopedNotifyCapture notify;
        EXPECT_TRUE(node->setCoordinateMapFile(files.otherMap));  // nothing to check against yet
        EXPECT_FALSE(node->usesCoordinateMap());
        EXPECT_TRUE(node->setMaterialFile(files.material));
        EXPECT_EQ(node->getCoordinateMapError(), expected);
        EXPECT_FALSE(node->usesCoordinateMap());
    }
    {
        // A map set in memory is named as such.
        osg::ref_ptr<MaterialNode> node = new MaterialNode;
        ASSERT_TRUE(node->setMaterialFile(files.material));
        ScopedNotifyCapture notify;
        EXPECT_FALSE(node->setCoordinateMap(
            std::make_shared<const CoordinateMap>(readCoordinateMap(files.otherMap))));
        EXPECT_EQ(node->getCoordinateMapError(),
                  "coordinate map: made for a 8x8 sample, but "
                  "material '" +
                      files.material + "' is 4x3");
    }
}

TEST(MaterialNodeCoordinateMap, MatchingMapIsUsedAndSharedAndCanBeRemoved) {
    Files files;
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    ASSERT_TRUE(node->setCoordinateMapFile(files.map));
    ASSERT_TRUE(node->setMaterialFile(files.material));
    EXPECT_TRUE(node->usesCoordinateMap());
    EXPECT_EQ(node->getCoordinateMapError(), "");
    EXPECT_EQ(node->getCoordinateMap()->width, 10);
    osg::ref_ptr<MaterialNode> other = new MaterialNode;
    ASSERT_TRUE(other->setCoordinateMapFile(files.map));
    EXPECT_EQ(other->getCoordinateMap(), node->getCoordinateMap());  // read once
    // Switching materials keeps the map (btfviewer's keys do that).
    node->setMaterial(nullptr);
    EXPECT_FALSE(node->usesCoordinateMap());
    node->setMaterial(other->getMaterial());
    EXPECT_FALSE(node->usesCoordinateMap());  // other has no material yet
    ASSERT_TRUE(other->setMaterialFile(files.material));
    node->setMaterial(other->getMaterial());
    EXPECT_TRUE(node->usesCoordinateMap());
    EXPECT_TRUE(node->setCoordinateMap(nullptr));
    EXPECT_FALSE(node->usesCoordinateMap());
    EXPECT_EQ(node->getCoordinateMapFile(), "");
}

namespace {

/** The coordinate-map texture `node` would compile (osgUtil::StateToCompile sees the StateSets
 *  it pushes at cull); null if none. */
osg::Texture* mapTexture(MaterialNode& node) {
    osgUtil::StateToCompile collect(osgUtil::GLObjectsVisitor::COMPILE_STATE_ATTRIBUTES, nullptr);
    node.accept(collect);
    for (osg::Texture* texture : collect._textures)
        if (texture->getName() == "osgBTF_coordinateMap") return texture;
    return nullptr;
}

}  // namespace

// Nodes drawing one map share its texture through one StateSet, which they push at cull: OSG's
// list of a texture's parent StateSets is not guarded, and nodes are made and deleted on any
// thread, so the texture is bound in that StateSet alone.
TEST(MaterialNodeCoordinateMap, NodesDrawingOneMapShareATextureWithOneParent) {
    Files files;
    osg::ref_ptr<MaterialNode> a = new MaterialNode, b = new MaterialNode;
    for (MaterialNode* node : {a.get(), b.get()}) {
        ASSERT_TRUE(node->setMaterialFile(files.material));
        ASSERT_TRUE(node->setCoordinateMapFile(files.map));
        node->addChild(new osg::Geode);
    }
    osg::Texture* texture = mapTexture(*a);
    ASSERT_NE(texture, nullptr);
    EXPECT_EQ(mapTexture(*b), texture);
    EXPECT_EQ(texture->getNumParents(), 1u);
    osg::ref_ptr<MaterialNode> copy = new MaterialNode(*b, osg::CopyOp::SHALLOW_COPY);
    b = nullptr;
    EXPECT_EQ(mapTexture(*copy), texture);
    EXPECT_EQ(texture->getNumParents(), 1u);
}

class CoordinateMapSerializer : public ::testing::TestWithParam<const char*> {};

TEST_P(CoordinateMapSerializer, MapFileRoundTrips) {
    Files files;
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options;
    options->getDatabasePathList().push_back(files.dir.path().string());
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    ASSERT_TRUE(node->setMaterialFile("wool.btfmat", options.get()));
    ASSERT_TRUE(node->setCoordinateMapFile("map.exr", options.get()));
    node->setTextureScale(3);
    node->addChild(new osg::Geode);
    const std::string scene = files.dir.file(std::string("scene.") + GetParam());
    ASSERT_TRUE(osgDB::writeNodeFile(*node, scene));
    osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(scene);
    MaterialNode* readNode = findMaterialNode(read.get());
    ASSERT_NE(readNode, nullptr);
    EXPECT_EQ(readNode->getMaterialFile(), "wool.btfmat");
    EXPECT_EQ(readNode->getCoordinateMapFile(), "map.exr");
    EXPECT_EQ(readNode->getTextureScale(), 3.0f);
    EXPECT_TRUE(readNode->usesCoordinateMap()) << readNode->getCoordinateMapError();
    EXPECT_EQ(readNode->getCoordinateMap()->coordinates, readCoordinateMap(files.map).coordinates);

    // Without a map nothing is stored, and nothing is read back.
    ASSERT_TRUE(node->setCoordinateMap(nullptr));
    ASSERT_TRUE(osgDB::writeNodeFile(*node, scene));
    read = osgDB::readRefNodeFile(scene);
    readNode = findMaterialNode(read.get());
    ASSERT_NE(readNode, nullptr);
    EXPECT_EQ(readNode->getCoordinateMapFile(), "");
    EXPECT_FALSE(readNode->usesCoordinateMap());
    EXPECT_NE(readNode->getMaterial(), nullptr);
}

INSTANTIATE_TEST_SUITE_P(SceneFormats, CoordinateMapSerializer, ::testing::Values("osgt", "osgb"));

TEST(CoordinateMapPlugin, MapOption) {
    Files files;
    const ReadResult good = test::readNode(files.material, "map=" + files.map + " scale=2");
    MaterialNode* node = test::asMaterialNode(good);
    ASSERT_NE(node, nullptr) << good.message();
    EXPECT_TRUE(node->usesCoordinateMap());
    EXPECT_EQ(node->getCoordinateMapFile(), files.map);
    EXPECT_EQ(node->getTextureScale(), 2.0f);

    ScopedNotifyCapture notify;  // MaterialNode's own warnings
    ReadResult missing = test::readNode(files.material, "map=" + files.dir.file("no.exr"));
    EXPECT_FALSE(missing.validNode());
    EXPECT_EQ(missing.message(), files.dir.file("no.exr") + ": no such file");
    ReadResult other = test::readNode(files.material, "map=" + files.otherMap);
    EXPECT_FALSE(other.validNode());
    EXPECT_EQ(other.message(), files.otherMap + ": made for a 8x8 sample, but material '" +
                                   files.material + "' is 4x3");
    ReadResult notAMap = test::readNode(files.material, "map=" + files.material);
    EXPECT_FALSE(notAMap.validNode());
    EXPECT_EQ(
        notAMap.message(),
        files.material + ": not an osgBTF coordinate map (no osgBTF.coordinateMap attribute)");
}

TEST(CoordinateMapPlugin, PseudoLoaderMapOption) {
    Files files;
    osg::ref_ptr<osg::Geode> model = new osg::Geode;
    ASSERT_TRUE(osgDB::writeNodeFile(*model, files.dir.file("model.osgt")));
    const ReadResult result = test::readNode(files.dir.file("model.osgt") + ".(" + files.material +
                                             ",map=" + files.map + ",scale=4).btfmaterial");
    MaterialNode* node = test::asMaterialNode(result);
    ASSERT_NE(node, nullptr) << result.message();
    EXPECT_TRUE(node->usesCoordinateMap());
    EXPECT_EQ(node->getTextureScale(), 4.0f);
    EXPECT_EQ(node->getNumChildren(), 1u);
}

}  // namespace OSGBTF_TEST_FILE
