// osgdb_bsvtf (plugins/bsvtf/ReaderWriterBSVTF.cpp) and StreamingGroup's serializer
// (plugins/osgbtf/StreamingGroupSerializer.cpp). A BSVTF tile set read through osgDB by
// the name of its index, from a folder and from nginx, is a StreamingGroup over a MaterialNode of
// the streamed material; a wrong name, a missing or broken set and bad options fail with messages
// that name the file. Skips the URL case without nginx (CI installs it).
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include <osg/Geode>
#include <osg/Shape>
#include <osg/ShapeDrawable>
#include <osgDB/ReadFile>
#include <osgDB/WriteFile>

#include "materials/fmf/Fmf.h"
#include "scene/MaterialNode.h"
#include "streaming/StreamedMaterial.h"
#include "streaming/StreamingGroup.h"
#include "streaming/TileBuilder.h"
#include "tests/NginxServer.h"
#include "tests/NotifyCapture.h"
#include "tests/PluginTestUtil.h"
#include "tests/RandomFactors.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

/** A 16 x 16 fmf material of 8 components as a raw tile set (8 x 8 tiles, 4 texels of padding)
 *  in `folder`. */
void writeTileSet(const std::string& folder) {
    const osg::ref_ptr<FmfMaterial> material =
        FmfMaterial::fromFactors(test::randomFactors(FactorModel::Fmf, {8, 0, 0}, 16, 16, 5));
    TileBuildOptions options;
    options.codec = "raw";
    options.tileSize = 8;
    options.padding = 4;
    buildTileSet(*material, folder, options);
}

/** The streamed material under the StreamingGroup a read gave, or null. */
StreamedFmfMaterial* streamedMaterial(osgDB::ReaderWriter::ReadResult& result) {
    auto* group = dynamic_cast<StreamingGroup*>(result.getNode());
    if (!group || group->getNumChildren() != 1) return nullptr;
    auto* node = dynamic_cast<MaterialNode*>(group->getChild(0));
    return node ? dynamic_cast<StreamedFmfMaterial*>(node->getMaterial()) : nullptr;
}

}  // namespace

TEST(BsvtfPlugin, ReadsATileSetFolderByItsIndex) {
    TempDir dir;
    writeTileSet(dir.file("set"));
    osgDB::ReaderWriter::ReadResult result =
        readNode(dir.file("set") + "/index.bsvtf", "cache=64 feedback=2");
    ASSERT_TRUE(result.success()) << result.message();
    StreamedFmfMaterial* material = streamedMaterial(result);
    ASSERT_NE(material, nullptr);
    EXPECT_EQ(material->width(), 16);
    EXPECT_EQ(material->height(), 16);
    EXPECT_EQ(material->sourceFile, dir.file("set") + "/index.bsvtf");
    EXPECT_EQ(material->location(), dir.file("set"));
    auto* group = dynamic_cast<StreamingGroup*>(result.getNode());
    EXPECT_EQ(group->streamer()->materialCount(), 1);
    EXPECT_EQ(group->streamer()->options().cacheSize, 64);
    EXPECT_EQ(group->feedbackScale(), 2);
}

// The pseudo-loader puts a model under a streamed material named by its index.
TEST(BsvtfPlugin, ThePseudoLoaderPutsAModelUnderAStreamedMaterial) {
    TempDir dir;
    writeTileSet(dir.file("set"));
    osg::ref_ptr<osg::Geode> model = new osg::Geode;
    model->addDrawable(new osg::ShapeDrawable(new osg::Box(osg::Vec3(), 1.0f)));
    ASSERT_TRUE(osgDB::writeNodeFile(*model, dir.file("box.osgt")));
    osgDB::ReaderWriter::ReadResult result = readNode(
        dir.file("box.osgt") + ".(" + dir.file("set") + "/index.bsvtf,scale=2).btfmaterial");
    ASSERT_TRUE(result.success()) << result.message();
    StreamedFmfMaterial* material = streamedMaterial(result);
    ASSERT_NE(material, nullptr);
    auto* node =
        static_cast<MaterialNode*>(static_cast<osg::Group*>(result.getNode())->getChild(0));
    EXPECT_EQ(node->getTextureScale(), 2.0f);
    ASSERT_EQ(node->getNumChildren(), 1u);
    EXPECT_NE(dynamic_cast<osg::Geode*>(node->getChild(0)), nullptr);

    const std::string missing = dir.file("none") + "/index.bsvtf";
    EXPECT_FALSE(readNode(dir.file("box.osgt") + ".(" + missing + ").btfmaterial").success());
}

