// Tests for plugins/btf (osgdb_btfmat, osgdb_btf, osgdb_btfzip, osgdb_btfmaterial), loaded the way
// applications load them: through osgDB and the build's plugin folder. No OpenGL here.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <filesystem>

#include <gtest/gtest.h>

#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Notify>
#include <osgDB/ReadFile>
#include <osgDB/Registry>
#include <osgDB/WriteFile>

#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/lambert/Lambert.h"
#include "scene/MaterialNode.h"
#include "tests/NotifyCapture.h"
#include "tests/PluginTestUtil.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using osgBTF::test::TempDir;
using ReadResult = osgDB::ReaderWriter::ReadResult;
using osgBTF::test::asMaterialNode;
using osgBTF::test::readNode;
using osgBTF::test::usePluginsFromBuild;

namespace {

using test::ScopedNotifyCapture;

osg::ref_ptr<LambertMaterial> sampleMaterial() {
    SampleOptions options;
    options.width = 4;
    options.height = 4;
    return LambertMaterial::fit(makeSampleBtf(options), {});
}

/** A tiny UBO2003 zip (8x8 texels, the 81x81 Bonn directions) written by the tool. */
std::string writeSampleZip(const TempDir& dir) {
    const std::string zip = dir.file("sample.zip");
    const auto result =
        osgBTF::test::runCommand(test::builtTool("btf") + " --no-progress sample --size 8 -o " +
                                 osgBTF::test::shellQuote(zip));
    EXPECT_EQ(result.exitCode, 0) << result.output;
    return zip;
}

std::vector<std::string> filesIn(const std::string& folder) {
    std::vector<std::string> names;
    std::error_code error;
    for (const auto& entry : fs::directory_iterator(folder, error))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

}  // namespace

// ---- failure cases first ---------------------------------------------------------------------

TEST(ScenePlugins, MissingFittedFileIsFileNotFound) {
    TempDir dir;
    const ReadResult result = readNode(dir.file("nope.btfmat"));
    EXPECT_EQ(result.status(), ReadResult::FILE_NOT_FOUND);
    EXPECT_EQ(result.message(), dir.file("nope.btfmat") + ": no such file");
}

TEST(ScenePlugins, NotAFittedFileIsAnErrorNamingIt) {
    TempDir dir;
    osgBTF::test::writeTextFile(dir.file("text.btfmat"), "not an EXR file\n");
    const ReadResult result = readNode(dir.file("text.btfmat"));
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message().rfind(dir.file("text.btfmat") + ": ", 0), 0u) << result.message();
}

TEST(ScenePlugins, UnknownMethodInAFittedFile) {
    TempDir dir;
    FittedMaterial fitted = sampleMaterial()->toFittedMaterial();
    fitted.method = "mystery";
    saveFittedMaterial(fitted, dir.file("mystery.btfmat"));
    const ReadResult result = readNode(dir.file("mystery.btfmat"));
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message().rfind(dir.file("mystery.btfmat") + ": unknown method 'mystery' "
                                                                  "(this osgBTF knows: ",
                                     0),
              0u)
        << result.message();
}

TEST(ScenePlugins, PseudoLoaderSyntaxErrors) {
    EXPECT_EQ(readNode("model.osgt.btfmaterial").message(),
              "model.osgt.btfmaterial: expected "
              "MODEL.(MATERIAL[,scale=S][,KEY=VALUE...]).btfmaterial");
    EXPECT_EQ(readNode("model.osgt.().btfmaterial").message(),
              "model.osgt.().btfmaterial: expected "
              "MODEL.(MATERIAL[,scale=S][,KEY=VALUE...]).btfmaterial");
    TempDir dir;
    saveMaterial(*sampleMaterial(), dir.file("m.btfmat"));
    const std::string badScale = "model.osgt.(" + dir.file("m.btfmat") + ",scale=zero).btfmaterial";
    EXPECT_EQ(readNode(badScale).message(), "option scale=zero: expected a positive number");
}

TEST(ScenePlugins, PseudoLoaderMissingMaterialOrModel) {
    TempDir dir;
    ReadResult result = readNode("model.osgt.(" + dir.file("none.btfmat") + ").btfmaterial");
    EXPECT_EQ(result.status(), ReadResult::FILE_NOT_FOUND);
    EXPECT_EQ(result.message(), dir.file("none.btfmat") + ": no such file");
    saveMaterial(*sampleMaterial(), dir.file("m.btfmat"));
    ScopedNotifyCapture quiet;  // osgDB complains about the model as well
    result = readNode(dir.file("none.osgt") + ".(" + dir.file("m.btfmat") + ").btfmaterial");
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message(), dir.file("none.osgt") + ": cannot read the model");
}

