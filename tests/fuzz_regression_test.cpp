// Replays fuzz/regression/<target>/ (inputs that once crashed or hung a fuzz target, plus a few
// seeds) through the fuzz targets' own bodies (fuzz/FuzzEntries.h), so every build checks them
// without clang. Each input may be refused with an osgBTF::Error; any other exception fails here,
// and a crash or sanitizer report fails the test process.
#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <sstream>
#include <typeinfo>

#include <gtest/gtest.h>
#include <osg/Notify>
#include <osgDB/ReaderWriter>
#include <osgDB/Registry>

#include "NotifyCapture.h"
#include "TestUtil.h"
#include "core/CoordinateMap.h"
#include "core/Error.h"
#include "core/FittedMaterialFile.h"
#include "core/MeasuredBtf.h"
#include "core/Progress.h"
#include "fuzz/FuzzEntries.h"
#include "loaders/Ubo2003.h"
#include "loaders/Ubo2014.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;

namespace {

class FuzzRegression : public ::testing::TestWithParam<std::string> {
protected:
    // setUp changes process-wide settings; put them back for the tests that follow in the same
    // process (a plain run of the test binary).
    void SetUp() override {
        _memoryLimit = osgBTF::memoryLimit();
        _progress = osgBTF::Progress::enabled();
        _notify = osg::getNotifyLevel();
        osgBTF::fuzz::setUp(osgBTF::test::sourceDir() + "/fuzz/fixtures");
    }
    void TearDown() override {
        osgBTF::setMemoryLimit(_memoryLimit);
        osgBTF::Progress::setEnabled(_progress);
        osg::setNotifyLevel(_notify);
    }

private:
    std::uint64_t _memoryLimit = 0;
    bool _progress = false;
    osg::NotifySeverity _notify = osg::NOTICE;
};

TEST_P(FuzzRegression, EveryInputIsReadOrRefusedWithAnError) {
    const osgBTF::fuzz::Target* target = osgBTF::fuzz::findTarget(GetParam());
    ASSERT_NE(target, nullptr);
    const fs::path folder =
        fs::path(osgBTF::test::sourceDir()) / "fuzz" / "regression" / GetParam();
    std::vector<fs::path> inputs;
    for (const auto& entry : fs::directory_iterator(folder))
        if (entry.is_regular_file()) inputs.push_back(entry.path());
    std::sort(inputs.begin(), inputs.end());
    // An empty or missing folder would pass vacuously.
    ASSERT_FALSE(inputs.empty()) << folder;
    for (const fs::path& input : inputs) {
        std::ifstream in(input, std::ios::binary);
        const std::string bytes((std::istreambuf_iterator<char>(in)),
                                std::istreambuf_iterator<char>());
        ASSERT_TRUE(in.good() || in.eof()) << input;
        try {
            target->run(reinterpret_cast<const std::uint8_t*>(bytes.data()), bytes.size());
        } catch (const osgBTF::Error&) {
            // A refusal with a message: what the parsers are for.
        } catch (const std::exception& e) {
            ADD_FAILURE() << input.filename() << ": " << typeid(e).name() << ": " << e.what();
        }
    }
}

std::vector<std::string> targetNames() {
    std::vector<std::string> names;
    for (const osgBTF::fuzz::Target& target : osgBTF::fuzz::targets()) names.push_back(target.name);
    return names;
}

INSTANTIATE_TEST_SUITE_P(Targets, FuzzRegression, ::testing::ValuesIn(targetNames()),
                         [](const auto& info) { return info.param; });

// The findings' messages, on their regression inputs (fuzz/README.md, "Findings").
class FuzzFindings : public ::testing::Test {
protected:
    void SetUp() override {
        _memoryLimit = osgBTF::memoryLimit();
        osgBTF::setMemoryLimit(std::uint64_t(256) << 20);
    }
    void TearDown() override { osgBTF::setMemoryLimit(_memoryLimit); }
    static std::string input(const std::string& target, const std::string& name) {
        return osgBTF::test::sourceDir() + "/fuzz/regression/" + target + "/" + name;
    }

private:
    std::uint64_t _memoryLimit = 0;
};

TEST_F(FuzzFindings, ZipMemberClaimingGigabytesIsRefusedBeforeAllocating) {
    const std::string path = input("ubo2003_zip", "member-claims-3.75GiB.zip");
    // 0xF0000000 bytes from 81 deflated ones: beyond deflate's 1032:1, refused before the memory
    // limit is even asked.
    EXPECT_EQ(osgBTF::test::errorOf([&] { osgBTF::loadUbo2003(path); }),
              path +
                  ": member '00000 tl000 pl000 tv000 pv000.png' claims 4026531840 bytes "
                  "uncompressed from 81 deflated bytes, more than deflate can expand (1032:1): a "
                  "corrupt archive or a zip bomb");
}

TEST_F(FuzzFindings, ImageClaimingHugeSizeIsRefusedBeforeItsBuffers) {
    const std::string path = input("ubo2003_zip", "claims-60000x60000-jpeg.zip");
    // 60000 x 60000 texels x 2 views x 2 lights x 3 floats = 172.8e9 bytes = 160.9 GiB.
    EXPECT_EQ(osgBTF::test::errorOf([&] { osgBTF::loadUbo2003(path); }),
              path +
                  ": BTF of 60000x60000 texels x 2 views x 2 lights: needs 160.9 GiB, more than "
                  "the memory limit of 256.0 MiB (raise it with --memory-limit or "
                  "OSGBTF_MEMORY_LIMIT)");
}

TEST_F(FuzzFindings, EmbeddedMaterialWithUnknownPixelKindIsRefused) {
    std::ifstream in(input("scene_file", "ub-pixel-kind-7.osgt"), std::ios::binary);
    std::stringstream scene;
    scene << in.rdbuf();
    osgDB::ReaderWriter* osgt = osgDB::Registry::instance()->getReaderWriterForExtension("osgt");
    ASSERT_NE(osgt, nullptr);
    osgBTF::test::ScopedNotifyCapture capture;
    osgDB::ReaderWriter::ReadResult result = osgt->readNode(scene);
    ASSERT_TRUE(result.validNode());
    EXPECT_NE(capture.text().find("osgBTF::MaterialNode: material embedded in the scene: texture "
                                  "'albedo' has an unknown pixel kind 7 (the node draws its "
                                  "children without the material)"),
              std::string::npos)
        << capture.text();
}

// scene_file's body skips inputs with numbers above 10000 or below 0 (OSG's own unbounded counts,
// fuzz/README.md); this one it skips is read here directly.
TEST_F(FuzzFindings, EmbeddedTextureOfNegativeSizeIsRefused) {
    std::ifstream in(input("scene_file", "negative-size-wraps.osgt"), std::ios::binary);
    std::stringstream scene;
    scene << in.rdbuf();
    osgDB::ReaderWriter* osgt = osgDB::Registry::instance()->getReaderWriterForExtension("osgt");
    ASSERT_NE(osgt, nullptr);
    osgBTF::test::ScopedNotifyCapture capture;
    osgDB::ReaderWriter::ReadResult result = osgt->readNode(scene);
    ASSERT_TRUE(result.validNode());
    EXPECT_NE(capture.text().find("osgBTF::MaterialNode: material embedded in the scene: texture "
                                  "data is damaged (the node draws its children without the "
                                  "material)"),
              std::string::npos)
        << capture.text();
}

// The campaign's findings (fuzz/README.md, "Campaign"): each input ran past libFuzzer's 5 s
// before its fix; now each is refused in milliseconds, so a regression shows as the test's timeout.
TEST_F(FuzzFindings, ExrAttributeClaimingMoreThanTheFileIsRefusedBeforeOpenExrAllocatesIt) {
    // A string attribute (the C++ reader zero-fills a std::string of the claimed size).
    const std::string material = input("fitted_material", "hang-string-attribute-claims-1.8GB.exr");
    EXPECT_EQ(osgBTF::test::errorOf([&] { osgBTF::loadFittedMaterial(material); }),
              material +
                  ": OpenEXR header: attribute 'osgBTF.method' (string) claims 1836347395 bytes "
                  "but 1728 remain in the file (truncated or corrupt file)");
    // A compression attribute whose size field says 905969665: OpenEXR's C++ reader reads its
    // one byte and takes what follows as the next attribute, an unknown type (allocated from its
    // size). A fixed-size value whose size field disagrees is now refused by itself.
    const std::string plugin =
        input("btfmat_plugin", "hang-attribute-after-compression-claims-1.9GB.btfmat");
    EXPECT_EQ(osgBTF::test::errorOf([&] { osgBTF::loadFittedMaterial(plugin); }),
              plugin +
                  ": OpenEXR header: attribute 'compression' (compression) gives its size as "
                  "905969665 bytes, but a value of that type takes 1 (corrupt file)");
    // A channel list whose fields and size field disagree: OpenEXR follows the fields, and the
    // string that it reads next is the one checked.
    const std::string channels =
        input("fitted_material", "oom-string-after-channel-list-read-by-its-fields.exr");
    EXPECT_EQ(osgBTF::test::errorOf([&] { osgBTF::loadFittedMaterial(channels); }),
              channels +
                  ": OpenEXR header: attribute 'osgBTF.param.fit.seconds' (string) claims "
                  "1409286154 bytes but 722 remain in the file (truncated or corrupt file)");
    const std::string map = input("coordinate_map", "hang-attribute-claims-1.7GB.exr");
    EXPECT_EQ(
        osgBTF::test::errorOf([&] { osgBTF::readCoordinateMap(map); }),
        map +
            ": OpenEXR header: attribute 'lineOrdpression' (\\x01) claims 1677918208 bytes but "
            "319 remain in the file (truncated or corrupt file)");
}

// CI's fuzz pass (2026-12-06): the same 3,223,415 x 1 ZIP window as slow-zip-window-3223415-wide,
// behind a compression attribute whose size field says 134217729. OpenEXR's C library, which the
// size guard reads headers with, calls that attribute invalid and read a window small enough to
// pass; the C++ reader, which reads the pixels, saw the wide one and filled its line buffers
// twice (5 s under ASan).
TEST_F(FuzzFindings, ExrAttributeOfFixedTypeWithAnotherSizeIsRefused) {
    const std::string map =
        input("coordinate_map", "slow-zip-window-behind-compression-size-134217729.exr");
    EXPECT_EQ(osgBTF::test::errorOf([&] { osgBTF::readCoordinateMap(map); }),
              map +
                  ": OpenEXR header: attribute 'compression' (compression) gives its size as "
                  "134217729 bytes, but a value of that type takes 1 (corrupt file)");
}

// CI's fuzz pass, the run after: the same window with no attribute named "compression" (the
// ZIP value sits under the name "\nion"). OpenEXR's C++ reader keeps its default, ZIP (16-line
// buffers of the full width), the C library its own: the guard saw 1-line buffers.
TEST_F(FuzzFindings, ExrPartWithoutACompressionAttributeIsRefused) {
    const std::string map = input("coordinate_map", "slow-zip-window-no-compression-attribute.exr");
    EXPECT_EQ(osgBTF::test::errorOf([&] { osgBTF::readCoordinateMap(map); }),
              map +
                  ": OpenEXR header: no 'compression' attribute (compression), which every "
                  "part has (corrupt file)");
}

TEST_F(FuzzFindings, Ubo2014RowsWithNoColumnToKeepAreSkippedNotWalked) {
    // The FMF header's height map is 0 texels wide and very many rows high: rows of nothing to
    // keep, which reading walked one by one. Now they are skipped, and the header's next field
    // is what fails.
    const std::string path = input("ubo2014", "hang-rows-of-zero-columns.btf");
    EXPECT_EQ(osgBTF::test::errorOf([&] { osgBTF::readUbo2014(path); }),
              path + ": FMF: scalar size 15 is not 2 (half), 4 (float) or 8 (double)");
}

// A node below itself: every traversal recursed until the stack overflowed (the first being
// the tangent generation of addChild, while the file was read), and the cycle leaked.
TEST_F(FuzzFindings, SceneNodeBelowItselfIsLeftOut) {
    osgDB::ReaderWriter* osgt = osgDB::Registry::instance()->getReaderWriterForExtension("osgt");
    ASSERT_NE(osgt, nullptr);
    // MaterialNode 1 > Group 2 > UniqueID 1 again: the group, whose child is the node itself, is
    // the one left out.
    std::ifstream in(input("scene_file", "cycle-node-below-itself.osgt"), std::ios::binary);
    std::stringstream scene;
    scene << in.rdbuf();
    osgBTF::test::ScopedNotifyCapture capture;
    osgDB::ReaderWriter::ReadResult result = osgt->readNode(scene);
    ASSERT_TRUE(result.validNode()) << result.message();
    ASSERT_NE(result.getNode()->asGroup(), nullptr);
    EXPECT_EQ(result.getNode()->asGroup()->getNumChildren(), 0u);
    EXPECT_NE(capture.text().find("osgBTF::MaterialNode: a child that is the node itself or one "
                                  "of its parents would make a cycle; it is left out"),
              std::string::npos)
        << capture.text();
}

// OSG's ASCII reader never returns from a string that the stream ends inside; the serializers
// refuse such a string before handing it to OSG (readWrappedStringChecked). Both inputs ran for
// minutes before, so the test's timeout is the hang criterion.
TEST_F(FuzzFindings, SceneEndingInsideAnEmbeddedMaterialIsRefused) {
    osgDB::ReaderWriter* osgt = osgDB::Registry::instance()->getReaderWriterForExtension("osgt");
    ASSERT_NE(osgt, nullptr);
    struct Case {
        const char* name;
        std::string message, warning;
    };
    const std::string node = " At osgBTF::MaterialNode ";
    const std::string children = " (the node draws its children without the material)";
    // The parameter count says 4000000000: names are read on past the list to the stream end.
    // The texture list ends in whitespace; the refusal's message is then replaced by OSG's for
    // the sizes read after it, and the empty name is what the material reports.
    for (const Case& c :
         {Case{"hang-parameter-count-4000000000.osgt",
               "InputStream: the stream ends inside a string (truncated or damaged)" + node,
               "osgBTF::MaterialNode: material embedded in the scene: a parameter has no name "
               "(damaged or truncated)" +
                   children},
          Case{"hang-texture-count-truncated.osgt",
               "InputStream: Failed to read from stream." + node,
               "osgBTF::MaterialNode: material embedded in the scene: a texture has no name "
               "(damaged or truncated)" +
                   children}}) {
        std::ifstream in(input("scene_file", c.name), std::ios::binary);
        std::stringstream scene;
        scene << in.rdbuf();
        osgBTF::test::ScopedNotifyCapture capture;
        osgDB::ReaderWriter::ReadResult result = osgt->readNode(scene);
        EXPECT_FALSE(result.validNode()) << c.name;
        EXPECT_EQ(result.message(), c.message) << c.name;
        EXPECT_NE(capture.text().find(c.warning), std::string::npos) << c.name << capture.text();
    }
}

}  // namespace

}  // namespace OSGBTF_TEST_FILE
