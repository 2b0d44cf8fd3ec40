// inputs whose headers claim absurd sizes are refused before anything sized
// from the claim is allocated. Every hostile file is written here byte by byte (or written small
// and patched), and each refusal runs in a forked child whose peak RSS growth is measured.
#include <sys/wait.h>
#include <unistd.h>

#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <iostream>
#include <string>
#include <vector>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <gtest/gtest.h>

#include "core/CoordinateMap.h"
#include "core/Error.h"
#include "core/FittedMaterialFile.h"
#include "core/FloatImage.h"
#include "core/MeasuredBtf.h"
#include "core/SizeGuard.h"
#include "loaders/LoadBtf.h"
#include "loaders/Ubo2003.h"
#include "loaders/Ubo2014.h"
#include "tests/PluginTestUtil.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;
namespace fs = std::filesystem;

namespace {

using osgBTF::test::kSanitized;

/** The issue's bound on the peak memory of a refusal. */
constexpr long kMaxGrowthKiB = 100 * 1024;

/** The memory limit the refusals run under: far above the 100 MB bound, so code that allocated
 *  part of a claim before checking it would show in the RSS growth, yet below every claim. */
constexpr std::uint64_t kLimit = std::uint64_t(8) << 30;

class MemoryLimit {
public:
    explicit MemoryLimit(std::uint64_t bytes) : _saved(memoryLimit()) { setMemoryLimit(bytes); }
    ~MemoryLimit() { setMemoryLimit(_saved); }

private:
    std::uint64_t _saved;
};

long statusKiB(const char* field) {
    std::ifstream in("/proc/self/status");
    std::string line;
    const std::size_t n = std::strlen(field);
    while (std::getline(in, line))
        if (line.compare(0, n, field) == 0) return std::stol(line.substr(n));
    return -1;
}

struct Refusal {
    std::string message;
    long growthKiB = -1;  ///< peak RSS during the call minus RSS before it
};

/** Runs `f` in a forked child and returns its error message and its peak RSS growth: VmHWM after
 *  the call minus VmRSS just before it, both of the child, whose only work in between is `f`
 *  (the child starts with the parent's pages, so the test's own files do not count). A child
 *  killed (e.g. by the OOM killer after a huge allocation) or hanging fails the test. */
Refusal refusalOf(const std::function<void()>& f) {
    int fds[2];
    if (pipe(fds) != 0) return {"pipe failed", -1};
    std::cout.flush();
    const pid_t pid = fork();
    if (pid == 0) {
        close(fds[0]);
        alarm(60);
        const long before = statusKiB("VmRSS:");
        const std::string message = errorOf(f);
        const long peak = statusKiB("VmHWM:");
        const std::string out = std::to_string(peak - before) + "\n" + message;
        for (std::size_t done = 0; done < out.size();) {
            const ssize_t n = write(fds[1], out.data() + done, out.size() - done);
            if (n <= 0) break;
            done += std::size_t(n);
        }
        _exit(0);  // no atexit handlers (LeakSanitizer, gtest) in the child
    }
    close(fds[1]);
    std::string text;
    char buffer[4096];
    for (ssize_t n; (n = read(fds[0], buffer, sizeof buffer)) > 0;) text.append(buffer, n);
    close(fds[0]);
    int status = 0;
    waitpid(pid, &status, 0);
    if (!WIFEXITED(status) || WEXITSTATUS(status) != 0)
        return {"child died (status " + std::to_string(status) + ")", -1};
    const std::size_t newline = text.find('\n');
    if (newline == std::string::npos) return {"child reported nothing", -1};
    return {text.substr(newline + 1), std::stol(text.substr(0, newline))};
}

void expectSmall(const Refusal& r, const std::string& what) {
    std::cout << "[ rss      ] " << what << ": peak RSS growth " << r.growthKiB << " KiB\n";
    ::testing::Test::RecordProperty(what, std::to_string(r.growthKiB) + " KiB");
    ASSERT_GE(r.growthKiB, 0) << r.message;
    // AddressSanitizer's shadow memory and quarantine inflate every RSS figure.
    if (!kSanitized) {
        EXPECT_LT(r.growthKiB, kMaxGrowthKiB) << what;
    }
}

// ---- bytes -----------------------------------------------------------------------------------

struct Bytes {
    std::string data;
    template <typename T>
    Bytes& put(T value) {
        data.append(reinterpret_cast<const char*>(&value), sizeof value);
        return *this;
    }
    Bytes& text(const std::string& s) {
        data += s;
        return *this;
    }
};

void writeBytes(const std::string& path, const std::string& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(bytes.data(), std::streamsize(bytes.size()));
}

std::string readBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

/** A valid uncompressed 1x1 float EXR written by OpenEXR, its header first passed to `edit`: the
 *  file the hostile EXR cases patch. */
void writeOnePixelExr(const std::string& path,
                      const std::function<void(Imf::Header&)>& edit = nullptr) {
    Imf::Header header(1, 1);
    header.compression() = Imf::NO_COMPRESSION;
    header.channels().insert("Y", Imf::Channel(Imf::FLOAT));
    if (edit) edit(header);
    float value = 0.5f;
    Imf::FrameBuffer frame;
    frame.insert("Y", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(&value), 4, 4));
    Imf::OutputFile file(path.c_str(), header);
    file.setFrameBuffer(frame);
    file.writePixels(1);
}

