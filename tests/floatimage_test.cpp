// Tests for core/FloatImage: EXR through OpenEXR, other formats through OIIO, errors, atomicity.
#include <unistd.h>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <limits>
#include <random>

#include <gtest/gtest.h>

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfOutputFile.h>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using osgBTF::test::runCommand;
using osgBTF::test::shellQuote;
using osgBTF::test::TempDir;

using osgBTF::test::errorOf;

namespace {

void oiiotool(const std::string& arguments) {
    const auto result = runCommand("oiiotool " + arguments);
    ASSERT_EQ(result.exitCode, 0) << result.output;
}

FloatImage noise(int width, int height, int channels, unsigned seed = 1) {
    FloatImage image(width, height, channels);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> dist(-100.0f, 100.0f);
    for (float& v : image.pixels) v = dist(rng);
    return image;
}

bool sameBits(float a, float b) {
    return std::memcmp(&a, &b, sizeof a) == 0;
}

std::vector<std::string> folderEntries(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

}  // namespace

TEST(FloatImage, ExrFloatRoundTripIsBitExactAndTopDown) {
    TempDir dir;
    FloatImage image = noise(5, 3, 4);
    image.at(0, 0, 0) = 1e-40f;  // denormal
    image.at(1, 0, 1) = 3e38f;
    image.at(4, 2, 3) = -0.0f;
    const std::string path = dir.file("a.exr");
    writeFloatImage(image, path);
    const FloatImage back = readFloatImage(path);
    ASSERT_EQ(back.width, 5);
    ASSERT_EQ(back.height, 3);
    ASSERT_EQ(back.channels, 4);
    EXPECT_EQ(back.channelNames, (std::vector<std::string>{"R", "G", "B", "A"}));
    for (std::size_t i = 0; i < image.pixels.size(); ++i)
        ASSERT_TRUE(sameBits(image.pixels[i], back.pixels[i])) << "value " << i;

    // Row 0 of a FloatImage is the file's first scanline (y = dataWindow.min.y).
    Imf::InputFile file(path.c_str());
    EXPECT_EQ(file.header().channels().findChannel("R")->type, Imf::FLOAT);
    std::vector<float> r(15);
    Imf::FrameBuffer fb;
    fb.insert("R", Imf::Slice(Imf::FLOAT, (char*)r.data(), sizeof(float), 5 * sizeof(float)));
    file.setFrameBuffer(fb);
    file.readPixels(0, 2);
    EXPECT_TRUE(sameBits(r[0], image.at(0, 0, 0)));
    EXPECT_EQ(r[5 * 2 + 3], image.at(3, 2, 0));
}

TEST(FloatImage, ExrHalfRoundTripKeepsHalfValues) {
    TempDir dir;
    FloatImage image = noise(4, 4, 3, 7);
    for (float& v : image.pixels) v = float(Imath::half(v));
    image.at(0, 0, 0) = 65504.0f;
    image.at(1, 0, 0) = 5.96046448e-08f;  // smallest half denormal
    const std::string path = dir.file("h.exr");
    writeFloatImage(image, path, /*half=*/true);
    Imf::InputFile file(path.c_str());
    EXPECT_EQ(file.header().channels().findChannel("G")->type, Imf::HALF);
    EXPECT_EQ(readFloatImage(path).pixels, image.pixels);
}

TEST(FloatImage, HalfOverflowIsAnErrorNotInf) {
    TempDir dir;
    FloatImage image(2, 1, 1);
    image.pixels = {1.0f, 70000.0f};
    const std::string path = dir.file("o.exr");
    EXPECT_EQ(errorOf([&] { writeFloatImage(image, path, true); }),
              path + ": 1 values exceed the half-float range (65504); write float instead");
    EXPECT_FALSE(fs::exists(path));
    writeFloatImage(image, path, false);
    EXPECT_EQ(readFloatImage(path).pixels[1], 70000.0f);
}

TEST(FloatImage, ReadsOiiotoolFloatAndHalfExactly) {
    TempDir dir;
    const std::string f = dir.file("f.exr"), h = dir.file("h.exr");
    oiiotool("--pattern constant:color=2.5,-1,0.25 4x3 3 -d float -o " + shellQuote(f));
    oiiotool("--pattern constant:color=2.5,-1,0.25 4x3 3 -d half -o " + shellQuote(h));
    for (const std::string& path : {f, h}) {
        const FloatImage image = readFloatImage(path);
        ASSERT_EQ(image.width, 4);
        ASSERT_EQ(image.height, 3);
        ASSERT_EQ(image.channels, 3);
        EXPECT_EQ(image.channelNames, (std::vector<std::string>{"R", "G", "B"}));
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 4; ++x) {
                EXPECT_EQ(image.at(x, y, 0), 2.5f);
                EXPECT_EQ(image.at(x, y, 1), -1.0f);
                EXPECT_EQ(image.at(x, y, 2), 0.25f);
            }
    }
}

