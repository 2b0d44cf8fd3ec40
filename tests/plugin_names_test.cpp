// osgBTF's osgDB modules never take the file name of one of OpenSceneGraph's own plugins (an OSG
// built from source has osgdb_zip and osgdb_exr; installing osgBTF must neither overwrite nor
// hide them), and ".zip" BTFs and ".exr" images still read by file name: through the extension
// aliases libosgBTF registers, `-e btfzip` / `-e btfexr` on a stock program's command line, the
// pseudo-file names x.zip.btfzip and x.exr.btfexr, or the .deb's update-alternatives links
// (plugins/README.md, "Names"). No OpenGL here.
#include <algorithm>
#include <cctype>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <set>
#include <sstream>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <Imath/ImathBox.h>
#include <Imath/half.h>
#include <OpenEXR/ImfArray.h>
#include <OpenEXR/ImfRgbaFile.h>
#include <osg/Image>
#include <osg/Version>
#include <osgDB/ReadFile>
#include <osgDB/Registry>

#include "scene/MaterialNode.h"
#include "scene/OwnPlugins.h"
#include "tests/PluginTestUtil.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using osgBTF::test::buildDir;
using osgBTF::test::builtTool;
using osgBTF::test::CommandResult;
using osgBTF::test::runCommand;
using osgBTF::test::shellQuote;
using osgBTF::test::TempDir;

namespace {

std::string lower(std::string text) {
    for (char& c : text) c = char(std::tolower(static_cast<unsigned char>(c)));
    return text;
}

/** OpenSceneGraph 3.6's plugin names, written down from its sources (tag OpenSceneGraph-3.6.5,
 *  the same list on the OpenSceneGraph-3.6 branch): every folder of src/osgPlugins/, the names
 *  those folders' CMakeLists.txt give SETUP_PLUGIN where they differ (Inventor -> iv, shadow ->
 *  osgshadow, ...), and the serializer and .osg wrapper modules of src/osgWrappers/serializers/
 *  and src/osgWrappers/deprecated-dotosg/ (one per node kit). A module is osgdb_<name>.so. */
const std::set<std::string>& upstreamPluginNames() {
    static const std::set<std::string> names = [] {
        // `git ls-tree --name-only OpenSceneGraph-3.6.5 src/osgPlugins/` (folders only).
        const std::string folders =
            "3dc 3ds Inventor OpenCASCADE OpenFlight QTKit RestHttpDevice V8 ZeroConfDevice ac "
            "avfoundation bmp bsp bvh cfg curl dae dds dicom directshow dot dxf exr fbx ffmpeg "
            "freetype gdal gif gles glsl gstreamer gta gz hdr imageio ive jp2 jpeg ktx las logo "
            "lua lwo lws md2 mdl normals nvtt obj ogr osc osg osga osgjs osgtgz p3d pdf pic ply "
            "png pnm pov pvr python quicktime revisions rgb rot scale sdl shadow shp stl svg "
            "terrain tf tga tgz tiff trans trk txf txp view vnc vtf x zip";
        // SETUP_PLUGIN names that are not their folder's.
        const std::string renamed =
            "iv opencascade openflight resthttp zeroconf qt osgshadow osgterrain osgviewer";
        // The node kits with serializer (osgdb_serializers_<kit>) or .osg wrapper
        // (osgdb_deprecated_<kit>) modules.
        const std::string kits =
            "osg osganimation osgfx osgga osgmanipulator osgparticle osgshadow osgsim osgterrain "
            "osgtext osgui osgutil osgviewer osgvolume osgwidget";
        std::set<std::string> all;
        std::istringstream words(folders + " " + renamed);
        for (std::string word; words >> word;) all.insert(lower(word));
        std::istringstream kitWords(kits);
        for (std::string kit; kitWords >> kit;) {
            all.insert("serializers_" + kit);
            all.insert("deprecated_" + kit);
        }
        return all;
    }();
    return names;
}

const std::string kPluginFolder = std::string("osgPlugins-") + osgGetVersion();

/** The <name>s of the osgdb_<name>.so files in a folder (lower case, as osgDB asks for them). */
std::vector<std::string> modulesIn(const fs::path& folder) {
    std::vector<std::string> names;
    std::error_code error;
    for (const auto& entry : fs::directory_iterator(folder, error)) {
        const std::string file = entry.path().filename().string();
        if (file.rfind("osgdb_", 0) == 0 && entry.path().extension() == ".so")
            names.push_back(lower(file.substr(6, file.size() - 6 - 3)));
    }
    std::sort(names.begin(), names.end());
    return names;
}

/** A tiny UBO2003 BTF zip, written by the btf tool. */
std::string writeBtfZip(const TempDir& dir, const std::string& name) {
    const std::string zip = dir.file(name);
    const CommandResult made =
        runCommand(builtTool("btf") + " --no-progress sample --size 4 -o " + shellQuote(zip));
    EXPECT_EQ(made.exitCode, 0) << made.output;
    return zip;
}

/** A 4 x 2 half RGB EXR of one colour, written by OpenImageIO (not by osgBTF's plugin). */
std::string writeExr(const TempDir& dir, const std::string& name) {
    const std::string exr = dir.file(name);
    const CommandResult made = runCommand(
        "oiiotool --pattern constant:color=0.25,0.5,2.0 4x2 3 "
        "-d half -o " +
        shellQuote(exr));
    EXPECT_EQ(made.exitCode, 0) << made.output;
    return exr;
}

/** Every pixel of an EXR file, read with OpenEXR itself. */
std::vector<Imf::Rgba> exrPixels(const std::string& file) {
    Imf::RgbaInputFile in(file.c_str());
    const Imath::Box2i window = in.dataWindow();
    const int width = window.max.x - window.min.x + 1, height = window.max.y - window.min.y + 1;
    std::vector<Imf::Rgba> pixels(std::size_t(width) * height);
    in.setFrameBuffer(pixels.data() - window.min.x - window.min.y * width, 1, width);
    in.readPixels(window.min.y, window.max.y);
    return pixels;
}

void expectTheColour(const osg::Image& image, const std::string& what) {
    ASSERT_EQ(image.s(), 4) << what;
    ASSERT_EQ(image.t(), 2) << what;
    ASSERT_EQ(image.getPixelFormat(), GLenum(GL_RGB)) << what;
    ASSERT_EQ(image.getDataType(), GLenum(GL_HALF_FLOAT)) << what;
    const float expected[3] = {0.25f, 0.5f, 2.0f};  // exact in half
    for (int row = 0; row < 2; ++row)
        for (int x = 0; x < 4; ++x)
            for (int c = 0; c < 3; ++c) {
                Imath::half value;
                std::uint16_t bits;
                std::memcpy(&bits, image.data(x, row) + 2 * c, 2);
                value.setBits(bits);
                EXPECT_EQ(float(value), expected[c]) << what << " at " << x << "," << row;
            }
}

using osgBTF::test::kSanitized;

/** Stock osgconv with this build's plugins (and none of osgBTF's aliases: a fresh process that
 *  does not link libosgBTF). Empty when osgconv is not installed, or when the plugins are built
 *  with a sanitizer, whose runtime an uninstrumented osgconv does not have. */
std::string osgconv() {
    if (kSanitized || runCommand("command -v osgconv").exitCode != 0) return {};
    return "env -u LD_LIBRARY_PATH OSG_LIBRARY_PATH=" + shellQuote(buildDir() + "/lib") +
           " ASAN_OPTIONS=detect_leaks=0 osgconv ";
}

}  // namespace