/** CRC-32 (ISO-HDLC), as PNG chunks and zip entries store it; table-driven because the tests
 *  checksum megabytes of member data. */
std::uint32_t crc32(const std::string& bytes) {
    static const std::vector<std::uint32_t> table = [] {
        std::vector<std::uint32_t> t(256);
        for (std::uint32_t n = 0; n < 256; ++n) {
            std::uint32_t c = n;
            for (int k = 0; k < 8; ++k) c = (c >> 1) ^ (0xedb88320u & (0u - (c & 1u)));
            t[n] = c;
        }
        return t;
    }();
    std::uint32_t crc = 0xffffffffu;
    for (unsigned char b : bytes) crc = table[(crc ^ b) & 0xffu] ^ (crc >> 8);
    return ~crc;
}

std::string bigEndian32(std::uint32_t v) {
    return {char(v >> 24), char(v >> 16), char(v >> 8), char(v)};
}

/** A PNG (RFC 2083) whose IHDR claims width x height 8-bit RGB pixels, with an empty zlib
 *  stream as its only IDAT: a decoder learns the size from the header and fails only when it
 *  reads the pixels. */
std::string pngHeader(std::uint32_t width, std::uint32_t height) {
    auto chunk = [](const std::string& type, const std::string& payload) {
        return bigEndian32(std::uint32_t(payload.size())) + type + payload +
               bigEndian32(crc32(type + payload));
    };
    const std::string ihdr =
        bigEndian32(width) + bigEndian32(height) + std::string("\x08\x02\x00\x00\x00", 5);
    return std::string("\x89PNG\r\n\x1a\n", 8) + chunk("IHDR", ihdr) +
           chunk("IDAT", std::string("\x78\x9c\x03\x00\x00\x00\x00\x01", 8)) + chunk("IEND", "");
}

/** A zip archive (APPNOTE 6.3) written by hand: each member's local header and data, the central
 *  directory and its end record. `claimed` (if set) is the uncompressed size the central
 *  directory gives member 0, in a Zip64 extra field when it does not fit 32 bits. */