TEST(FloatImage, RowZeroIsTheTopRowForExrAndPng) {
    TempDir dir;
    for (const char* name : {"g.exr", "g.png"}) {
        const std::string path = dir.file(name);
        oiiotool("--pattern fill:top=1,0,0:bottom=0,0,1 4x4 3 -d " +
                 std::string(std::strstr(name, "exr") ? "float" : "uint8") + " -o " +
                 shellQuote(path));
        const FloatImage image = readFloatImage(path);
        EXPECT_EQ(image.at(2, 0, 0), 1.0f) << name;
        EXPECT_EQ(image.at(2, 0, 2), 0.0f) << name;
        EXPECT_EQ(image.at(2, 3, 0), 0.0f) << name;
        EXPECT_EQ(image.at(2, 3, 2), 1.0f) << name;
    }
}

TEST(FloatImage, AnyChannelCountInNaturalOrder) {
    TempDir dir;
    FloatImage image = noise(3, 2, 12);
    const std::string path = dir.file("c.exr");
    writeFloatImage(image, path);  // default names c0..c11; EXR stores c0, c1, c10, c11, c2...
    const FloatImage back = readFloatImage(path);
    ASSERT_EQ(back.channels, 12);
    EXPECT_EQ(back.channelNames[2], "c2");
    EXPECT_EQ(back.channelNames[11], "c11");
    EXPECT_EQ(back.pixels, image.pixels);

    FloatImage layered(1, 1, 5);
    layered.channelNames = {"diffuse.R", "diffuse.G", "diffuse.B", "Z", "diffuse.A"};
    layered.pixels = {1, 2, 3, 4, 5};
    writeFloatImage(layered, dir.file("l.exr"));
    const FloatImage l = readFloatImage(dir.file("l.exr"));
    EXPECT_EQ(l.channelNames,
              (std::vector<std::string>{"Z", "diffuse.R", "diffuse.G", "diffuse.B", "diffuse.A"}));
    EXPECT_EQ(l.pixels, (std::vector<float>{4, 1, 2, 3, 5}));
    EXPECT_EQ(l.channelIndex("diffuse.B"), 3);

    layered.channelNames = {"R", "R", "B", "Z", "A"};
    EXPECT_EQ(errorOf([&] { writeFloatImage(layered, dir.file("d.exr")); }),
              dir.file("d.exr") + ": channel names repeat");
}

TEST(FloatImage, TiledOffsetUintAndMultiPartExr) {
    TempDir dir;
    const std::string tiled = dir.file("t.exr"), offset = dir.file("o.exr");
    oiiotool("--pattern constant:color=1,2,3,4 8x8 4 -d half --tile 4 4 -o " + shellQuote(tiled));
    FloatImage t = readFloatImage(tiled);
    ASSERT_EQ(t.width, 8);
    EXPECT_EQ(t.at(7, 7, 3), 4.0f);
    EXPECT_EQ(t.at(0, 0, 0), 1.0f);

    oiiotool("--pattern fill:top=1,0,0:bottom=0,0,1 4x3 3 -d float --origin +2+3 -o " +
             shellQuote(offset));
    const FloatImage o = readFloatImage(offset);
    EXPECT_EQ(o.width, 4);
    EXPECT_EQ(o.height, 3);
    EXPECT_EQ(o.at(0, 0, 0), 1.0f);

    const std::string uintPath = dir.file("u.exr");
    {
        Imf::Header header(2, 1);
        header.channels().insert("id", Imf::Channel(Imf::UINT));
        unsigned ids[2] = {7, 4000000};
        Imf::FrameBuffer fb;
        fb.insert("id", Imf::Slice(Imf::UINT, (char*)ids, sizeof(unsigned), 2 * sizeof(unsigned)));
        Imf::OutputFile out(uintPath.c_str(), header);
        out.setFrameBuffer(fb);
        out.writePixels(1);
    }
    EXPECT_EQ(readFloatImage(uintPath).pixels, (std::vector<float>{7.0f, 4000000.0f}));

    const std::string a = dir.file("pa.exr"), b = dir.file("pb.exr"), mp = dir.file("mp.exr");
    oiiotool("--pattern constant:color=1,2,3 4x3 3 -d float -o " + shellQuote(a));
    oiiotool("--pattern constant:color=5 4x3 1 -d half -o " + shellQuote(b));
    oiiotool(shellQuote(a) + " " + shellQuote(b) + " --siappend -o " + shellQuote(mp));
    const std::vector<FloatImage> parts = readExrParts(mp);
    ASSERT_EQ(parts.size(), 2u);
    EXPECT_EQ(parts[0].channels, 3);
    EXPECT_EQ(parts[1].channels, 1);
    EXPECT_EQ(readFloatImage(mp).at(0, 0, 2), 3.0f);
    EXPECT_EQ(readFloatImage(mp, 1).at(3, 2, 0), 5.0f);
    EXPECT_EQ(errorOf([&] { readFloatImage(mp, 5); }), mp + ": has 2 part(s), no part 5");
}

