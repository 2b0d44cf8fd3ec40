#include "fuzz/FuzzEntries.h"

#include <fcntl.h>
#include <unistd.h>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <osg/Notify>
#include <osgDB/FileNameUtils>
#include <osgDB/Options>
#include <osgDB/ReaderWriter>
#include <osgDB/Registry>

#include "core/CoordinateMap.h"
#include "core/Error.h"
#include "core/FittedMaterialFile.h"
#include "core/ImageCodecs.h"
#include "core/MeasuredBtf.h"
#include "core/Progress.h"
#include "loaders/Ubo2003.h"
#include "loaders/Ubo2014.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "plugins/btf/ReaderWriterBTF.h"
#include "streaming/TileCodec.h"
#include "streaming/TileSet.h"

namespace fs = std::filesystem;

namespace osgBTF::fuzz {

namespace {

/** Far above what the seeds need (a few KB) and far below libFuzzer's 2 GB RSS limit, so a header
 *  claiming a huge size meets the memory guard instead of the allocator. 32 MiB, not more: inputs
 *  that fill buffers up to the limit dominate the time per input (at 256 MiB fitted_material ran
 *  at 8 executions/s, each zero-filling and freeing hundreds of MB under ASan). */
constexpr std::uint64_t kMemoryLimit = std::uint64_t(32) << 20;
/** decodeUbo2014 only for BTFs of at most this many values: decoding is not parsing, and a
 *  valid 100-byte file can describe millions of values (e.g. rank 0 factors). */
constexpr std::uint64_t kMaxDecodedValues = std::uint64_t(1) << 20;

/** OSG's own serializers loop or allocate from counts in an .osgt file without a bound: a
 *  truncated osg::Group with `Children 10000000` takes 20 s in stock osgconv, each child a failed
 *  read (fuzz/README.md, fuzz/open/). osgBTF cannot change that, so scene_file does not read an
 *  input with a bare number above this (or a negative one, which OSG reads as a huge unsigned):
 *  the target fuzzes osgBTF's serializers, whose own counts FuzzFindings tests with such values. */
constexpr unsigned long long kMaxSceneCount = 10000;

bool hasLargeCount(const std::string& text) {
    bool quoted = false;
    for (std::size_t i = 0; i < text.size();) {
        if (text[i] == '"') {
            quoted = !quoted;
            ++i;
            continue;
        }
        if (quoted || std::isspace(static_cast<unsigned char>(text[i]))) {
            ++i;
            continue;
        }
        std::size_t end = i;
        while (end < text.size() && !std::isspace(static_cast<unsigned char>(text[end])) &&
               text[end] != '"')
            ++end;
        const std::string token = text.substr(i, end - i);
        const std::size_t digit = token[0] == '-' || token[0] == '+' ? 1 : 0;
        if (digit < token.size() && std::isdigit(static_cast<unsigned char>(token[digit]))) {
            // Base 0, as strtoul: OSG reads "0x..." as hexadecimal.
            const unsigned long long value = std::strtoull(token.c_str() + digit, nullptr, 0);
            if (value > kMaxSceneCount || (token[0] == '-' && value != 0)) return true;
        }
        i = end;
    }
    return false;
}

std::string g_fixtures;

/** The loaders read files: each input is written to one file per process and extension in a
 *  private folder under the temporary directory (tmpfs on most systems), rewritten per input. */
std::string writeInput(const std::uint8_t* data, std::size_t size, const std::string& name) {
    // Removed at exit, so test runs leave nothing behind.
    static const struct Folder {
        fs::path path = fs::temp_directory_path() / ("osgbtf-fuzz-" + std::to_string(::getpid()));
        Folder() { fs::create_directories(path); }
        ~Folder() {
            std::error_code ignored;
            fs::remove_all(path, ignored);
        }
    } folder;
    const std::string path = (folder.path / name).string();
    std::ofstream out(path, std::ios::binary | std::ios::trunc);
    out.write(reinterpret_cast<const char*>(data), std::streamsize(size));
    out.close();
    if (!out) throw Error(path + ": cannot write the fuzz input");
    return path;
}

/** The process works in `dir` while alive, so file names from an input resolve only there. */
class InFolder {
public:
    explicit InFolder(const std::string& dir) : _previous(::open(".", O_RDONLY | O_DIRECTORY)) {
        if (::chdir(dir.c_str()) != 0) throw Error(dir + ": cannot enter the fixtures folder");
    }
    ~InFolder() {
        if (_previous >= 0) {
            if (::fchdir(_previous) != 0) std::perror("osgBTF fuzz: fchdir");
            ::close(_previous);
        }
    }
    InFolder(const InFolder&) = delete;
    InFolder& operator=(const InFolder&) = delete;

private:
    int _previous;
};

const osgBTF::plugin::ReaderWriterBTF& reader(const std::string& extension) {
    // One per extension, as the four plugin modules; built once (their option tables walk the
    // method registry).
    static const osg::ref_ptr<osgBTF::plugin::ReaderWriterBTF> btfmat =
        new osgBTF::plugin::ReaderWriterBTF("btfmat");
    static const osg::ref_ptr<osgBTF::plugin::ReaderWriterBTF> btf =
        new osgBTF::plugin::ReaderWriterBTF("btf");
    static const osg::ref_ptr<osgBTF::plugin::ReaderWriterBTF> zip =
        new osgBTF::plugin::ReaderWriterBTF("btfzip");  // osgdb_btfzip's: ".zip" and ".btfzip"
    static const osg::ref_ptr<osgBTF::plugin::ReaderWriterBTF> pseudo =
        new osgBTF::plugin::ReaderWriterBTF("btfmaterial");
    if (extension == "btf") return *btf;
    if (extension == "zip") return *zip;
    if (extension == "btfmaterial") return *pseudo;
    return *btfmat;
}

}  // namespace

const std::vector<Target>& targets() {
    static const std::vector<Target> all = {
        {"ubo2003_zip", ubo2003Zip},
        {"ubo2014", ubo2014},
        {"fitted_material", fittedMaterial},
        {"coordinate_map", coordinateMap},
        {"btfmat_plugin", btfmatPlugin},
        {"plugin_names", pluginNames},
        {"scene_file", sceneFile},
        {"bsvtf_tiles", bsvtfTiles},
        {"rti_files", rtiFiles},
    };
    return all;
}

const Target* findTarget(const std::string& name) {
    for (const Target& target : targets())
        if (name == target.name) return &target;
    return nullptr;
}

void setUp(const std::string& fixtures) {
    g_fixtures = fs::absolute(fixtures).string();
    setMemoryLimit(kMemoryLimit);
    Progress::setEnabled(false);
    osg::setNotifyLevel(osg::FATAL);
    // One-time loads outside any input's time: libFuzzer's per-input timeout once fired on the
    // first input of fuzz_ubo2003_zip and fuzz_plugin_names on a busy machine, inside dlopen of
    // the image codecs module (OpenImageIO, under ASan) and of OSG's own plugins (issue 47).
    try {
        imageCodecs();
    } catch (const Error&) {
        // Then each input that needs it gets the same Error, as without this.
    }
    reader("btfmat");
    osgDB::Registry::instance()->getReaderWriterForExtension("osgt");
}

void ubo2003Zip(const std::uint8_t* data, std::size_t size) {
    const std::string path = writeInput(data, size, "input.zip");
    if (!mayBeUbo2003(path)) return;
    loadUbo2003(path);
}

void ubo2014(const std::uint8_t* data, std::size_t size) {
    const std::string path = writeInput(data, size, "input.btf");
    LoadOptions headerOnly;
    headerOnly.headerOnly = true;
    readUbo2014(path, headerOnly);
    const Ubo2014Factors factors = readUbo2014(path);
    // long double: the product of header fields can wrap around 64 bits.
    const long double values = (long double)factors.width * factors.height * factors.views.size() *
                               factors.lights.size() * 3;
    if (values <= (long double)kMaxDecodedValues) {
        LoadOptions half;
        half.storage = Storage::Half;
        decodeUbo2014(factors, half);
    }
}

void fittedMaterial(const std::uint8_t* data, std::size_t size) {
    loadFittedMaterial(writeInput(data, size, "input.exr"));
}

void rtiFiles(const std::uint8_t* data, std::size_t size) {
    if (size >= 1 && data[0] == '{') {
        // relight's web layout, packed into one input: info.json, then each plane_N.jpg after
        // the line "--plane--" (make_seeds.cpp packs the test fixtures so), in a fresh folder.
        const fs::path folder =
            fs::path(writeInput(data, 0, "relight-marker")).parent_path() / "relight";
        std::error_code ignored;
        fs::remove_all(folder, ignored);
        fs::create_directories(folder);
        const std::string bytes(reinterpret_cast<const char*>(data), size);
        const std::string separator = "\n--plane--\n";
        std::size_t at = 0;
        for (int part = 0; part <= 16; ++part) {
            const std::size_t end = bytes.find(separator, at);
            std::string piece = bytes.substr(at, end == std::string::npos ? end : end - at);
            std::string name = part == 0 ? "relight/info.json"
                                         : "relight/plane_" + std::to_string(part - 1) + ".jpg";
            // A piece "@NAME\n..." is the file NAME of the folder instead (the deep-zoom layout:
            // plane_0.dzi, plane_0_files/0/0_0.jpg), NAME of [a-z0-9_./] without "..".
            if (part > 0 && !piece.empty() && piece[0] == '@') {
                const std::size_t line = piece.find('\n');
                const std::string file = piece.substr(1, line == std::string::npos ? 0 : line - 1);
                if (!file.empty() && file.size() < 64 && file.find("..") == std::string::npos &&
                    file[0] != '/' &&
                    file.find_first_not_of("abcdefghijklmnopqrstuvwxyz0123456789_./") ==
                        std::string::npos) {
                    name = "relight/" + file;
                    fs::create_directories((folder / file).parent_path(), ignored);
                    piece = piece.substr(line + 1);
                }
            }
            writeInput(reinterpret_cast<const std::uint8_t*>(piece.data()), piece.size(), name);
            if (end == std::string::npos) break;
            at = end + separator.size();
        }
        loadMaterial((folder / "info.json").string());
        return;
    }
    // A PTM file begins with its version; anything else is tried as an .rti (comments first).
    const bool ptm = size >= 3 && std::memcmp(data, "PTM", 3) == 0;
    loadMaterial(writeInput(data, size, ptm ? "input.ptm" : "input.rti"));
}

void coordinateMap(const std::uint8_t* data, std::size_t size) {
    readCoordinateMap(writeInput(data, size, "input-map.exr"));
}

void btfmatPlugin(const std::uint8_t* data, std::size_t size) {
    const std::string path = writeInput(data, size, "input.btfmat");
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options("cache=off");
    reader("btfmat").readNode(path, options.get());
}

void pluginNames(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    const auto newline = text.find('\n');
    const std::string name = text.substr(0, newline);
    const std::string optionString = newline == std::string::npos ? "" : text.substr(newline + 1);
    if (name.find('/') != std::string::npos || name.find("..") != std::string::npos ||
        name.find('\0') != std::string::npos || name.find("cache=") != std::string::npos)
        return;
    InFolder inFixtures(g_fixtures);
    // cache=off last: the last word wins, so no input writes fits anywhere.
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options(optionString + " cache=off");
    const std::string extension = osgDB::getLowerCaseFileExtension(name);
    reader(extension).readNode(name, options.get());
}

void sceneFile(const std::uint8_t* data, std::size_t size) {
    osgDB::ReaderWriter* osgt = osgDB::Registry::instance()->getReaderWriterForExtension("osgt");
    if (!osgt) throw Error("osgDB has no .osgt reader (Debian's osgdb_osg plugin)");
    const std::string text(reinterpret_cast<const char*>(data), size);
    if (hasLargeCount(text)) return;
    // Text starting "<?xml" goes to OSG's XML reader (osgDB::XmlNode::read), which loops on
    // damaged input (fuzz/open/osg-xml-reader-hang.osgt: over 6 s for 200 bytes, in Debian's
    // libosgDB, no osgBTF code on the stack); osgBTF's scenes are .osgt and .osgb.
    if (text.rfind("<?xml", 0) == 0) return;
    InFolder inFixtures(g_fixtures);
    std::istringstream in(text);
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options("cache=off");
    osgt->readNode(in, options.get());
}

void bsvtfTiles(const std::uint8_t* data, std::size_t size) {
    const std::string text(reinterpret_cast<const char*>(data), size);
    if (text.rfind("osgBTF-bsvtf", 0) == 0) {
        const TileSetIndex index = TileSetIndex::parse(text, "fuzz.bsvtf");
        index.serialize();
        return;
    }
    constexpr int kSide = 16;
    std::vector<Imath::half> out(kSide * kSide * 4),
        prediction(kSide * kSide * 4, Imath::half(0.5f));
    TileCodecSettings settings;
    settings.unit = 0.01f;
    try {
        decodeTile(data, size, nullptr, kSide, settings, out.data(), "fuzz.tile");
    } catch (const Error&) {
    }
    decodeTile(data, size, prediction.data(), kSide, settings, out.data(), "fuzz.tile");
}

}  // namespace osgBTF::fuzz