struct ZipMember {
    std::string name, data;
    std::uint16_t method = 0;  // 0 stored, 8 deflated
};
std::string zipArchive(const std::vector<ZipMember>& members, std::uint64_t claimed = 0) {
    Bytes out, central;
    for (std::size_t i = 0; i < members.size(); ++i) {
        const ZipMember& m = members[i];
        const std::uint32_t offset = std::uint32_t(out.data.size());
        const std::uint32_t crc = crc32(m.data), size = std::uint32_t(m.data.size());
        const std::uint64_t full = i == 0 && claimed ? claimed : size;
        const bool zip64 = full > 0xfffffffeu;
        const std::uint32_t fullField = zip64 ? 0xffffffffu : std::uint32_t(full);
        out.put(std::uint32_t(0x04034b50)).put(std::uint16_t(zip64 ? 45 : 20));
        out.put(std::uint16_t(0)).put(m.method).put(std::uint32_t(0)).put(crc);
        out.put(zip64 ? 0xffffffffu : size).put(fullField);
        out.put(std::uint16_t(m.name.size())).put(std::uint16_t(zip64 ? 20 : 0)).text(m.name);
        if (zip64)
            out.put(std::uint16_t(1)).put(std::uint16_t(16)).put(full).put(std::uint64_t(size));
        out.text(m.data);
        central.put(std::uint32_t(0x02014b50)).put(std::uint16_t(45));
        central.put(std::uint16_t(zip64 ? 45 : 20)).put(std::uint16_t(0)).put(m.method);
        central.put(std::uint32_t(0)).put(crc).put(size).put(fullField);
        central.put(std::uint16_t(m.name.size())).put(std::uint16_t(zip64 ? 12 : 0));
        central.put(std::uint16_t(0)).put(std::uint16_t(0)).put(std::uint16_t(0));
        central.put(std::uint32_t(0)).put(offset).text(m.name);
        if (zip64) central.put(std::uint16_t(1)).put(std::uint16_t(8)).put(full);
    }
    const std::uint32_t centralOffset = std::uint32_t(out.data.size());
    out.text(central.data);
    out.put(std::uint32_t(0x06054b50)).put(std::uint16_t(0)).put(std::uint16_t(0));
    out.put(std::uint16_t(members.size())).put(std::uint16_t(members.size()));
    out.put(std::uint32_t(central.data.size())).put(centralOffset).put(std::uint16_t(0));
    return out.data;
}

std::string memberName(int lightTheta, int lightPhi, int viewTheta, int viewPhi,
                       const char* extension = "png") {
    char name[64];
    std::snprintf(name, sizeof name, "tl%03d pl%03d tv%03d pv%03d.%s", lightTheta, lightPhi,
                  viewTheta, viewPhi, extension);
    return name;
}

/** Overwrites the dataWindow attribute of the first EXR header (name, type "box2i", size 16,
 *  then xMin, yMin, xMax, yMax as little-endian int32). */
void patchDataWindow(const std::string& path, std::int32_t xMax, std::int32_t yMax) {
    std::string bytes = readBytes(path);
    const std::string key("dataWindow\0box2i\0", 17);
    const std::size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    std::memcpy(&bytes[at + key.size() + 4 + 8], &xMax, 4);
    std::memcpy(&bytes[at + key.size() + 4 + 12], &yMax, 4);
    writeBytes(path, bytes);
}

/** A scanline EXR with a header of width x height float R, G, B pixels and no pixel data: the
 *  library writes the header and an offset table of one entry per line (no compression). */
void writeExrHeaderOnly(const std::string& path, int width, int height) {
    Imf::Header header(width, height);
    header.compression() = Imf::NO_COMPRESSION;
    for (const char* c : {"R", "G", "B"}) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    Imf::OutputFile file(path.c_str(), header);
}

/** A UBO2014 DFMF header (formats.md section 2) of one view and one light whose first factor
 *  claims k components of 1 x 1 matrices, or, with views/lights set, a direction count. */
std::string dfmfHeader(std::uint32_t views, std::uint32_t lights, std::uint32_t k) {
    Bytes b;
    b.text("!DFMF08FCR");
    b.put(std::uint32_t(291)).put(std::uint32_t(4)).text(std::string(240, '\0'));
    b.put(1.0f).put(1.0f).put(1.0f).put(1.0f);      // ppmm, rgb scale
    b.put(std::uint32_t(0)).put(std::uint32_t(0));  // cosine, xml length
    b.put(std::uint32_t(3));                        // channels
    for (const char* n : {"R", "G", "B"}) b.put(std::uint32_t(1)).text(n);
    b.put(views).put(0.0f).put(0.0f).put(lights).put(0.0f).put(0.0f);
    b.put(std::uint32_t(1)).put(std::uint32_t(1)).put(std::uint32_t(0));  // 1x1, no rotations
    b.put(std::uint32_t(1)).put(std::int32_t(0));                         // max k, colour model
    for (int i = 0; i < 12; ++i) b.put(0.0f);                             // mean, matrix
    b.put(std::uint8_t(4)).put(k).put(std::uint32_t(1)).put(std::uint32_t(1));
    return b.data;
}