TEST(FloatImage, EightBitFormatsClampWithoutSrgbUnlessAsked) {
    TempDir dir;
    FloatImage image(5, 1, 4);
    image.channelNames = {"R", "G", "B", "A"};
    const float nan = std::numeric_limits<float>::quiet_NaN();
    image.pixels = {0.5f, 1.5f, -1.0f, 1.0f,  nan,  0.2f, 0.0f, 0.5f, 1.0f, 1.0f,
                    1.0f, 0.0f, 0.25f, 0.75f, 0.1f, 1.0f, 0.0f, 0.0f, 0.0f, 0.0f};
    const std::string png = dir.file("a.png");
    writeFloatImage(image, png);
    const FloatImage back = readFloatImage(png);
    ASSERT_EQ(back.channels, 4);
    const float tolerance = 0.5f / 255.0f + 1e-6f;
    EXPECT_NEAR(back.at(0, 0, 0), 0.5f, tolerance);  // no sRGB encoding
    EXPECT_EQ(back.at(0, 0, 1), 1.0f);
    EXPECT_EQ(back.at(0, 0, 2), 0.0f);
    EXPECT_EQ(back.at(1, 0, 0), 0.0f);  // NaN
    // Alpha 0.5 or 0 must not scale colour: the values are stored unassociated.
    EXPECT_NEAR(back.at(1, 0, 1), 0.2f, tolerance);
    EXPECT_EQ(back.at(2, 0, 0), 1.0f);
    EXPECT_EQ(back.at(2, 0, 3), 0.0f);

    const std::string srgb = dir.file("s.png");
    writeFloatImage(image, srgb, false, /*srgbEncode=*/true);
    const FloatImage s = readFloatImage(srgb);
    const float encoded = 1.055f * std::pow(0.5f, 1.0f / 2.4f) - 0.055f;
    EXPECT_NEAR(s.at(0, 0, 0), encoded, tolerance);
    EXPECT_NEAR(s.at(1, 0, 3), 0.5f, tolerance);  // alpha is not encoded

    EXPECT_NE(errorOf([&] { writeFloatImage(image, dir.file("a.jpg")); }).find("alpha"),
              std::string::npos);
    FloatImage rgb(2, 2, 3);
    rgb.pixels.assign(12, 0.5f);
    writeFloatImage(rgb, dir.file("a.jpg"));
    EXPECT_NEAR(readFloatImage(dir.file("a.jpg")).at(1, 1, 1), 0.5f, 2.0f / 255.0f);
}

TEST(FloatImage, HdrAndTiffThroughOiio) {
    TempDir dir;
    FloatImage image = noise(6, 4, 3, 3);
    for (float& v : image.pixels) v = std::abs(v);
    writeFloatImage(image, dir.file("a.tif"));
    EXPECT_EQ(readFloatImage(dir.file("a.tif")).pixels, image.pixels);
    writeFloatImage(image, dir.file("a.hdr"));
    const FloatImage hdr = readFloatImage(dir.file("a.hdr"));
    ASSERT_EQ(hdr.pixels.size(), image.pixels.size());
    // RGBE shares one exponent per pixel: relative to the pixel's largest value, ~1/256.
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 6; ++x) {
            const float m = std::max({image.at(x, y, 0), image.at(x, y, 1), image.at(x, y, 2)});
            for (int c = 0; c < 3; ++c) EXPECT_NEAR(hdr.at(x, y, c), image.at(x, y, c), m / 100);
        }
}