TEST(BsvtfPlugin, FailuresNameTheFile) {
    TempDir dir;
    writeTileSet(dir.file("set"));
    using ReadResult = osgDB::ReaderWriter::ReadResult;
    EXPECT_EQ(readNode(dir.file("none") + "/index.bsvtf").status(), ReadResult::FILE_NOT_FOUND);

    const std::string other = dir.file("set") + "/other.bsvtf";
    EXPECT_EQ(readNode(other).message(),
              other +
                  ": name a tile set by its index.bsvtf (DIR/index.bsvtf or "
                  "http://HOST/PATH/index.bsvtf)");

    const std::string index = dir.file("set") + "/index.bsvtf";
    EXPECT_EQ(readNode(index, "cache=0").message(),
              index + ": option cache=0: expected a positive integer");

    writeTextFile(index, "not an index");
    const ReadResult broken = readNode(index);
    EXPECT_FALSE(broken.success());
    EXPECT_NE(broken.message().find(index), std::string::npos) << broken.message();
}

TEST(BsvtfPlugin, ReadsATileSetFromAUrl) {
    if (NginxServer::executable().empty())
        GTEST_SKIP() << "nginx is not installed (CI installs it)";
    NginxServer server;
    writeTileSet(server.root() + "/set");
    ASSERT_EQ(server.start(), "");
    osgDB::ReaderWriter::ReadResult result = readNode(server.url("/set/index.bsvtf"));
    ASSERT_TRUE(result.success()) << result.message();
    StreamedFmfMaterial* material = streamedMaterial(result);
    ASSERT_NE(material, nullptr);
    EXPECT_EQ(material->location(), server.url("/set"));
    EXPECT_EQ(server.requestCount("/set/index.bsvtf"), 1);

    const osgDB::ReaderWriter::ReadResult missing = readNode(server.url("/none/index.bsvtf"));
    EXPECT_FALSE(missing.success());
    EXPECT_NE(missing.message().find(server.url("/none/index.bsvtf") + ": HTTP 404"),
              std::string::npos)
        << missing.message();
}

// A scene file holds streamed materials: the group's cache size, feedback scale and tile sets,
// and the MaterialNodes that name a streamed material, written and read back (.osgt, .osgb)
// without a warning; a tile set gone since is one warning naming it.
TEST(BsvtfSerializer, AStreamingGroupRoundTripsThroughOsgtAndOsgb) {
    usePluginsFromBuild();  // the wrapper is osgdb_osgbtf's
    TempDir dir;
    writeTileSet(dir.file("set"));
    TileStreamerOptions options;
    options.cacheSize = 64;
    osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(options));
    group->setFeedbackScale(2);
    osg::ref_ptr<MaterialNode> node =
        new MaterialNode(group->streamer()->open(dir.file("set")).get());
    osg::ref_ptr<osg::Geode> box = new osg::Geode;
    box->addDrawable(new osg::ShapeDrawable(new osg::Box(osg::Vec3(), 1.0f)));
    node->addChild(box.get());
    group->addChild(node.get());
    EXPECT_EQ(node->getMaterialFile(), dir.file("set") + "/index.bsvtf");
    for (const std::string ext : {"osgt", "osgb"}) {
        SCOPED_TRACE(ext);
        const std::string file = dir.file("scene." + ext);
        ScopedNotifyCapture capture;
        ASSERT_TRUE(osgDB::writeNodeFile(*group, file));
        const osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(file);
        auto* back = dynamic_cast<StreamingGroup*>(read.get());
        ASSERT_NE(back, nullptr);
        EXPECT_EQ(back->streamer()->options().cacheSize, 64);
        EXPECT_EQ(back->feedbackScale(), 2);
        ASSERT_EQ(back->streamer()->materialCount(), 1);
        EXPECT_EQ(back->streamer()->material(0)->location(), dir.file("set"));
        ASSERT_EQ(back->getNumChildren(), 1u);
        auto* backNode = dynamic_cast<MaterialNode*>(back->getChild(0));
        ASSERT_NE(backNode, nullptr);
        EXPECT_EQ(backNode->getMaterial(), back->streamer()->material(0));
        EXPECT_EQ(backNode->getNumChildren(), 1u);
        EXPECT_EQ(capture.text(), "");
    }

    std::filesystem::remove_all(dir.file("set"));
    ScopedNotifyCapture capture;
    const osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(dir.file("scene.osgt"));
    auto* back = dynamic_cast<StreamingGroup*>(read.get());
    ASSERT_NE(back, nullptr);
    EXPECT_EQ(back->streamer()->materialCount(), 0);
    auto* backNode = dynamic_cast<MaterialNode*>(back->getChild(0));
    ASSERT_NE(backNode, nullptr);
    EXPECT_EQ(backNode->getMaterial(), nullptr);
    EXPECT_NE(capture.text().find("osgBTF::StreamingGroup: " + dir.file("set")), std::string::npos)
        << capture.text();
    EXPECT_NE(capture.text().find("(its nodes draw their children without it)"), std::string::npos)
        << capture.text();
}

}  // namespace OSGBTF_TEST_FILE