const std::string kRaise = " (raise it with --memory-limit or OSGBTF_MEMORY_LIMIT)";

}  // namespace

// ---- UBO2003 zips and folders ----------------------------------------------------------------

TEST(HostileInputs, ZipMemberClaimingSixtyFourGiBIsAZipBomb) {
    TempDir dir;
    const std::string path = dir.file("bomb.zip");
    const std::string name = memberName(0, 0, 0, 0);
    // 16 deflated bytes whose central directory entry claims 64 GiB (a Zip64 extra field).
    writeBytes(path, zipArchive({{name, std::string(16, '\0'), 8}}, std::uint64_t(64) << 30));
    MemoryLimit limit(kLimit);
    const Refusal r = refusalOf([&] { loadMeasuredBtf(path); });
    EXPECT_EQ(r.message, path + ": member '" + name +
                             "' claims 68719476736 bytes uncompressed from 16 deflated bytes, "
                             "more than deflate can expand (1032:1): a corrupt archive or a zip "
                             "bomb");
    expectSmall(r, "zip member claiming 64 GiB");
}

TEST(HostileInputs, ZipMemberAboveTheMemoryLimitIsRefusedBeforeReading) {
    TempDir dir;
    const std::string path = dir.file("large.zip");
    const std::string name = memberName(0, 0, 0, 0);
    // 1 MiB deflated claiming 1 GiB: within deflate's ratio, beyond a 256 MiB limit.
    writeBytes(path, zipArchive({{name, std::string(1 << 20, '\0'), 8}}, std::uint64_t(1) << 30));
    MemoryLimit limit(std::uint64_t(256) << 20);
    const Refusal r = refusalOf([&] { loadMeasuredBtf(path); });
    EXPECT_EQ(r.message, path + ": member '" + name +
                             "' of 1073741824 bytes: needs 1.0 GiB, more than the memory limit "
                             "of 256.0 MiB" +
                             kRaise);
    expectSmall(r, "zip member claiming 1 GiB over a 256 MiB limit");
}

TEST(HostileInputs, ZipMemberLargerThanAnyImageEncodingIsRefused) {
    TempDir dir;
    const std::string png = dir.file("pixel.png"), path = dir.file("padded.zip");
    writeFloatImage(FloatImage(1, 1, 3), png);
    const std::string second = memberName(0, 0, 0, 1);
    // A 1x1 first image bounds every other member at 32 bytes a pixel + 16 MiB = 16777248 bytes;
    // the second stores 17 MiB. Read by the loader's parallel pipeline, so not in a forked child
    // (threads do not survive a fork).
    writeBytes(path, zipArchive({{memberName(0, 0, 0, 0), readBytes(png), 0},
                                 {second, std::string(17 << 20, '\0'), 0}}));
    MemoryLimit limit(kLimit);
    EXPECT_EQ(errorOf([&] { loadMeasuredBtf(path); }),
              path + ": member '" + second +
                  "' is 17825792 bytes, more than any encoding of the archive's images needs (at "
                  "most 16777248 bytes)");
}