TEST(ScenePlugins, UnknownFitMethod) {
    TempDir dir;
    const std::string zip = writeSampleZip(dir);
    const ReadResult result = readNode(zip, "method=nope cache=" + dir.file("cache"));
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message().rfind("unknown method 'nope' (known: ", 0), 0u) << result.message();
    EXPECT_FALSE(fs::exists(dir.file("cache")));
}

TEST(ScenePlugins, FitOptionsAreValidatedAgainstTheMethodsTable) {
    TempDir dir;
    const std::string zip = writeSampleZip(dir);
    ReadResult result = readNode(zip, "method=lambert lobes=2 cache=off");
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message(), "lambert: option lobes is unknown (known: none)");
    result = readNode(zip, "method=pca storage=int cache=off");
    EXPECT_EQ(result.message(), "pca: option storage must be one of unorm8, half, float, got int");
    // Words no method knows belong to other plugins and are left alone.
    result = readNode(zip, "method=lambert noRotation otherPlugin=3 cache=off");
    EXPECT_TRUE(result.success()) << result.message();
}

TEST(ScenePlugins, OptionDocumentationComesFromTheMethodTables) {
    usePluginsFromBuild();
    osgDB::ReaderWriter* reader = osgDB::Registry::instance()->getReaderWriterForExtension("btf");
    ASSERT_NE(reader, nullptr);
    const auto options = reader->supportedOptions();
    for (const std::string& name : methodNames())
        for (const OptionSpec& option : findMethod(name).options) {
            const auto it = options.find(option.name + "=<" + option.typeName() + ">");
            ASSERT_NE(it, options.end()) << name << " " << option.name;
            EXPECT_NE(it->second.find(name + ": " + optionHelp(option)), std::string::npos)
                << it->second;
        }
    EXPECT_EQ(options.at("lobes=<integer>")
                  .rfind("laf: number of Lafortune lobes (integer in 1..8, default 2); slaf: ", 0),
              0u);
}

TEST(ScenePlugins, BrokenMeasuredFileIsAnErrorNamingIt) {
    TempDir dir;
    osgBTF::test::writeTextFile(dir.file("broken.zip"), "PK but not really");
    const ReadResult result = readNode(dir.file("broken.zip"), "method=lambert cache=off");
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message().rfind(dir.file("broken.zip") + ": ", 0), 0u) << result.message();
}

// ---- what works ------------------------------------------------------------------------------

TEST(ScenePlugins, FittedFileGivesAMaterialNode) {
    TempDir dir;
    osg::ref_ptr<LambertMaterial> material = sampleMaterial();
    saveMaterial(*material, dir.file("wool.btfmat"));
    const ReadResult result = readNode(dir.file("wool.btfmat"), "scale=3");
    MaterialNode* node = asMaterialNode(result);
    ASSERT_NE(node, nullptr) << result.message();
    ASSERT_NE(node->getMaterial(), nullptr);
    EXPECT_EQ(node->getMaterial()->methodName(), "lambert");
    EXPECT_EQ(node->getMaterialFile(), dir.file("wool.btfmat"));
    EXPECT_EQ(node->getTextureScale(), 3.0f);
    // A fitted file with another extension, through the ".btfmat" pseudo-extension.
    fs::copy_file(dir.file("wool.btfmat"), dir.file("wool.exr"));
    const ReadResult pseudo = readNode(dir.file("wool.exr.btfmat"));
    node = asMaterialNode(pseudo);
    ASSERT_NE(node, nullptr);
    EXPECT_EQ(node->getMaterialFile(), dir.file("wool.exr"));
}

TEST(ScenePlugins, PseudoLoaderPutsTheModelUnderTheMaterial) {
    TempDir dir;
    saveMaterial(*sampleMaterial(), dir.file("wool.btfmat"));
    osg::ref_ptr<osg::Geode> model = new osg::Geode;
    model->setName("the model");
    ASSERT_TRUE(osgDB::writeNodeFile(*model, dir.file("model.osgt")));
    const ReadResult result =
        readNode(dir.file("model.osgt") + ".(" + dir.file("wool.btfmat") + ",scale=4).btfmaterial");
    MaterialNode* node = asMaterialNode(result);
    ASSERT_NE(node, nullptr) << result.message();
    ASSERT_NE(node->getMaterial(), nullptr);
    EXPECT_EQ(node->getTextureScale(), 4.0f);
    ASSERT_EQ(node->getNumChildren(), 1u);
    EXPECT_EQ(node->getChild(0)->getName(), "the model");
}