TEST(FloatImage, ReadErrorsNameTheFileAndTheProblem) {
    TempDir dir;
    const std::string missing = dir.file("missing.exr");
    EXPECT_EQ(errorOf([&] { readFloatImage(missing); }), missing + ": no such file");

    const std::string empty = dir.file("empty.exr");
    test::writeTextFile(empty, "");
    EXPECT_EQ(errorOf([&] { readFloatImage(empty); }), empty + ": file is empty");
    EXPECT_EQ(errorOf([&] { readExrParts(empty); }), empty + ": file is empty");

    const std::string png = dir.file("p.png"), renamed = dir.file("png.exr");
    oiiotool("--pattern constant:color=0.5 4x4 3 -d uint8 -o " + shellQuote(png));
    fs::copy_file(png, renamed);
    EXPECT_EQ(errorOf([&] { readFloatImage(renamed); }),
              renamed + ": not an OpenEXR file (wrong magic number)");
    EXPECT_EQ(errorOf([&] { readExrParts(png); }),
              png + ": not an OpenEXR file (wrong magic number)");

    const std::string garbage = dir.file("garbage.png");
    test::writeTextFile(garbage, "this is not a PNG file at all");
    const std::string g = errorOf([&] { readFloatImage(garbage); });
    EXPECT_EQ(g.rfind(garbage + ": ", 0), 0u) << g;

    // Truncated EXRs: in the pixel data and in the header.
    const std::string good = dir.file("good.exr");
    writeFloatImage(noise(64, 64, 3), good);
    const std::string data = test::readTextFile(good);
    for (std::size_t keep : {data.size() / 2, std::size_t(40)}) {
        const std::string cut = dir.file("cut" + std::to_string(keep) + ".exr");
        test::writeTextFile(cut, data.substr(0, keep));
        const std::string message = errorOf([&] { readFloatImage(cut); });
        EXPECT_EQ(message.rfind(cut + ": OpenEXR: ", 0), 0u) << message;
    }
    EXPECT_EQ(errorOf([&] { readFloatImage(good, -1); }), good + ": invalid part index -1");
    EXPECT_EQ(errorOf([&] { readFloatImage(dir.path().string()); }),
              dir.path().string() + ": is a folder, not an image file");
}

TEST(FloatImage, CountNonFiniteAndRequireFinite) {
    FloatImage image(3, 2, 2);
    image.channelNames = {"R", "G"};
    const float nan = std::numeric_limits<float>::quiet_NaN();
    const float inf = std::numeric_limits<float>::infinity();
    EXPECT_EQ(countNonFinite(image), 0u);
    EXPECT_NO_THROW(requireFinite(image, "x.exr"));
    image.at(1, 0, 1) = nan;
    image.at(2, 0, 0) = nan;
    image.at(0, 1, 1) = -inf;
    image.at(2, 1, 1) = nan;
    EXPECT_EQ(countNonFinite(image), 4u);
    EXPECT_EQ(errorOf([&] { requireFinite(image, "x.exr"); }),
              "x.exr: 3 NaN and 1 Inf values (first at x=1, y=0, channel 'G')");
}

TEST(FloatImage, WritesAreAtomic) {
    TempDir dir;
    const std::string path = dir.file("a.exr");
    const FloatImage first = noise(4, 4, 3, 1), second = noise(4, 4, 3, 2);
    writeFloatImage(first, path);
    writeFloatImage(first, dir.file("a.png"));
    EXPECT_EQ(folderEntries(dir.path()), (std::vector<std::string>{"a.exr", "a.png"}));

    const std::string nowhere = dir.file("no/such/folder/a.exr");
    EXPECT_EQ(errorOf([&] { writeFloatImage(first, nowhere); }),
              nowhere + ": folder '" + dir.file("no/such/folder") + "' does not exist");

    // A failure half-way leaves the old file and no temporary file.
    const std::string message = errorOf([&] {
        writeFileAtomically(path, [&](const std::string& temporary) {
            test::writeTextFile(temporary, "partial");
            fail(path, "disk full");
        });
    });
    EXPECT_EQ(message, path + ": disk full");
    EXPECT_EQ(readFloatImage(path).pixels, first.pixels);
    EXPECT_EQ(folderEntries(dir.path()), (std::vector<std::string>{"a.exr", "a.png"}));

    // The writer itself failing (its temporary name is taken by a folder) also keeps the file.
    fs::create_directory(path + ".tmp" + std::to_string(getpid()));
    EXPECT_NE(errorOf([&] { writeFloatImage(second, path); }), "");
    EXPECT_EQ(readFloatImage(path).pixels, first.pixels);
    fs::remove(path + ".tmp" + std::to_string(getpid()));

    writeFloatImage(second, path);
    EXPECT_EQ(readFloatImage(path).pixels, second.pixels);

    FloatImage broken(2, 2, 3);
    broken.pixels.resize(5);
    EXPECT_EQ(errorOf([&] { writeFloatImage(broken, path); }),
              path + ": image has 5 values, 2x2x3 needs 12");
    EXPECT_EQ(errorOf([&] { writeFloatImage(FloatImage(), path); }),
              path + ": cannot write an empty image (0x0, 0 channels)");
}

}  // namespace OSGBTF_TEST_FILE