TEST(HostileInputs, ZipOfEightThousandDirectionsAllocatesNoGrid) {
    TempDir dir;
    const std::string path = dir.file("directions.zip");
    // Member i lights and views from its own direction: 8000 light and 8000 view directions,
    // so 64 million (light, view) slots, of which 8000 are filled.
    std::vector<ZipMember> members;
    for (int i = 0; i < 8000; ++i)
        members.push_back({memberName(i / 360, i % 360, i / 360, i % 360), "", 0});
    writeBytes(path, zipArchive(members));
    MemoryLimit limit(kLimit);
    const Refusal r = refusalOf([&] { loadMeasuredBtf(path); });
    EXPECT_EQ(r.message, path +
                             ": 63992000 of 64000000 (light, view) images are missing, e.g. "
                             "'tl000 pl000 tv000 pv001' (found 8000 light and 8000 view "
                             "directions)");
    expectSmall(r, "zip of 8000 x 8000 directions");
}

TEST(HostileInputs, PngClaiming100000x100000PixelsIsRefusedBeforeDecoding) {
    TempDir dir;
    const std::string folder = dir.file("btf");
    fs::create_directory(folder);
    const std::string png = folder + "/" + memberName(0, 0, 0, 0);
    writeBytes(png, pngHeader(100000, 100000));
    MemoryLimit limit(kLimit);
    // 1e10 texels x 3 floats = 1.2e11 bytes = 111.8 GiB.
    Refusal r = refusalOf([&] { loadMeasuredBtf(folder); });
    EXPECT_EQ(r.message, folder +
                             ": BTF of 100000x100000 texels x 1 views x 1 lights: needs 111.8 "
                             "GiB, more than the memory limit of 8.0 GiB" +
                             kRaise);
    expectSmall(r, "PNG claiming 100000x100000 in a UBO2003 folder");

    const std::string zip = dir.file("png.zip");
    writeBytes(zip, zipArchive({{memberName(0, 0, 0, 0), readBytes(png), 0}}));
    r = refusalOf([&] { loadMeasuredBtf(zip); });
    EXPECT_EQ(r.message, zip +
                             ": BTF of 100000x100000 texels x 1 views x 1 lights: needs 111.8 "
                             "GiB, more than the memory limit of 8.0 GiB" +
                             kRaise);
    expectSmall(r, "PNG claiming 100000x100000 in a UBO2003 zip");

    r = refusalOf([&] { readFloatImage(png); });
    EXPECT_EQ(r.message, png +
                             ": 100000x100000 pixels x 3 channels: needs 111.8 GiB, more than "
                             "the memory limit of 8.0 GiB" +
                             kRaise);
    expectSmall(r, "PNG claiming 100000x100000 through readFloatImage");
}

// ---- UBO2014 .btf ----------------------------------------------------------------------------

TEST(HostileInputs, BtfClaiming2To31DirectionsIsRefusedByTheFileSize) {
    TempDir dir;
    const std::string views = dir.file("views.btf"), lights = dir.file("lights.btf");
    // The header up to the view count, then 12 bytes: one view's angles and light count.
    const std::string full = dfmfHeader(1, 1, 1);
    const std::size_t viewCountAt = 10 + 291;
    std::string bytes = full.substr(0, viewCountAt);
    const std::uint32_t huge = 0x80000000u;
    bytes.append(reinterpret_cast<const char*>(&huge), 4);
    bytes += full.substr(viewCountAt + 4, 12);
    writeBytes(views, bytes);
    writeBytes(lights, dfmfHeader(1, huge, 1));
    MemoryLimit limit(kLimit);
    Refusal r = refusalOf([&] { readUbo2014(views); });
    // 2^31 views x (2 angles + light count) x 4 bytes = 25769803776.
    EXPECT_EQ(r.message, views +
                             ": unexpected end of file while reading view directions: the header "
                             "announces 25769803776 bytes but only 12 remain (truncated or "
                             "corrupt file)");
    expectSmall(r, ".btf claiming 2^31 views");

    r = refusalOf([&] { readUbo2014(lights); });
    // 2^31 lights x 2 angles x 4 bytes; the rest of the header (8 + 12 + 8 + 48 + 13) remains.
    EXPECT_EQ(r.message, lights +
                             ": unexpected end of file while reading view 0 light directions: "
                             "the header announces 17179869184 bytes but only 89 remain "
                             "(truncated or corrupt file)");
    expectSmall(r, ".btf claiming 2^31 lights");
}