TEST(PluginNames, NoModuleTakesTheNameOfAnOpenSceneGraphPlugin) {
    const std::vector<std::string> ours = modulesIn(fs::path(buildDir()) / "lib" / kPluginFolder);
    // The modules the build made, whatever CMake calls them; the two renamed ones among them.
    ASSERT_FALSE(ours.empty()) << "no osgdb_*.so in " << buildDir() << "/lib/" << kPluginFolder;
    EXPECT_NE(std::find(ours.begin(), ours.end(), "btfzip"), ours.end());
    EXPECT_NE(std::find(ours.begin(), ours.end(), "btfexr"), ours.end());
    for (const std::string& name : ours)
        EXPECT_EQ(upstreamPluginNames().count(name), 0u)
            << "osgdb_" << name << ".so is also an OpenSceneGraph plugin's name";
}

TEST(PluginNames, TheUpstreamListHoldsEveryPluginOfTheInstalledOsg) {
    // The list above is complete for the OSG this test runs with: every module in OSG's own
    // plugin folders (those on osgDB's library path, the build's excepted) is on it.
    std::size_t seen = 0;
    for (const std::string& path : osgDB::Registry::instance()->getLibraryFilePathList()) {
        // An entry holds osgPlugins-<version>/, or is that folder (Debian's OSG lists its own).
        fs::path entry = fs::path(path).lexically_normal();
        if (!entry.has_filename()) entry = entry.parent_path();  // a trailing '/'
        const fs::path folder = entry.filename() == kPluginFolder ? entry : entry / kPluginFolder;
        std::error_code error;
        if (fs::equivalent(folder, fs::path(buildDir()) / "lib" / kPluginFolder, error)) continue;
        for (const std::string& name : modulesIn(folder)) {
            if (name.rfind("btf", 0) == 0 || name == "serializers_osgbtf") continue;  // a .deb
            ++seen;
            EXPECT_EQ(upstreamPluginNames().count(name), 1u)
                << "osgdb_" << name << ".so in " << folder << " is missing from the list";
        }
    }
    if (seen == 0) GTEST_SKIP() << "no OpenSceneGraph plugin folder on osgDB's library path";
}

