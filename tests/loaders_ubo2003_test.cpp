// UBO2003 / ATRIUM zip and folder loader, and the matching writer.
#include <unistd.h>

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <functional>
#include <set>
#include <string>
#include <vector>

#include <OpenImageIO/imageio.h>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "loaders/LoadBtf.h"
#include "loaders/Ubo2003.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using osgBTF::test::runCommand;
using osgBTF::test::shellQuote;
using osgBTF::test::TempDir;

using osgBTF::test::errorOf;

namespace {

// Non-square texels catch transposed images; the light and view sets differ so a swapped
// light/view index shows up too.
constexpr int kW = 8, kH = 4;

DirectionSet smallLights() {
    return DirectionSet("l", {{0, 0}, {30, 90}, {60, 180}});
}
DirectionSet smallViews() {
    return DirectionSet("v", {{0, 0}, {45, 270}});
}

/** A value in [0,1] that is an exact multiple of 1/255 and differs per view, light, texel and
 *  channel. */
float exact8(std::size_t view, std::size_t light, int x, int y, int c) {
    const int k = int(view * 37 + light * 23 + x * 11 + y * 29 + c * 71) % 256;
    return float(k) / 255.0f;
}

/** Smooth enough for JPEG. */
float smooth(std::size_t view, std::size_t light, int x, int y, int c) {
    return 0.3f + 0.05f * float(view) + 0.1f * float(light) + 0.02f * x + 0.03f * y + 0.05f * c;
}

MeasuredBtf makeBtf(const DirectionSet& views, const DirectionSet& lights, int w, int h,
                    const std::function<float(std::size_t, std::size_t, int, int, int)>& f) {
    MeasuredBtf btf(w, h, views, lights);
    for (std::size_t v = 0; v < views.size(); ++v)
        for (std::size_t l = 0; l < lights.size(); ++l)
            for (int y = 0; y < h; ++y)
                for (int x = 0; x < w; ++x)
                    for (int c = 0; c < 3; ++c)
                        btf.setValue(v, l, std::size_t(y) * w + x, c, f(v, l, x, y, c));
    return btf;
}

MeasuredBtf smallBtf(const std::function<float(std::size_t, std::size_t, int, int, int)>& f) {
    return makeBtf(smallViews(), smallLights(), kW, kH, f);
}

/** Writes a PNG of w x h RGB pixels, rows top first. */
void writePng(const std::string& path, int w, int h, const std::vector<unsigned char>& rgb) {
    auto out = OIIO::ImageOutput::create(path);
    ASSERT_TRUE(out);
    OIIO::ImageSpec spec(w, h, 3, OIIO::TypeDesc::UINT8);
    ASSERT_TRUE(out->open(path, spec));
    ASSERT_TRUE(out->write_image(OIIO::TypeDesc::UINT8, rgb.data()));
    ASSERT_TRUE(out->close());
}

/** A folder of PNG members for the small BTF, to be edited and zipped by the failure tests. */
std::string makeImageFolder(const TempDir& dir, const std::string& name = "images") {
    const std::string folder = dir.file(name);
    writeUbo2003Folder(smallBtf(exact8), folder, Ubo2003ImageFormat::Png);
    return folder;
}

/** Zips the contents of folder (paths relative to it) with the zip command-line tool. */
std::string zipFolder(const std::string& folder, const std::string& zipPath) {
    const auto result =
        runCommand("cd " + shellQuote(folder) + " && zip -q -r " + shellQuote(zipPath) + " .");
    EXPECT_EQ(result.exitCode, 0) << result.output;
    return zipPath;
}

std::string memberPath(const std::string& folder, int index, int lt, int lp, int vt, int vp,
                       const char* ext = "png") {
    char name[80];
    std::snprintf(name, sizeof name, "%05d tl%03d pl%03d tv%03d pv%03d.%s", index, lt, lp, vt, vp,
                  ext);
    return (fs::path(folder) / name).string();
}

void expectEqualBtf(const MeasuredBtf& expected, const MeasuredBtf& actual, float tolerance) {
    ASSERT_EQ(actual.width(), expected.width());
    ASSERT_EQ(actual.height(), expected.height());
    ASSERT_TRUE(actual.views() == expected.views());
    ASSERT_TRUE(actual.lights() == expected.lights());
    float worst = 0;
    for (std::size_t v = 0; v < expected.viewCount(); ++v)
        for (std::size_t l = 0; l < expected.lightCount(); ++l)
            for (std::size_t t = 0; t < expected.texelCount(); ++t)
                for (int c = 0; c < 3; ++c)
                    worst = std::max(
                        worst, std::abs(actual.value(v, l, t, c) - expected.value(v, l, t, c)));
    EXPECT_LE(worst, tolerance);
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Failures: each names the file and the exact problem, and nothing crashes.

TEST(Ubo2003Loader, TruncatedZipReportsLibzipError) {
    TempDir dir;
    const std::string zip = dir.file("cut.zip");
    writeUbo2003Zip(smallBtf(exact8), zip, Ubo2003ImageFormat::Png);
    fs::resize_file(zip, fs::file_size(zip) / 2);
    const std::string message = errorOf([&] { loadUbo2003(zip); });
    EXPECT_NE(message.find(zip + ": cannot open zip archive"), std::string::npos) << message;
    EXPECT_NE(message.find("Not a zip archive"), std::string::npos) << message;
}

TEST(Ubo2003Loader, MissingMemberIsNamedAndCounted) {
    TempDir dir;
    const std::string folder = makeImageFolder(dir);
    fs::remove(memberPath(folder, 3, 30, 90, 45, 270));
    const std::string zip = zipFolder(folder, dir.file("missing.zip"));
    const std::string message = errorOf([&] { loadUbo2003(zip); });
    EXPECT_NE(message.find(zip + ": 1 of 6 (light, view) images are missing"), std::string::npos)
        << message;
    EXPECT_NE(message.find("tl030 pl090 tv045 pv270"), std::string::npos) << message;
}

TEST(Ubo2003Loader, DuplicateMemberNamesBoth) {
    TempDir dir;
    const std::string folder = makeImageFolder(dir);
    fs::create_directory(fs::path(folder) / "again");
    fs::copy_file(memberPath(folder, 2, 30, 90, 0, 0),
                  fs::path(folder) / "again" / "tl030 pl090 tv000 pv000.png");
    const std::string zip = zipFolder(folder, dir.file("dup.zip"));
    const std::string message = errorOf([&] { loadUbo2003(zip); });
    EXPECT_NE(message.find(zip + ": members '"), std::string::npos) << message;
    EXPECT_NE(message.find("00002 tl030 pl090 tv000 pv000.png"), std::string::npos) << message;
    EXPECT_NE(message.find("again/tl030 pl090 tv000 pv000.png"), std::string::npos) << message;
    EXPECT_NE(message.find("hold the same image"), std::string::npos) << message;
}

TEST(Ubo2003Loader, ImagesOfDifferentSizesAreRefused) {
    TempDir dir;
    const std::string folder = makeImageFolder(dir);
    const std::string odd = memberPath(folder, 5, 60, 180, 45, 270);
    writePng(odd, 4, 2, std::vector<unsigned char>(4 * 2 * 3, 100));
    const std::string zip = zipFolder(folder, dir.file("sizes.zip"));
    const std::string message = errorOf([&] { loadUbo2003(zip); });
    EXPECT_NE(message.find(zip + ": member '00005 tl060 pl180 tv045 pv270.png' is 4x2 pixels"),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("is 8x4"), std::string::npos) << message;
}

TEST(Ubo2003Loader, NonImageWithImageNameIsAnError) {
    TempDir dir;
    const std::string folder = makeImageFolder(dir);
    osgBTF::test::writeTextFile(memberPath(folder, 1, 0, 0, 45, 270), "not a png at all\n");
    const std::string zip = zipFolder(folder, dir.file("text.zip"));
    const std::string message = errorOf([&] { loadUbo2003(zip); });
    EXPECT_NE(message.find(zip + ": member '00001 tl000 pl000 tv045 pv270.png'"), std::string::npos)
        << message;
    EXPECT_NE(message.find("not a decodable image"), std::string::npos) << message;
}

TEST(Ubo2003Loader, CorruptJpegNamesTheMember) {
    TempDir dir;
    const std::string folder = dir.file("jpegs");
    writeUbo2003Folder(smallBtf(smooth), folder, Ubo2003ImageFormat::Jpeg);
    const std::string victim = memberPath(folder, 4, 60, 180, 0, 0, "jpg");
    std::string bytes = osgBTF::test::readTextFile(victim);
    ASSERT_GT(bytes.size(), 200u);
    // Keep the SOI marker, destroy the headers that follow.
    for (std::size_t i = 2; i < 120; ++i) bytes[i] = char(0x5a);
    osgBTF::test::writeTextFile(victim, bytes);
    const std::string zip = zipFolder(folder, dir.file("corrupt.zip"));
    const std::string message = errorOf([&] { loadUbo2003(zip); });
    EXPECT_NE(message.find(zip + ": member '00004 tl060 pl180 tv000 pv000.jpg'"), std::string::npos)
        << message;
    EXPECT_TRUE(message.find("not a decodable image") != std::string::npos ||
                message.find("corrupt image") != std::string::npos)
        << message;
}

TEST(Ubo2003Loader, TruncatedJpegIsAnError) {
    TempDir dir;
    const std::string folder = dir.file("jpegs");
    writeUbo2003Folder(smallBtf(smooth), folder, Ubo2003ImageFormat::Jpeg);
    const std::string victim = memberPath(folder, 4, 60, 180, 0, 0, "jpg");
    fs::resize_file(victim, fs::file_size(victim) / 2);
    const std::string message = errorOf([&] { loadUbo2003(folder); });
    EXPECT_NE(message.find(folder + ": member '00004 tl060 pl180 tv000 pv000.jpg'"),
              std::string::npos)
        << message;
}

TEST(Ubo2003Loader, ArchiveWithoutBtfImages) {
    TempDir dir;
    const std::string folder = dir.file("other");
    fs::create_directory(folder);
    osgBTF::test::writeTextFile(folder + "/README.txt", "hello\n");
    writePng(folder + "/photo.png", 2, 2, std::vector<unsigned char>(12, 7));
    const std::string zip = zipFolder(folder, dir.file("none.zip"));
    const std::string message = errorOf([&] { loadUbo2003(zip); });
    EXPECT_NE(message.find(zip + ": no BTF images (tlTTT plPPP tvTTT pvPPP.jpg) found"),
              std::string::npos)
        << message;
}

TEST(Ubo2003Loader, LookalikeNameWithOtherExtensionIsAnError) {
    TempDir dir;
    const std::string folder = makeImageFolder(dir);
    osgBTF::test::writeTextFile(folder + "/tl000 pl000 tv000 pv000.txt", "notes\n");
    const std::string zip = zipFolder(folder, dir.file("lookalike.zip"));
    const std::string message = errorOf([&] { loadUbo2003(zip); });
    EXPECT_NE(message.find(zip + ": member 'tl000 pl000 tv000 pv000.txt' looks like a BTF image"),
              std::string::npos)
        << message;
}

TEST(Ubo2003Loader, AngleOutOfRangeIsAnError) {
    TempDir dir;
    const std::string folder = makeImageFolder(dir);
    fs::rename(memberPath(folder, 0, 0, 0, 0, 0), folder + "/tl095 pl000 tv000 pv000.png");
    const std::string message = errorOf([&] { loadUbo2003(folder); });
    EXPECT_NE(message.find(folder + ": member 'tl095 pl000 tv000 pv000.png': light theta 95 is "
                                    "outside [0, 90] degrees"),
              std::string::npos)
        << message;
}

TEST(Ubo2003Loader, MemoryGuardRefusesBeforeAllocating) {
    TempDir dir;
    const std::string zip = dir.file("small.zip");
    writeUbo2003Zip(smallBtf(exact8), zip, Ubo2003ImageFormat::Png);
    const std::uint64_t saved = memoryLimit();
    setMemoryLimit(1000);  // the BTF needs 8*4*6*3*4 = 2304 bytes
    const std::string message = errorOf([&] { loadUbo2003(zip); });
    setMemoryLimit(saved);
    EXPECT_NE(message.find(zip + ": BTF of 8x4 texels x 2 views x 3 lights: needs"),
              std::string::npos)
        << message;
    EXPECT_NE(message.find("memory limit"), std::string::npos) << message;
}

TEST(Ubo2003Writer, RefusesNonIntegerDirections) {
    TempDir dir;
    const DirectionSet odd("odd", {{0, 0}, {23.5f, 15}});
    const MeasuredBtf btf = makeBtf(odd, odd, 2, 2, exact8);
    const std::string zip = dir.file("odd.zip");
    const std::string message = errorOf([&] { writeUbo2003Zip(btf, zip); });
    EXPECT_NE(message.find(zip + ": light 1 has angle 23.5 degrees"), std::string::npos) << message;
    EXPECT_NE(message.find("integer degrees"), std::string::npos) << message;
    EXPECT_FALSE(fs::exists(zip));
    EXPECT_FALSE(fs::exists(zip + ".tmp" + std::to_string(getpid())));
}

// ---------------------------------------------------------------------------------------------
// Names.

TEST(Ubo2003Loader, ParsesDocumentedNames) {
    Ubo2003Name n;
    ASSERT_TRUE(parseUbo2003Name("00008 tl000 pl000 tv030 pv030.jpg", n));
    EXPECT_EQ(n.index, 8);
    EXPECT_EQ(n.lightTheta, 0);
    EXPECT_EQ(n.lightPhi, 0);
    EXPECT_EQ(n.viewTheta, 30);
    EXPECT_EQ(n.viewPhi, 30);
    EXPECT_EQ(n.extension, "jpg");
    ASSERT_TRUE(
        parseUbo2003Name("UBO2003/MANYFILES/tv030_pv030/00162 tl015 pl060 tv000 pv000.JPG", n));
    EXPECT_EQ(n.index, 162);
    EXPECT_EQ(n.lightTheta, 15);
    EXPECT_EQ(n.lightPhi, 60);
    EXPECT_EQ(n.viewTheta, 0);
    EXPECT_EQ(n.viewPhi, 0);
    EXPECT_EQ(n.extension, "jpg");
    ASSERT_TRUE(parseUbo2003Name("tl075 pl345 tv060 pv342.hdr", n));
    EXPECT_EQ(n.index, -1);
    EXPECT_EQ(n.lightPhi, 345);
    EXPECT_EQ(n.viewPhi, 342);
    EXPECT_EQ(n.extension, "hdr");
    EXPECT_FALSE(parseUbo2003Name("tl75 pl345 tv060 pv342.jpg", n));
    EXPECT_FALSE(parseUbo2003Name("tl075 pl345 tv060 pv342.txt", n));
    EXPECT_FALSE(parseUbo2003Name("tl075_pl345_tv060_pv342.jpg", n));
    EXPECT_FALSE(parseUbo2003Name("0008 tl000 pl000 tv030 pv030.jpg", n));
}

TEST(Ubo2003Writer, MemberNamesFollowTheBonnIndex) {
    const DirectionSet bonn = DirectionSet::bonn81();
    EXPECT_EQ(ubo2003MemberName(8, bonn[0], bonn[8], Ubo2003ImageFormat::Jpeg),
              "00008 tl000 pl000 tv030 pv030.jpg");
    EXPECT_EQ(ubo2003MemberName(162, bonn[2], bonn[0], Ubo2003ImageFormat::Hdr),
              "00162 tl015 pl060 tv000 pv000.hdr");
}

// ---------------------------------------------------------------------------------------------
// Round trips and layout.

TEST(Ubo2003Loader, PngZipRoundTripIsExact) {
    TempDir dir;
    const MeasuredBtf btf = smallBtf(exact8);
    const std::string zip = dir.file("png.zip");
    writeUbo2003Zip(btf, zip, Ubo2003ImageFormat::Png);
    const MeasuredBtf loaded = loadUbo2003(zip);
    EXPECT_EQ(loaded.source, zip);
    expectEqualBtf(btf, loaded, 1e-6f);
    // Not the Bonn set: directions sorted by theta, then phi.
    EXPECT_EQ(loaded.lights()[1].theta, 30.0f);
    EXPECT_EQ(loaded.lights()[1].phi, 90.0f);
    EXPECT_EQ(loaded.views()[1].phi, 270.0f);
}

TEST(Ubo2003Loader, PngQuantisesToEightBits) {
    TempDir dir;
    const MeasuredBtf btf = smallBtf(smooth);
    const std::string zip = dir.file("q.zip");
    writeUbo2003Zip(btf, zip, Ubo2003ImageFormat::Png);
    const MeasuredBtf loaded = loadUbo2003(zip);
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        for (int c = 0; c < 3; ++c) {
            const float v = btf.value(1, 2, t, c);
            EXPECT_NEAR(loaded.value(1, 2, t, c), std::round(std::clamp(v, 0.f, 1.f) * 255) / 255,
                        1e-6f);
        }
}

TEST(Ubo2003Loader, JpegZipRoundTripWithinBound) {
    TempDir dir;
    const MeasuredBtf btf = smallBtf(smooth);
    const std::string zip = dir.file("jpg.zip");
    writeUbo2003Zip(btf, zip, Ubo2003ImageFormat::Jpeg, 95);
    expectEqualBtf(btf, loadUbo2003(zip), 0.06f);
}

TEST(Ubo2003Loader, HdrZipRoundTripWithinRgbePrecision) {
    TempDir dir;
    const MeasuredBtf btf = smallBtf([](std::size_t v, std::size_t l, int x, int y, int c) {
        return 0.02f + 3.0f * exact8(v, l, x, y, c);  // HDR: values above 1
    });
    const std::string zip = dir.file("hdr.zip");
    writeUbo2003Zip(btf, zip, Ubo2003ImageFormat::Hdr);
    const MeasuredBtf loaded = loadUbo2003(zip);
    ASSERT_EQ(loaded.width(), kW);
    ASSERT_EQ(loaded.height(), kH);
    for (std::size_t v = 0; v < btf.viewCount(); ++v)
        for (std::size_t l = 0; l < btf.lightCount(); ++l)
            for (std::size_t t = 0; t < btf.texelCount(); ++t) {
                float maxChannel = 0;
                for (int c = 0; c < 3; ++c)
                    maxChannel = std::max(maxChannel, btf.value(v, l, t, c));
                // RGBE shares one exponent per pixel: error relative to the largest channel.
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(loaded.value(v, l, t, c), btf.value(v, l, t, c), 0.01f * maxChannel)
                        << "view " << v << " light " << l << " texel " << t;
            }
}

TEST(Ubo2003Loader, ExrFolderRoundTripIsExact) {
    TempDir dir;
    const MeasuredBtf btf = smallBtf([](std::size_t v, std::size_t l, int x, int y, int c) {
        return 5.0f * smooth(v, l, x, y, c) - 0.5f;
    });
    const std::string folder = dir.file("exr");
    writeUbo2003Folder(btf, folder, Ubo2003ImageFormat::Exr);
    expectEqualBtf(btf, loadUbo2003(folder), 0.0f);
}

TEST(Ubo2003Loader, HalfStorageAndDecodeCurves) {
    TempDir dir;
    const MeasuredBtf btf = smallBtf(exact8);
    const std::string zip = dir.file("png.zip");
    writeUbo2003Zip(btf, zip, Ubo2003ImageFormat::Png);
    LoadOptions half;
    half.storage = Storage::Half;
    const MeasuredBtf loadedHalf = loadUbo2003(zip, half);
    EXPECT_EQ(loadedHalf.storage(), Storage::Half);
    expectEqualBtf(btf, loadedHalf, 1e-3f);
    LoadOptions gamma;
    gamma.curve = LoadOptions::DecodeCurve::Gamma22;
    LoadOptions srgb;
    srgb.curve = LoadOptions::DecodeCurve::Srgb;
    const MeasuredBtf g = loadUbo2003(zip, gamma), s = loadUbo2003(zip, srgb);
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        const float v = btf.value(1, 1, t, 0);
        EXPECT_NEAR(g.value(1, 1, t, 0), std::pow(v, 2.2f), 1e-5f);
        const float expected = v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
        EXPECT_NEAR(s.value(1, 1, t, 0), expected, 1e-5f);
    }
}

TEST(Ubo2003Loader, TopRowOfImageFileIsTopRowOfBtf) {
    TempDir dir;
    const std::string folder = dir.file("orient");
    fs::create_directory(folder);
    // Every image: red top row (first in the file), black elsewhere; one 3x2 size, single pair.
    std::vector<unsigned char> rgb(3 * 2 * 3, 0);
    for (int x = 0; x < 3; ++x) rgb[std::size_t(x) * 3] = 255;
    writePng(folder + "/tl000 pl000 tv000 pv000.png", 3, 2, rgb);
    const MeasuredBtf btf = loadUbo2003(folder);
    ASSERT_EQ(btf.width(), 3);
    ASSERT_EQ(btf.height(), 2);
    for (int x = 0; x < 3; ++x) {
        EXPECT_EQ(btf.value(0, 0, std::size_t(1) * 3 + x, 0), 1.0f);  // row height-1
        EXPECT_EQ(btf.value(0, 0, std::size_t(x), 0), 0.0f);          // row 0
    }
}

TEST(Ubo2003Loader, HdrResolutionLineOrientationIsApplied) {
    // ATRIUM_HDR members carry "+X M -Y N" (formats.md 1.2): each stored scanline is an image
    // column, left to right, its pixels top to bottom. OIIO reports it as orientation 5.
    // "-Y N -X M" (orientation 2) stores rows top to bottom, each right to left.
    struct Case {
        const char* resolution;
        int width, height;
        std::function<int(int, int)> storedIndex;  ///< upright (x, y from top) -> stored pixel
    };
    const Case cases[] = {
        {"+X 2 -Y 4", 2, 4, [](int x, int y) { return x * 4 + y; }},
        {"-Y 2 -X 4", 4, 2, [](int x, int y) { return y * 4 + (3 - x); }},
    };
    for (const Case& test : cases) {
        SCOPED_TRACE(test.resolution);
        TempDir dir;
        const std::string folder = dir.file("atrium");
        fs::create_directory(folder);
        const std::string file = folder + "/tl000 pl000 tv000 pv000.hdr";
        std::vector<float> stored(4 * 2 * 3);
        for (int i = 0; i < 8; ++i)
            for (int c = 0; c < 3; ++c) stored[std::size_t(i) * 3 + c] = 0.25f * float(i + 1);
        {
            auto out = OIIO::ImageOutput::create(file);
            ASSERT_TRUE(out);
            ASSERT_TRUE(out->open(file, OIIO::ImageSpec(4, 2, 3, OIIO::TypeDesc::FLOAT)));
            ASSERT_TRUE(out->write_image(OIIO::TypeDesc::FLOAT, stored.data()));
            ASSERT_TRUE(out->close());
        }
        std::string bytes = osgBTF::test::readTextFile(file);
        const auto at = bytes.find("-Y 2 +X 4");
        ASSERT_NE(at, std::string::npos);
        bytes.replace(at, 9, test.resolution);
        osgBTF::test::writeTextFile(file, bytes);
        const MeasuredBtf btf = loadUbo2003(folder);
        ASSERT_EQ(btf.width(), test.width);
        ASSERT_EQ(btf.height(), test.height);
        for (int y = 0; y < test.height; ++y)
            for (int x = 0; x < test.width; ++x)
                EXPECT_NEAR(btf.value(0, 0, std::size_t(test.height - 1 - y) * test.width + x, 0),
                            0.25f * float(test.storedIndex(x, y) + 1), 1e-6f)
                    << "x " << x << " y " << y;
    }
}

TEST(Ubo2003Loader, NamingVariantsInZipsMadeByZipTool) {
    TempDir dir;
    const std::string root = dir.file("tree");
    const std::string base = root + "/UBO2003/MANYFILES";
    const MeasuredBtf btf = smallBtf(exact8);
    const DirectionSet lights = smallLights(), views = smallViews();
    for (std::size_t l = 0; l < lights.size(); ++l)
        for (std::size_t v = 0; v < views.size(); ++v) {
            char sub[32], name[64];
            std::snprintf(sub, sizeof sub, "tv%03d_pv%03d", int(views[v].theta), int(views[v].phi));
            // Half the members carry the index prefix, half do not; case of extensions varies.
            const int index = int(l * views.size() + v);
            if (index % 2)
                std::snprintf(name, sizeof name, "tl%03d pl%03d tv%03d pv%03d.PNG",
                              int(lights[l].theta), int(lights[l].phi), int(views[v].theta),
                              int(views[v].phi));
            else
                std::snprintf(name, sizeof name, "%05d tl%03d pl%03d tv%03d pv%03d.png", index,
                              int(lights[l].theta), int(lights[l].phi), int(views[v].theta),
                              int(views[v].phi));
            fs::create_directories(fs::path(base) / sub);
            std::vector<float> image = btf.image(v, l);
            std::vector<unsigned char> rgb(image.size());
            for (int y = 0; y < kH; ++y)
                for (int i = 0; i < kW * 3; ++i)
                    rgb[std::size_t(y) * kW * 3 + i] = (unsigned char)std::lround(
                        image[std::size_t(kH - 1 - y) * kW * 3 + i] * 255);
            writePng((fs::path(base) / sub / name).string(), kW, kH, rgb);
        }
    // Junk an archiver adds, and an unrelated file.
    fs::create_directories(root + "/__MACOSX/UBO2003/MANYFILES");
    osgBTF::test::writeTextFile(root + "/__MACOSX/UBO2003/MANYFILES/._tl000 pl000 tv000 pv000.png",
                                "resource fork");
    osgBTF::test::writeTextFile(base + "/._00000 tl000 pl000 tv000 pv000.png", "resource fork");
    osgBTF::test::writeTextFile(root + "/README.txt", "UBO2003 test\n");
    const std::string zip = zipFolder(root, dir.file("variants.zip"));
    const MeasuredBtf loaded = loadUbo2003(zip);
    expectEqualBtf(btf, loaded, 1e-6f);
    // The same tree loads as a folder, and through the dispatcher.
    expectEqualBtf(btf, loadUbo2003(root), 1e-6f);
    expectEqualBtf(btf, loadMeasuredBtf(zip), 1e-6f);
}

TEST(Ubo2003Loader, Bonn81ZipKeepsBonnOrderAndNames) {
    TempDir dir;
    const DirectionSet bonn = DirectionSet::bonn81();
    const MeasuredBtf btf = makeBtf(bonn, bonn, 4, 4, exact8);
    const std::string zip = dir.file("bonn.zip");
    writeUbo2003Zip(btf, zip, Ubo2003ImageFormat::Png);
    const auto listing = runCommand("unzip -l " + shellQuote(zip));
    EXPECT_NE(listing.output.find("00008 tl000 pl000 tv030 pv030.png"), std::string::npos);
    EXPECT_NE(listing.output.find("00162 tl015 pl060 tv000 pv000.png"), std::string::npos);
    const MeasuredBtf loaded = loadUbo2003(zip);
    EXPECT_TRUE(loaded.lights() == bonn);
    EXPECT_TRUE(loaded.views() == bonn);
    EXPECT_EQ(loaded.lights().name(), "bonn81");
    expectEqualBtf(btf, loaded, 1e-6f);
    // (light 0/0, view 30/30) is view index 8.
    EXPECT_EQ(loaded.value(8, 0, 5, 1), exact8(8, 0, 1, 1, 1));
}

TEST(Ubo2003Writer, JpegMembersAreStoredAndWriteIsAtomic) {
    TempDir dir;
    const std::string zip = dir.file("stored.zip");
    writeUbo2003Zip(smallBtf(smooth), zip, Ubo2003ImageFormat::Jpeg);
    EXPECT_FALSE(fs::exists(zip + ".tmp" + std::to_string(getpid())));
    const auto listing = runCommand("unzip -v " + shellQuote(zip));
    EXPECT_EQ(listing.exitCode, 0);
    EXPECT_NE(listing.output.find("Stored"), std::string::npos) << listing.output;
    EXPECT_EQ(listing.output.find("Defl"), std::string::npos) << listing.output;
}

}  // namespace OSGBTF_TEST_FILE