TEST(HostileInputs, BtfClaiming2To31ComponentsIsRefusedBeforeAllocating) {
    TempDir dir;
    const std::string path = dir.file("components.btf");
    writeBytes(path, dfmfHeader(1, 1, 0x80000000u));
    MemoryLimit limit(kLimit);
    // (1 U row + 1 SxV row + S) x 2^31 floats = 24 GiB.
    Refusal r = refusalOf([&] { readUbo2014(path); });
    EXPECT_EQ(r.message, path +
                             ": channel 0 factors: needs 24.0 GiB, more than the memory limit "
                             "of 8.0 GiB" +
                             kRaise);
    expectSmall(r, ".btf claiming 2^31 components");

    // A header-only read (btf info) allocates no factors; the file size refuses the claim.
    LoadOptions headerOnly;
    headerOnly.headerOnly = true;
    r = refusalOf([&] { readUbo2014(path, headerOnly); });
    EXPECT_EQ(r.message, path +
                             ": unexpected end of file while reading channel 0 factors: the "
                             "header announces 25769803776 bytes but only 0 remain (truncated "
                             "or corrupt file)");
    expectSmall(r, ".btf claiming 2^31 components, header only");
}

// ---- OpenEXR: images, fitted materials, coordinate maps --------------------------------------

TEST(HostileInputs, ExrClaiming100000x100000PixelsIsRefusedBeforeReading) {
    TempDir dir;
    const std::string path = dir.file("huge.exr");
    writeExrHeaderOnly(path, 100000, 100000);
    MemoryLimit limit(kLimit);
    // 1.2e11 bytes of pixels + 24 bytes per row + 8 per chunk (OpenEXR's tables) = 111.8 GiB.
    Refusal r = refusalOf([&] { readFloatImage(path); });
    EXPECT_EQ(r.message, path +
                             ": 100000x100000 pixels x 3 channels: needs 111.8 GiB, more than "
                             "the memory limit of 8.0 GiB" +
                             kRaise);
    expectSmall(r, "EXR claiming 100000x100000");

    r = refusalOf([&] { readExrParts(path); });
    EXPECT_EQ(r.message,
              path + ": 1 part: needs 111.8 GiB, more than the memory limit of 8.0 GiB" + kRaise);
    expectSmall(r, "EXR claiming 100000x100000, all parts");
}

TEST(HostileInputs, ExrWhoseChunkTableIsLargerThanTheFileIsRefused) {
    TempDir dir;
    const std::string path = dir.file("tall.exr");
    writeOnePixelExr(path);
    // One row per chunk: 1073741001 chunks, an 8 GiB offset table that OpenEXR's C++ reader
    // would allocate (and zero) on opening the file.
    patchDataWindow(path, 0, 1073741000);
    const std::string size = std::to_string(fs::file_size(path));
    MemoryLimit limit(kLimit);
    const std::string expected = path +
                                 ": the headers announce 1073741001 chunks, whose offset table "
                                 "alone takes 8.0 GiB, but the file holds only " +
                                 size + " bytes (truncated or corrupt file)";
    Refusal r = refusalOf([&] { readFloatImage(path); });
    EXPECT_EQ(r.message, expected);
    expectSmall(r, "EXR with a 2^30-row window in a small file");
    r = refusalOf([&] { loadFittedMaterial(path); });
    EXPECT_EQ(r.message, expected);
    expectSmall(r, "fitted material with a 2^30-row window in a small file");

    // The same file as a UBO2003 member, which OIIO would open with OpenEXR's C++ reader.
    const std::string zip = dir.file("tall.zip"), name = memberName(0, 0, 0, 0, "exr");
    writeBytes(zip, zipArchive({{name, readBytes(path), 0}}));
    r = refusalOf([&] { loadMeasuredBtf(zip); });
    EXPECT_EQ(r.message, zip + ": member '" + name +
                             "': the headers announce 1073741001 chunks, whose offset table "
                             "alone takes 8.0 GiB, but the file holds only " +
                             size + " bytes (truncated or corrupt file)");
    expectSmall(r, "EXR member with a 2^30-row window in a UBO2003 zip");
}