// An RTI capture (tests/data/rti-icon-64: photos and dirs.lp) is measured data wherever a measured
// BTF goes: as a zip read by its name, and as the material of the pseudo-loader, given as its
// folder or as its .lp file.
TEST(ScenePlugins, RtiCapturesAreFittedAsTheyCome) {
    usePluginsFromBuild();
    TempDir dir;
    const std::string capture = std::string(test::sourceDir()) + "/tests/data/rti-icon-64";
    const std::string zip = dir.file("icon.zip");
    ASSERT_EQ(test::runCommand("cd " + test::shellQuote(capture) + " && zip -q " +
                               test::shellQuote(zip) + " dirs.lp *.jpg")
                  .exitCode,
              0);
    osg::ref_ptr<osg::Geode> model = new osg::Geode;
    ASSERT_TRUE(osgDB::writeNodeFile(*model, dir.file("model.osgt")));
    for (const std::string& name :
         {zip, zip + ".btfzip",
          dir.file("model.osgt") + ".(" + capture + "/dirs.lp,method=hsh,cache=off).btfmaterial",
          dir.file("model.osgt") + ".(" + capture + ",method=hsh,cache=off).btfmaterial"}) {
        const osg::ref_ptr<osgDB::Options> options =
            new osgDB::Options("method=hsh cache=off mipmap=off");
        const ReadResult result = osgDB::Registry::instance()->readNode(name, options.get());
        MaterialNode* node = asMaterialNode(result);
        ASSERT_NE(node, nullptr) << name << ": " << result.message();
        ASSERT_NE(node->getMaterial(), nullptr) << name;
        EXPECT_EQ(node->getMaterial()->methodName(), "hsh") << name;
        EXPECT_EQ(node->getMaterial()->width(), 64) << name;
        EXPECT_EQ(node->getMaterial()->views().size(), 1u) << name;
        EXPECT_EQ(node->getMaterial()->lights().size(), 72u) << name;
    }
}

// The RTI field's fitted files through osgDB: osgdb_ptm and osgdb_rti give a MaterialNode over a
// patch of the file's aspect; the pseudo-loader puts a model under one.
TEST(ScenePlugins, PtmAndRtiFilesAreMaterialsOverAPatch) {
    usePluginsFromBuild();
    TempDir dir;
    const MeasuredBtf btf = test::sampleBtf(6, 3);
    saveMaterial(*findMethod("ptm").fit(btf, FitOptions()), dir.file("a.ptm"));
    saveMaterial(*findMethod("hsh").fit(btf, FitOptions()), dir.file("a.rti"));
    for (const char* name : {"a.ptm", "a.rti"}) {
        const ReadResult result = readNode(dir.file(name));
        MaterialNode* node = asMaterialNode(result);
        ASSERT_NE(node, nullptr) << name << ": " << result.message();
        ASSERT_NE(node->getMaterial(), nullptr) << name;
        EXPECT_EQ(node->getMaterial()->width(), 6) << name;
        ASSERT_EQ(node->getNumChildren(), 1u) << name;
        EXPECT_EQ(node->getMaterialFile(), dir.file(name));
        // A scene keeps the reference: written and read back, the node reads the file again.
        ASSERT_TRUE(osgDB::writeNodeFile(*node, dir.file(std::string(name) + ".osgt")));
        const ReadResult back = readNode(dir.file(std::string(name) + ".osgt"));
        MaterialNode* again = asMaterialNode(back);
        ASSERT_NE(again, nullptr) << name;
        ASSERT_NE(again->getMaterial(), nullptr) << name;
        EXPECT_EQ(again->getMaterial()->methodName(), node->getMaterial()->methodName());
        // The patch: 2 x 1 (the file's aspect), in the XZ plane.
        const osg::BoundingSphere bound = node->getChild(0)->getBound();
        EXPECT_NEAR(bound.radius(), std::sqrt(1.0 + 0.25), 1e-5) << name;
    }
    osg::ref_ptr<osg::Geode> model = new osg::Geode;
    model->setName("the model");
    ASSERT_TRUE(osgDB::writeNodeFile(*model, dir.file("model.osgt")));
    const ReadResult result =
        readNode(dir.file("model.osgt") + ".(" + dir.file("a.rti") + ").btfmaterial");
    MaterialNode* node = asMaterialNode(result);
    ASSERT_NE(node, nullptr) << result.message();
    EXPECT_EQ(node->getMaterial()->methodName(), "hsh");
    ASSERT_EQ(node->getNumChildren(), 1u);
    EXPECT_EQ(node->getChild(0)->getName(), "the model");
    EXPECT_EQ(readNode(dir.file("none.ptm")).status(), ReadResult::FILE_NOT_FOUND);
    test::writeTextFile(dir.file("bad.rti"), "#HSH1.2\n2\n1 1 3\n");
    EXPECT_EQ(readNode(dir.file("bad.rti")).message(),
              dir.file("bad.rti") + ": RTI type 2 is not read (only 3, hemispherical harmonics)");
}