TEST(PluginNames, ZipAndExrLeadToOsgBtfsModules) {
    osgBTF::test::usePluginsFromBuild();
    const std::vector<std::string> aliased = osgBTF::aliasOwnPlugins();
    EXPECT_NE(std::find(aliased.begin(), aliased.end(), "zip"), aliased.end());
    EXPECT_NE(std::find(aliased.begin(), aliased.end(), "exr"), aliased.end());
    osgDB::Registry* registry = osgDB::Registry::instance();
    EXPECT_EQ(registry->createLibraryNameForExtension("zip"), kPluginFolder + "/osgdb_btfzip.so");
    EXPECT_EQ(registry->createLibraryNameForExtension("ZIP"), kPluginFolder + "/osgdb_btfzip.so");
    EXPECT_EQ(registry->createLibraryNameForExtension("exr"), kPluginFolder + "/osgdb_btfexr.so");
    // Each module's own extension leads to it: OSG's built-in aliases take none of them.
    for (const std::string& name : modulesIn(fs::path(buildDir()) / "lib" / kPluginFolder))
        EXPECT_EQ(registry->createLibraryNameForExtension(name),
                  kPluginFolder + "/osgdb_" + name + ".so");
}

TEST(PluginNames, BtfZipsAndExrImagesReadByFileName) {
    osgBTF::test::usePluginsFromBuild();
    TempDir dir;
    const std::string zip = writeBtfZip(dir, "wool.zip");
    const std::string exr = writeExr(dir, "sky.exr");
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options("method=lambert cache=off");
    for (const std::string& name : {zip, zip + ".btfzip"}) {
        osg::ref_ptr<osg::Node> node = osgDB::readRefNodeFile(name, options.get());
        const auto* material = dynamic_cast<osgBTF::MaterialNode*>(node.get());
        ASSERT_NE(material, nullptr) << name;
        EXPECT_NE(material->getMaterial(), nullptr) << name;
    }
    for (const std::string& name : {exr, exr + ".btfexr"}) {
        osg::ref_ptr<osg::Image> image = osgDB::readRefImageFile(name);
        ASSERT_TRUE(image.valid()) << name;
        expectTheColour(*image, name);
    }
    // The pseudo-name insists on a BTF: any other zip is an error naming the file.
    const std::string other = dir.file("notes.zip");
    const std::string folder = dir.file("notes");
    fs::create_directories(folder);
    osgBTF::test::writeTextFile(folder + "/README.txt", "hello\n");
    ASSERT_EQ(
        runCommand("cd " + shellQuote(folder) + " && zip -q " + shellQuote(other) + " README.txt")
            .exitCode,
        0);
    const osgDB::ReaderWriter::ReadResult result =
        osgDB::Registry::instance()->readNode(other + ".btfzip", options.get());
    EXPECT_EQ(result.status(), osgDB::ReaderWriter::ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message().rfind(other + ": not a measured BTF zip", 0), 0u)
        << result.message();
}