TEST(HostileInputs, ExrHeaderWithAnAttributeTwiceIsRefused) {
    TempDir dir;
    const std::string path = dir.file("twice.exr");
    writeOnePixelExr(path, [](Imf::Header& header) {
        header.insert("noteA", Imf::StringAttribute("abcd"));
        header.insert("noteB", Imf::StringAttribute("efgh"));
    });
    // Attribute names are NUL-terminated in the header: "noteB" becomes a second "noteA". OpenEXR's
    // C++ reader keeps the last of two, its C library the first.
    std::string bytes = readBytes(path);
    const std::size_t at = bytes.find(std::string("noteB") + '\0');
    ASSERT_NE(at, std::string::npos);
    bytes[at + 4] = 'A';
    writeBytes(path, bytes);
    EXPECT_EQ(refusalOf([&] { readFloatImage(path); }).message,
              path + ": OpenEXR header: attribute 'noteA' appears twice (corrupt file)");
}

TEST(HostileInputs, ExrAttributeClaimingTwoGiBIsRefusedBeforeOpenExrAllocatesIt) {
    TempDir dir;
    const std::string path = dir.file("note.exr");
    writeOnePixelExr(
        path, [](Imf::Header& header) { header.insert("note", Imf::StringAttribute("abcd")); });
    // An attribute is name\0 type\0 size(int32 LE) value: the string's size 4 becomes 2^31 - 16.
    // OpenEXR's C++ reader resizes a std::string to the claim before reading it (the fuzz
    // campaign's finding, fuzz/README.md).
    std::string bytes = readBytes(path);
    const std::string field = std::string("note") + '\0' + "string" + '\0';
    const std::size_t at = bytes.find(field);
    ASSERT_NE(at, std::string::npos);
    const std::size_t sizeAt = at + field.size();
    ASSERT_EQ(bytes.substr(sizeAt, 4), std::string("\x04\0\0\0", 4));
    bytes.replace(sizeAt, 4, std::string("\xf0\xff\xff\x7f", 4));
    writeBytes(path, bytes);
    const std::string remain = std::to_string(bytes.size() - sizeAt - 4);
    const std::string expected = path +
                                 ": OpenEXR header: attribute 'note' (string) claims 2147483632 "
                                 "bytes but " +
                                 remain + " remain in the file (truncated or corrupt file)";
    MemoryLimit limit(kLimit);
    Refusal r = refusalOf([&] { readFloatImage(path); });
    EXPECT_EQ(r.message, expected);
    expectSmall(r, "EXR image with a string attribute claiming 2 GiB");
    r = refusalOf([&] { loadFittedMaterial(path); });
    EXPECT_EQ(r.message, expected);
    expectSmall(r, "fitted material with a string attribute claiming 2 GiB");

    // An attribute of a type OpenEXR does not know is read as opaque bytes of the claimed size.
    std::string opaque = bytes;
    opaque.replace(at + 5, 6, "strinx");
    writeBytes(path, opaque);
    r = refusalOf([&] { loadFittedMaterial(path); });
    EXPECT_EQ(r.message, path +
                             ": OpenEXR header: attribute 'note' (strinx) claims 2147483632 "
                             "bytes but " +
                             remain + " remain in the file (truncated or corrupt file)");
    expectSmall(r, "fitted material with an attribute of unknown type claiming 2 GiB");
}