TEST(ScenePlugins, MeasuredBtfIsFittedOnceThenReadFromTheCache) {
    TempDir dir;
    const std::string zip = writeSampleZip(dir);
    const std::string cache = dir.file("cache");
    const std::string options = "method=lambert cache=" + cache;
    ScopedNotifyCapture capture;

    const ReadResult first = readNode(zip, options);
    ASSERT_NE(asMaterialNode(first), nullptr) << first.message();
    const std::vector<std::string> files = filesIn(cache);
    ASSERT_EQ(files.size(), 1u);
    const std::string cached = (fs::path(cache) / files[0]).string();
    EXPECT_EQ(files[0].rfind("sample.zip-lambert-", 0), 0u) << files[0];
    EXPECT_NE(capture.text().find("osgBTF: " + zip +
                                  ": fitting method 'lambert', then caching it in " + cached),
              std::string::npos)
        << capture.text();
    EXPECT_EQ(asMaterialNode(first)->getMaterialFile(), cached);
    const auto writtenAt = fs::last_write_time(cached);

    capture.capture->text.clear();
    const ReadResult second = readNode(zip, options);
    ASSERT_NE(asMaterialNode(second), nullptr) << second.message();
    EXPECT_NE(capture.text().find("osgBTF: " + zip + ": using the cached fit " + cached),
              std::string::npos)
        << capture.text();
    EXPECT_EQ(fs::last_write_time(cached), writtenAt);
    EXPECT_EQ(filesIn(cache).size(), 1u);
    const glm::vec3 v(0, 0, 1), l(0.3f, 0.2f, 0.93f);
    EXPECT_EQ(asMaterialNode(first)->getMaterial()->evaluate(3, 5, v, l),
              asMaterialNode(second)->getMaterial()->evaluate(3, 5, v, l));

    // Other options, or a changed input, make another fit; no temporary files are left behind.
    ASSERT_NE(asMaterialNode(readNode(zip, "method=pca components=2 cache=" + cache)), nullptr);
    EXPECT_EQ(filesIn(cache).size(), 2u);
    fs::last_write_time(zip, fs::last_write_time(zip) + std::chrono::seconds(5));
    capture.capture->text.clear();
    ASSERT_NE(asMaterialNode(readNode(zip, options)), nullptr);
    EXPECT_NE(capture.text().find("fitting method 'lambert'"), std::string::npos) << capture.text();
    EXPECT_EQ(filesIn(cache).size(), 3u);
}

TEST(ScenePlugins, MipmapIsTheDefaultAndOffIsItsOwnCacheEntry) {
    TempDir dir;
    const std::string zip = writeSampleZip(dir);
    const std::string cache = "cache=" + dir.file("cache");
    ReadResult result = readNode(zip, "method=lambert mipmap=yes " + cache);
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message(), "option mipmap=yes: expected on or off");
    result = readNode(zip, "method=lambert mipmap=on " + cache);
    ASSERT_NE(asMaterialNode(result), nullptr) << result.message();
    const Material& mip = *asMaterialNode(result)->getMaterial();
    EXPECT_TRUE(mip.mipLayout().mipMapped());
    EXPECT_EQ(mip.width(), mip.mipLayout().baseWidth() * 3 / 2);
    // The plain fit of the same file and method is another entry, without levels.
    result = readNode(zip, "method=lambert mipmap=off " + cache);
    ASSERT_NE(asMaterialNode(result), nullptr) << result.message();
    EXPECT_FALSE(asMaterialNode(result)->getMaterial()->mipLayout().mipMapped());
    EXPECT_EQ(filesIn(dir.file("cache")).size(), 2u);
    // No option: mip-mapped, as `btf fit`, the same entry as mipmap=on.
    result = readNode(zip, "method=lambert " + cache);
    ASSERT_NE(asMaterialNode(result), nullptr) << result.message();
    EXPECT_TRUE(asMaterialNode(result)->getMaterial()->mipLayout().mipMapped());
    EXPECT_EQ(filesIn(dir.file("cache")).size(), 2u);
}

TEST(ScenePlugins, CacheOffFitsWithoutWriting) {
    TempDir dir;
    const std::string zip = writeSampleZip(dir);
    setenv("OSGBTF_CACHE_DIR", dir.file("env-cache").c_str(), 1);
    const ReadResult result = readNode(zip, "method=lambert cache=off");
    ASSERT_NE(asMaterialNode(result), nullptr) << result.message();
    EXPECT_EQ(asMaterialNode(result)->getMaterialFile(), "");  // serialised embedded
    EXPECT_FALSE(fs::exists(dir.file("env-cache")));
    // Without cache=, $OSGBTF_CACHE_DIR is the cache.
    ASSERT_NE(asMaterialNode(readNode(zip, "method=lambert")), nullptr);
    EXPECT_EQ(filesIn(dir.file("env-cache")).size(), 1u);
    unsetenv("OSGBTF_CACHE_DIR");
}

}  // namespace OSGBTF_TEST_FILE
