// osgdb_btfzip and zips that are not BTFs: the plugin hands them to the next reader of ".zip"
// (OSG's own zip archive plugin, osgdb_zip, where a system has one; osgDB itself would not load
// it once libosgBTF has aliased ".zip" to osgdb_btfzip), answers FILE_NOT_HANDLED where there is
// none, and still reads BTF zips and reports damaged ones. No OpenGL here.
#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <string>

#include <gtest/gtest.h>

#include <osg/Group>
#include <osgDB/FileNameUtils>
#include <osgDB/Registry>

#include "loaders/Ubo2003.h"
#include "scene/MaterialNode.h"
#include "scene/OwnPlugins.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using osgBTF::test::buildDir;
using osgBTF::test::builtTool;
using osgBTF::test::runCommand;
using osgBTF::test::shellQuote;
using osgBTF::test::TempDir;
using ReadResult = osgDB::ReaderWriter::ReadResult;

namespace {

osgDB::ReaderWriter* btfZipReader() {
    const std::string dir = buildDir() + "/lib";
    osgDB::FilePathList& paths = osgDB::Registry::instance()->getLibraryFilePathList();
    if (std::find(paths.begin(), paths.end(), dir) == paths.end()) paths.push_front(dir);
    osgBTF::aliasOwnPlugins();
    return osgDB::Registry::instance()->getReaderWriterForExtension("zip");
}

/** A zip of the given (name, text) members, made by the zip tool. */
std::string makeZip(const TempDir& dir, const std::string& name,
                    const std::vector<std::pair<std::string, std::string>>& members) {
    const std::string folder = dir.file(name + ".d");
    for (const auto& [member, text] : members) {
        const std::filesystem::path file = folder + "/" + member;
        std::filesystem::create_directories(file.parent_path());
        osgBTF::test::writeTextFile(file.string(), text);
    }
    const std::string zip = dir.file(name);
    const auto result =
        runCommand("cd " + shellQuote(folder) + " && zip -q -r " + shellQuote(zip) + " .");
    EXPECT_EQ(result.exitCode, 0) << result.output;
    return zip;
}

const char* const kTinyScene = R"(#Ascii Scene
#Version 161
#Generator OpenSceneGraph 3.6.5

osg::Group {
  UniqueID 1
  Name "inside the zip"
}
)";

/** Stands in for OSG's zip archive plugin: reads any zip as a group named after it. Registered
 *  after osgBTF's reader, so it is asked only when that one does not handle the file. */
class NextZipReader : public osgDB::ReaderWriter {
public:
    NextZipReader() { supportsExtension("zip", "test stand-in for OSG's zip plugin"); }
    ReadResult readNode(const std::string& file, const Options*) const override {
        if (osgDB::getLowerCaseFileExtension(file) != "zip") return ReadResult::FILE_NOT_HANDLED;
        osg::ref_ptr<osg::Group> group = new osg::Group;
        group->setName("next reader: " + osgDB::getSimpleFileName(file));
        return group.get();
    }
    ReadResult readObject(const std::string& file, const Options* options) const override {
        return readNode(file, options);
    }
};

}  // namespace

TEST(ZipPlugin, PlainZipsAreNotHandled) {
    osgDB::ReaderWriter* reader = btfZipReader();
    ASSERT_NE(reader, nullptr) << "osgdb_btfzip not found in " << buildDir() << "/lib";
    TempDir dir;
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options("method=lambert cache=off");
    const std::string text = makeZip(dir, "text.zip", {{"README.txt", "hello\n"}});
    const std::string model = makeZip(dir, "model.zip", {{"scene/group.osgt", kTinyScene}});
    EXPECT_FALSE(osgBTF::mayBeUbo2003(text));
    EXPECT_FALSE(osgBTF::mayBeUbo2003(model));
    for (const std::string& zip : {text, model}) {
        const ReadResult result = reader->readNode(zip, options.get());
        EXPECT_EQ(result.status(), ReadResult::FILE_NOT_HANDLED) << zip << ": " << result.message();
    }
}

TEST(ZipPlugin, OsgDbGoesOnToTheNextReader) {
    ASSERT_NE(btfZipReader(), nullptr);
    TempDir dir;
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options("method=lambert cache=off");
    const std::string model = makeZip(dir, "model.zip", {{"group.osgt", kTinyScene}});
    // With osgBTF's reader alone: an error from it would end the search (osgDB returns the first
    // ERROR_IN_READING_FILE and loads no further plugin); "not handled" lets osgDB look on.
    ReadResult result = osgDB::Registry::instance()->readNode(model, options.get());
    EXPECT_EQ(result.status(), ReadResult::FILE_NOT_HANDLED) << result.message();

    osg::ref_ptr<NextZipReader> next = new NextZipReader;
    osgDB::Registry::instance()->addReaderWriter(next.get());
    result = osgDB::Registry::instance()->readNode(model, options.get());
    ASSERT_TRUE(result.validNode()) << result.message();
    EXPECT_EQ(result.getNode()->getName(), "next reader: model.zip");
    // osgBTF's reader hands the zip over itself: asked directly, it answers with the other's node.
    result = btfZipReader()->readNode(model, options.get());
    ASSERT_TRUE(result.validNode()) << result.message();
    EXPECT_EQ(result.getNode()->getName(), "next reader: model.zip");
    result = btfZipReader()->readObject(model, options.get());
    ASSERT_TRUE(result.validObject()) << result.message();
    EXPECT_EQ(result.getObject()->getName(), "next reader: model.zip");

    // A BTF zip is still osgBTF's, and so is a damaged one (its message names the file).
    const std::string btf = dir.file("sample.zip");
    const auto made =
        runCommand(builtTool("btf") + " --no-progress sample --size 4 -o " + shellQuote(btf));
    ASSERT_EQ(made.exitCode, 0) << made.output;
    EXPECT_TRUE(osgBTF::mayBeUbo2003(btf));
    result = osgDB::Registry::instance()->readNode(btf, options.get());
    EXPECT_NE(dynamic_cast<osgBTF::MaterialNode*>(result.getNode()), nullptr) << result.message();
    const std::string odd = makeZip(dir, "odd.zip", {{"tl000 pl000 tv000 pv000.txt", "notes\n"}});
    EXPECT_TRUE(osgBTF::mayBeUbo2003(odd));
    result = btfZipReader()->readNode(odd, options.get());
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message().rfind(odd + ": ", 0), 0u) << result.message();
    osgDB::Registry::instance()->removeReaderWriter(next.get());
}

}  // namespace OSGBTF_TEST_FILE