TEST(HostileInputs, FittedMaterialWithAbsurdWindowOrDepthIsRefused) {
    TempDir dir;
    FittedMaterial material;
    material.method = "lambert";
    MaterialTexture t;
    t.name = "albedo";
    t.width = 4;
    t.height = 4;
    t.channels = 3;
    t.data.assign(t.valueCount(), 0.25f);
    material.textures.push_back(t);
    const std::string wide = dir.file("wide.exr"), deep = dir.file("deep.exr");
    saveFittedMaterial(material, wide);
    fs::copy_file(wide, deep);
    // A row of a billion texels; the 4 rows (one chunk) keep the offset table as it is.
    patchDataWindow(wide, 999999999, 3);
    MemoryLimit limit(kLimit);
    Refusal r = refusalOf([&] { loadFittedMaterial(wide); });
    // 1e9 x 4 x 3 values, read through two float buffers: 96e9 bytes; OpenEXR's two line
    // buffers of 16 lines (ZIP) of the full width: 1e9 x 16 x 3 x 4 x 2 = 384e9 bytes; together
    // 480e9 bytes = 447.0 GiB.
    EXPECT_EQ(r.message, wide +
                             ": textures of 1 part(s), the largest 1000000000x4 pixels x 3 "
                             "channels: needs 447.0 GiB, more than the memory limit of 8.0 GiB" +
                             kRaise);
    expectSmall(r, "fitted material 1e9 texels wide");

    // The same file as a scene's material, through the osgdb_btfmat plugin.
    const std::string btfmat = dir.file("wide.btfmat");
    fs::copy_file(wide, btfmat);
    r = refusalOf([&] {
        const osgDB::ReaderWriter::ReadResult result = readNode(btfmat);
        throw Error(result.success() ? "read" : result.message());
    });
    EXPECT_EQ(r.message, btfmat +
                             ": textures of 1 part(s), the largest 1000000000x4 pixels x 3 "
                             "channels: needs 447.0 GiB, more than the memory limit of 8.0 GiB" +
                             kRaise);
    expectSmall(r, "fitted material 1e9 texels wide through osgdb_btfmat");

    // osgBTF.depth (int attribute: name, type, size 4, value) claiming 2^31 - 1 slices.
    std::string bytes = readBytes(deep);
    const std::string key("osgBTF.depth\0int\0", 17);
    const std::size_t at = bytes.find(key);
    ASSERT_NE(at, std::string::npos);
    const std::int32_t depth = 0x7fffffff;
    std::memcpy(&bytes[at + key.size() + 4], &depth, 4);
    writeBytes(deep, bytes);
    r = refusalOf([&] { loadFittedMaterial(deep); });
    EXPECT_EQ(r.message, deep +
                             ": texture 'albedo' has 4 rows, not a multiple of its depth "
                             "2147483647");
    expectSmall(r, "fitted material of depth 2^31 - 1");
}

TEST(HostileInputs, CoordinateMapWithAbsurdSizeIsRefused) {
    TempDir dir;
    const std::string path = dir.file("map.exr");
    CoordinateMap map(4, 4, 2, 2);
    writeCoordinateMap(map, path);
    patchDataWindow(path, 999999999, 3);
    MemoryLimit limit(kLimit);
    const Refusal r = refusalOf([&] { readCoordinateMap(path); });
    // 1e9 x 4 texels x 2 channels x 4 bytes (32e9) + OpenEXR's two line buffers of 16 lines
    // (ZIP) of the full width, 1e9 x 16 x 2 x 4 x 2 (256e9) + 4 rows x 24 + 1 chunk x 8 = 268.2
    // GiB.
    EXPECT_EQ(r.message, path +
                             ": 1000000000x4 pixels x 2 channels: needs 268.2 GiB, more than the "
                             "memory limit of 8.0 GiB" +
                             kRaise);
    expectSmall(r, "coordinate map 1e9 texels wide");
}

// The measurement itself: a valid load of similar size grows the RSS by little, and an
// allocation of 200 MiB in the child shows as at least that, so the method can fail.
TEST(HostileInputs, RssMeasurementSeesAnAllocation) {
    const Refusal r = refusalOf([] {
        std::vector<char> block(std::size_t(200) << 20, 1);
        throw Error("allocated " + std::to_string(block.size()));
    });
    std::cout << "[ rss      ] 200 MiB allocation: peak RSS growth " << r.growthKiB << " KiB\n";
    EXPECT_EQ(r.message, "allocated 209715200");
    EXPECT_GE(r.growthKiB, 200 * 1024);
}

}  // namespace OSGBTF_TEST_FILE