TEST(PluginNames, StockOsgconvReadsThemWithDashEOrAPseudoName) {
    const std::string tool = osgconv();
    if (tool.empty()) GTEST_SKIP() << "no osgconv, or a sanitizer build (.ci/run checks the .deb)";
    TempDir dir;
    const std::string zip = writeBtfZip(dir, "wool.zip");
    const std::string exr = writeExr(dir, "sky.exr");
    const std::string fit = "-O 'method=lambert cache=off' ";
    for (const std::string& input : {"-e btfzip " + shellQuote(zip), shellQuote(zip + ".btfzip")}) {
        const std::string out = dir.file("wool.osgt");
        fs::remove(out);
        const CommandResult converted = runCommand(tool + fit + input + " " + shellQuote(out));
        ASSERT_EQ(converted.exitCode, 0) << input << ": " << converted.output;
        EXPECT_NE(osgBTF::test::readTextFile(out).find("osgBTF::MaterialNode"), std::string::npos)
            << input;
    }
    // EXR in and out through osgdb_btfexr, the written file checked with OpenEXR itself.
    for (const std::string& arguments :
         {"-e btfexr " + shellQuote(exr) + " " + shellQuote(dir.file("copy1.exr")),
          shellQuote(exr + ".btfexr") + " " + shellQuote(dir.file("copy2.exr") + ".btfexr")}) {
        const CommandResult converted = runCommand(tool + arguments);
        ASSERT_EQ(converted.exitCode, 0) << arguments << ": " << converted.output;
    }
    for (const std::string& copy : {dir.file("copy1.exr"), dir.file("copy2.exr")}) {
        const std::vector<Imf::Rgba> pixels = exrPixels(copy);
        ASSERT_EQ(pixels.size(), 8u) << copy;
        for (const Imf::Rgba& p : pixels) {
            EXPECT_EQ(float(p.r), 0.25f) << copy;
            EXPECT_EQ(float(p.g), 0.5f) << copy;
            EXPECT_EQ(float(p.b), 2.0f) << copy;
        }
    }
}

// The .deb's maintainer scripts (cmake/debian/), run in a scratch root (DPKG_ROOT, which
// update-alternatives honours): OSG's names become links to our modules only where no real file
// has them, and removal takes back only those links.
TEST(PackageScripts, LinkOsgsPluginNamesToOursOnlyWhereFree) {
    const std::string postinst = buildDir() + "/debian/postinst";
    const std::string prerm = buildDir() + "/debian/prerm";
    ASSERT_TRUE(fs::exists(postinst) && fs::exists(prerm)) << "cmake/Package.cmake writes them";
    if (runCommand("command -v update-alternatives").exitCode != 0)
        GTEST_SKIP() << "no update-alternatives (package dpkg)";
    // The plugin folder as the script names it, e.g. /usr/lib/x86_64-linux-gnu/osgPlugins-3.6.5.
    const std::string script = osgBTF::test::readTextFile(postinst);
    const auto start = script.find("plugins=\"");
    ASSERT_NE(start, std::string::npos) << script;
    const std::string folder = script.substr(start + 9, script.find('"', start + 9) - start - 9);
    ASSERT_EQ(folder.rfind('/' + kPluginFolder), folder.size() - kPluginFolder.size() - 1)
        << folder;

    TempDir root;
    const fs::path plugins = root.path() / folder.substr(1);
    for (const char* dir : {"etc/alternatives", "var/lib/dpkg/alternatives", "var/log"})
        fs::create_directories(root.path() / dir);
    fs::create_directories(plugins);
    osgBTF::test::writeTextFile((plugins / "osgdb_btfzip.so").string(), "ours\n");
    osgBTF::test::writeTextFile((plugins / "osgdb_btfexr.so").string(), "ours\n");
    osgBTF::test::writeTextFile((plugins / "osgdb_exr.so").string(), "OpenSceneGraph's\n");
    const std::string env = "DPKG_ROOT=" + shellQuote(root.path().string()) + " sh ";

    const CommandResult installed = runCommand(env + shellQuote(postinst) + " configure");
    ASSERT_EQ(installed.exitCode, 0) << installed.output;
    // osgdb_zip.so was free: a link, through the alternatives folder, to osgdb_btfzip.so.
    const fs::path zip = plugins / "osgdb_zip.so";
    ASSERT_TRUE(fs::is_symlink(zip)) << installed.output;
    const fs::path alternative = fs::read_symlink(zip);
    EXPECT_EQ(alternative, "/etc/alternatives/osgbtf-osgdb_zip.so");
    EXPECT_EQ(fs::read_symlink(root.path() / alternative.relative_path()),
              fs::path(folder) / "osgdb_btfzip.so");
    // osgdb_exr.so was OSG's: left as it was.
    EXPECT_FALSE(fs::is_symlink(plugins / "osgdb_exr.so"));
    EXPECT_EQ(osgBTF::test::readTextFile((plugins / "osgdb_exr.so").string()),
              "OpenSceneGraph's\n");

    const CommandResult removed = runCommand(env + shellQuote(prerm) + " remove");
    ASSERT_EQ(removed.exitCode, 0) << removed.output;
    EXPECT_FALSE(fs::exists(fs::symlink_status(zip))) << removed.output;
    EXPECT_EQ(osgBTF::test::readTextFile((plugins / "osgdb_exr.so").string()),
              "OpenSceneGraph's\n");
    EXPECT_TRUE(fs::exists(plugins / "osgdb_btfzip.so"));  // dpkg's to remove, not the script's
}

}  // namespace OSGBTF_TEST_FILE
