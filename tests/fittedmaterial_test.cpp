// Tests for core/FittedMaterialFile: the multi-part EXR container of fitted materials.
#include <unistd.h>
#include <cstring>
#include <filesystem>
#include <random>

#include <gtest/gtest.h>

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>

#include "core/Error.h"
#include "core/FittedMaterialFile.h"
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

MaterialTexture makeTexture(const std::string& name, int width, int height, int depth, int channels,
                            MaterialTexture::PixelKind kind, unsigned seed) {
    MaterialTexture t;
    t.name = name;
    t.width = width;
    t.height = height;
    t.depth = depth;
    t.channels = channels;
    t.kind = kind;
    t.data.resize(t.valueCount());
    std::mt19937 rng(seed);
    for (float& v : t.data) {
        if (kind == MaterialTexture::Float) {
            // Any finite bit pattern, denormals included: the container must keep every bit.
            std::uint32_t bits;
            do bits = std::uint32_t(rng());
            while ((bits & 0x7f800000u) == 0x7f800000u);
            std::memcpy(&v, &bits, sizeof v);
        } else {
            std::uint16_t bits;
            do bits = std::uint16_t(rng());
            while ((bits & 0x7c00u) == 0x7c00u);
            Imath::half h;
            h.setBits(bits);
            v = float(h);
        }
    }
    return t;
}

/** A single-channel texture of 2 slices of 2x3 texels, small enough to write the file's
 *  expected rows by hand: add(t, slice, row, column) stores each value, in memory order (rows
 *  counted from the bottom). */
template <class Add>
MaterialTexture twoSlicesOfTwoByThree(const std::string& name, MaterialTexture::PixelKind kind,
                                      Add add) {
    MaterialTexture t;
    t.name = name;
    t.width = 2;
    t.height = 3;
    t.depth = 2;
    t.channels = 1;
    t.kind = kind;
    for (int z = 0; z < 2; ++z)
        for (int y = 0; y < 3; ++y)
            for (int x = 0; x < 2; ++x) add(t, z, y, x);
    return t;
}

/** A material of method "test" holding `t` alone. */
FittedMaterial materialOf(const MaterialTexture& t) {
    FittedMaterial m;
    m.method = "test";
    m.textures.push_back(t);
    return m;
}

FittedMaterial makeMaterial() {
    FittedMaterial m;
    m.method = "lpca";
    m.parameters = {{"components", "8"}, {"clusters", "32"}, {"note", "fitted; with spaces"}};
    m.views = DirectionSet::bonn81();
    m.lights = DirectionSet::ubo2014();
    m.textures.push_back(makeTexture("coefficients", 5, 4, 1, 3, MaterialTexture::Float, 1));
    m.textures.push_back(makeTexture("basis", 7, 3, 1, 4, MaterialTexture::Half, 2));
    m.textures.push_back(makeTexture("volume", 3, 2, 4, 7, MaterialTexture::Float, 3));
    m.textures.push_back(makeTexture("mask", 2, 2, 1, 1, MaterialTexture::Half, 4));
    m.textures.push_back(makeTexture("uv", 2, 3, 1, 2, MaterialTexture::Float, 5));
    return m;
}

bool sameBits(const std::vector<float>& a, const std::vector<float>& b) {
    return a.size() == b.size() && std::memcmp(a.data(), b.data(), a.size() * sizeof(float)) == 0;
}

/** Writes a multi-part EXR by hand, for files saveFittedMaterial would never write. */
void writeRawExr(const std::string& path, const std::vector<std::string>& channels,
                 const std::function<void(Imf::Header&)>& edit) {
    Imf::Header header(2, 2);
    header.setName("t");
    header.setType(Imf::SCANLINEIMAGE);
    for (const std::string& c : channels) header.channels().insert(c, Imf::Channel(Imf::FLOAT));
    edit(header);
    std::vector<float> data(4 * channels.size(), 1.0f);
    Imf::FrameBuffer fb;
    for (std::size_t c = 0; c < channels.size(); ++c)
        fb.insert(channels[c],
                  Imf::Slice(Imf::FLOAT, (char*)(data.data() + c), sizeof(float) * channels.size(),
                             2 * sizeof(float) * channels.size()));
    Imf::MultiPartOutputFile file(path.c_str(), &header, 1);
    Imf::OutputPart part(file, 0);
    part.setFrameBuffer(fb);
    part.writePixels(2);
}

std::vector<std::string> folderEntries(const fs::path& folder) {
    std::vector<std::string> names;
    for (const auto& entry : fs::directory_iterator(folder))
        names.push_back(entry.path().filename().string());
    std::sort(names.begin(), names.end());
    return names;
}

}  // namespace

TEST(FittedMaterial, RoundTripIsExactForFloatAndHalf) {
    TempDir dir;
    const FittedMaterial m = makeMaterial();
    const std::string path = dir.file("m.exr");
    saveFittedMaterial(m, path);
    const FittedMaterial back = loadFittedMaterial(path);
    EXPECT_EQ(back.method, "lpca");
    EXPECT_EQ(back.parameters, m.parameters);
    EXPECT_EQ(back.views, m.views);
    EXPECT_EQ(back.views.name(), m.views.name());
    EXPECT_EQ(back.lights, m.lights);
    EXPECT_EQ(back.source, path);
    ASSERT_EQ(back.textures.size(), m.textures.size());
    for (std::size_t i = 0; i < m.textures.size(); ++i) {
        const MaterialTexture &a = m.textures[i], &b = back.textures[i];
        SCOPED_TRACE(a.name);
        EXPECT_EQ(b.name, a.name);
        EXPECT_EQ(b.width, a.width);
        EXPECT_EQ(b.height, a.height);
        EXPECT_EQ(b.depth, a.depth);
        EXPECT_EQ(b.channels, a.channels);
        EXPECT_EQ(b.kind, a.kind);
        EXPECT_TRUE(sameBits(b.data, a.data));
    }
    EXPECT_TRUE(sameBits(back.texture("volume").data, m.textures[2].data));
}

// Textures are written in chunks of rows (8 MiB each): several chunks, chunk borders inside a
// slice and across slices must give the same file as one piece would.
TEST(FittedMaterial, TexturesOfSeveralWriteChunksRoundTripExactly) {
    TempDir dir;
    FittedMaterial m = makeMaterial();
    m.textures.clear();
    // 16 KiB rows, 512 per chunk: chunks of 2 x 280 rows end inside the second slice.
    m.textures.push_back(makeTexture("big-float", 1024, 280, 2, 4, MaterialTexture::Float, 7));
    m.textures.push_back(makeTexture("big-half", 2048, 280, 2, 4, MaterialTexture::Half, 8));
    const std::string path = dir.file("big.exr");
    saveFittedMaterial(m, path);
    const FittedMaterial back = loadFittedMaterial(path);
    ASSERT_EQ(back.textures.size(), 2u);
    for (std::size_t i = 0; i < 2; ++i) {
        SCOPED_TRACE(m.textures[i].name);
        EXPECT_EQ(back.textures[i].depth, 2);
        EXPECT_TRUE(sameBits(back.textures[i].data, m.textures[i].data));
    }
}

TEST(FittedMaterial, TextureLookupNamesWhatIsMissing) {
    TempDir dir;
    const std::string path = dir.file("m.exr");
    saveFittedMaterial(makeMaterial(), path);
    const FittedMaterial m = loadFittedMaterial(path);
    EXPECT_EQ(m.texture("mask").channels, 1);
    EXPECT_EQ(m.findTexture("nope"), nullptr);
    EXPECT_EQ(errorOf([&] { m.texture("nope"); }),
              path +
                  ": fitted material 'lpca' has no texture 'nope' (textures: coefficients, "
                  "basis, volume, mask, uv)");
    EXPECT_EQ(m.parameter("components"), "8");
    EXPECT_EQ(errorOf([&] { m.parameter("rank"); }),
              path + ": fitted material 'lpca' has no parameter 'rank'");
}

TEST(FittedMaterial, FileShowsEachSliceUprightInViewers) {
    TempDir dir;
    // value = 10 * slice + row, rows counted from the bottom.
    const MaterialTexture t = twoSlicesOfTwoByThree(
        "v", MaterialTexture::Float,
        [](MaterialTexture& t, int z, int y, int) { t.data.push_back(float(10 * z + y)); });
    const FittedMaterial m = materialOf(t);
    const std::string path = dir.file("v.exr");
    saveFittedMaterial(m, path);
    const FloatImage file = readFloatImage(path);
    ASSERT_EQ(file.height, 6);
    EXPECT_EQ(file.channelNames, (std::vector<std::string>{"v.Y"}));
    // File rows top-down: slice 0 rows 2,1,0 then slice 1 rows 2,1,0.
    const float expected[6] = {2, 1, 0, 12, 11, 10};
    for (int row = 0; row < 6; ++row) EXPECT_EQ(file.at(1, row, 0), expected[row]) << row;
}

TEST(FittedMaterial, EightBitTextureHeldAsBytesIsWrittenAsItsIntegers) {
    TempDir dir;
    // byte = 100 * slice + 10 * row + column, rows counted from the bottom.
    const MaterialTexture t = twoSlicesOfTwoByThree(
        "q", MaterialTexture::UNorm8, [](MaterialTexture& t, int z, int y, int x) {
            t.bytes.push_back(std::uint8_t(100 * z + 10 * y + x));
        });
    FittedMaterial m = materialOf(t);
    const std::string path = dir.file("q.exr");
    saveFittedMaterial(m, path);
    // The file as any EXR reader sees it: the integers, slices one below the other, each upright.
    const FloatImage file = readFloatImage(path);
    ASSERT_EQ(file.width, 2);
    ASSERT_EQ(file.height, 6);
    for (int row = 0; row < 6; ++row)
        for (int x = 0; x < 2; ++x)
            EXPECT_EQ(file.at(x, row, 0), float(100 * (row / 3) + 10 * (2 - row % 3) + x)) << row;
    const FittedMaterial back = loadFittedMaterial(path);
    const MaterialTexture& q = back.texture("q");
    EXPECT_EQ(q.kind, MaterialTexture::UNorm8);
    ASSERT_EQ(q.data.size(), t.bytes.size());
    for (std::size_t i = 0; i < t.bytes.size(); ++i) {
        EXPECT_EQ(q.data[i], float(t.bytes[i]) / 255.0f) << i;
        EXPECT_EQ(q.value(i), t.value(i)) << i;
    }
    // As loadMaterial reads it: the integers themselves, a quarter of the memory.
    const FittedMaterial asBytes = loadFittedMaterial(path, CompactTextures{true, false});
    EXPECT_EQ(asBytes.texture("q").bytes, t.bytes);
    EXPECT_TRUE(asBytes.texture("q").data.empty());

    const std::string bad = dir.file("bad.exr");
    m.textures[0].data.assign(t.valueCount(), 0.0f);
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, bad); }),
              bad +
                  ": texture 'q' holds its values twice (in more than one of floats, bytes and "
                  "halves)");
    m.textures[0] = t;
    m.textures[0].kind = MaterialTexture::Half;
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, bad); }),
              bad + ": texture 'q' holds bytes but is not stored as 8-bit");
    m.textures[0] = t;
    m.textures[0].bytes.pop_back();
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, bad); }),
              bad + ": texture 'q' has 11 values, 12 expected");
    EXPECT_FALSE(fs::exists(bad));
}

TEST(FittedMaterial, HalfTextureHeldAsHalvesIsWrittenAndReadAsItsHalves) {
    TempDir dir;
    // value = 1000 * slice + row + column / 3 rounded to half, rows counted from the bottom: the
    // thirds are not exact in half, so a float path would show.
    const MaterialTexture t = twoSlicesOfTwoByThree(
        "h", MaterialTexture::Half, [](MaterialTexture& t, int z, int y, int x) {
            t.halves.push_back(Imath::half(1000.0f * float(z) + float(y) + float(x) / 3.0f));
        });
    FittedMaterial m = materialOf(t);
    const std::string path = dir.file("h.exr");
    saveFittedMaterial(m, path);
    // The file as any EXR reader sees it: slices one below the other, each upright.
    const FloatImage file = readFloatImage(path);
    ASSERT_EQ(file.height, 6);
    for (int row = 0; row < 6; ++row)
        EXPECT_EQ(file.at(1, row, 0),
                  float(Imath::half(1000.0f * float(row / 3) + float(2 - row % 3) + 1.0f / 3.0f)))
            << row;
    // As floats by default, as the same halves when asked (what loadMaterial asks for fmf).
    const FittedMaterial asFloats = loadFittedMaterial(path);
    const FittedMaterial asHalves = loadFittedMaterial(path, CompactTextures{false, true});
    EXPECT_TRUE(asFloats.texture("h").halves.empty());
    EXPECT_TRUE(asHalves.texture("h").data.empty());
    ASSERT_EQ(asHalves.texture("h").halves.size(), t.halves.size());
    for (std::size_t i = 0; i < t.halves.size(); ++i) {
        EXPECT_EQ(asHalves.texture("h").halves[i].bits(), t.halves[i].bits()) << i;
        EXPECT_EQ(asFloats.texture("h").data[i], float(t.halves[i])) << i;
    }
    // A method's choice by name: only the file's method is asked for.
    std::vector<std::string> asked;
    const FittedMaterial chosen = loadFittedMaterial(path, [&](const std::string& method) {
        asked.push_back(method);
        return CompactTextures{false, true};
    });
    EXPECT_EQ(asked, std::vector<std::string>{"test"});
    EXPECT_EQ(chosen.texture("h").halves.size(), t.halves.size());

    const std::string bad = dir.file("bad.exr");
    m.textures[0].kind = MaterialTexture::Float;
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, bad); }),
              bad + ": texture 'h' holds halves but is not stored as half");
    EXPECT_FALSE(fs::exists(bad));
}

TEST(FittedMaterial, ExrheaderAndOiiotoolReadTheFile) {
    TempDir dir;
    const std::string path = dir.file("m.exr");
    saveFittedMaterial(makeMaterial(), path);

    const auto header = runCommand("exrheader " + shellQuote(path));
    ASSERT_EQ(header.exitCode, 0) << header.output;
    EXPECT_NE(header.output.find("osgBTF.method (type string): \"lpca\""), std::string::npos)
        << header.output;
    EXPECT_NE(header.output.find("osgBTF.version (type int): 1"), std::string::npos);
    EXPECT_NE(header.output.find("osgBTF.param.components (type string): \"8\""),
              std::string::npos);
    EXPECT_NE(header.output.find("name (type string): \"coefficients\""), std::string::npos);
    EXPECT_NE(header.output.find("name (type string): \"volume\""), std::string::npos);
    EXPECT_NE(header.output.find("volume.c6, 32-bit floating-point"), std::string::npos);
    EXPECT_NE(header.output.find("basis.A, 16-bit floating-point"), std::string::npos);

    const auto info = runCommand("oiiotool --info -v " + shellQuote(path));
    ASSERT_EQ(info.exitCode, 0) << info.output;
    EXPECT_NE(info.output.find("osgBTF.method: \"lpca\""), std::string::npos) << info.output;
    EXPECT_NE(info.output.find("coefficients.R, coefficients.G, coefficients.B"),
              std::string::npos);
    EXPECT_NE(info.output.find("5 subimages"), std::string::npos);
}

TEST(FittedMaterial, SaveIsAtomic) {
    TempDir dir;
    const std::string path = dir.file("m.exr");
    const FittedMaterial m = makeMaterial();
    saveFittedMaterial(m, path);
    EXPECT_EQ(folderEntries(dir.path()), std::vector<std::string>{"m.exr"});
    const std::string good = test::readTextFile(path);

    const std::string nowhere = dir.file("missing/m.exr");
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, nowhere); }),
              nowhere + ": folder '" + dir.file("missing") + "' does not exist");

    // OpenEXR cannot create the temporary file: the existing file must survive untouched.
    const std::string temporary = path + ".tmp" + std::to_string(getpid());
    fs::create_directory(temporary);
    FittedMaterial other = m;
    other.method = "other";
    const std::string message = errorOf([&] { saveFittedMaterial(other, path); });
    EXPECT_EQ(message.rfind(path + ": OpenEXR: ", 0), 0u) << message;
    EXPECT_EQ(test::readTextFile(path), good);
    fs::remove(temporary);

    other.textures[1].data.pop_back();
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(other, path); }),
              path + ": texture 'basis' has 83 values, 84 expected");
    EXPECT_EQ(test::readTextFile(path), good);
    EXPECT_EQ(folderEntries(dir.path()), std::vector<std::string>{"m.exr"});
}

TEST(FittedMaterial, SaveRejectsInvalidMaterials) {
    TempDir dir;
    const std::string path = dir.file("m.exr");
    FittedMaterial m = makeMaterial();
    m.textures[3].name = "basis";
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, path); }),
              path + ": two textures are called 'basis'");
    m = makeMaterial();
    m.textures[1].data[0] = 1e6f;
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, path); }),
              path +
                  ": texture 'basis' is stored as half but 1 values exceed the half range "
                  "(65504)");
    m = makeMaterial();
    m.textures.clear();
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, path); }),
              path + ": fitted material 'lpca' has no textures");
    m = makeMaterial();
    m.method.clear();
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, path); }),
              path + ": fitted material has no method name");
    m = makeMaterial();
    m.textures[0].depth = 0;
    EXPECT_EQ(errorOf([&] { saveFittedMaterial(m, path); }),
              path + ": texture 'coefficients' has size 5x4x0 with 3 channels");
    EXPECT_FALSE(fs::exists(path));
}

TEST(FittedMaterial, LoadErrorsNameTheFileAndTheProblem) {
    TempDir dir;
    const std::string missing = dir.file("missing.exr");
    EXPECT_EQ(errorOf([&] { loadFittedMaterial(missing); }), missing + ": no such file");

    const std::string empty = dir.file("empty.exr");
    test::writeTextFile(empty, "");
    EXPECT_EQ(errorOf([&] { loadFittedMaterial(empty); }), empty + ": file is empty");

    const std::string png = dir.file("p.png"), renamed = dir.file("png.exr");
    ASSERT_EQ(
        runCommand("oiiotool --pattern constant:color=0.5 4x4 3 -d uint8 -o " + shellQuote(png))
            .exitCode,
        0);
    fs::copy_file(png, renamed);
    EXPECT_EQ(errorOf([&] { loadFittedMaterial(renamed); }),
              renamed +
                  ": not an OpenEXR file (wrong magic number), so not a fitted-material "
                  "file");

    const std::string plain = dir.file("plain.exr");
    FloatImage image(2, 2, 3);
    writeFloatImage(image, plain);
    EXPECT_EQ(errorOf([&] { loadFittedMaterial(plain); }),
              plain + ": not an osgBTF fitted-material file (no osgBTF.method attribute)");

    const std::string good = dir.file("good.exr");
    saveFittedMaterial(makeMaterial(), good);
    const std::string data = test::readTextFile(good);
    for (std::size_t keep : {data.size() - 100, data.size() / 2, std::size_t(60)}) {
        const std::string cut = dir.file("cut" + std::to_string(keep) + ".exr");
        test::writeTextFile(cut, data.substr(0, keep));
        const std::string message = errorOf([&] { loadFittedMaterial(cut); });
        EXPECT_EQ(message.rfind(cut + ": ", 0), 0u) << message;
        EXPECT_GT(message.size(), cut.size() + 10) << message;
    }

    const std::string v2 = dir.file("v2.exr");
    writeRawExr(v2, {"t.Y"}, [](Imf::Header& h) {
        h.insert("osgBTF.method", Imf::StringAttribute("lpca"));
        h.insert("osgBTF.version", Imf::IntAttribute(2));
    });
    EXPECT_EQ(errorOf([&] { loadFittedMaterial(v2); }),
              v2 + ": fitted-material container version 2 is not supported (this build reads "
                   "version 1)");

    const std::string layout = dir.file("layout.exr");
    writeRawExr(layout, {"R", "G", "B"}, [](Imf::Header& h) {
        h.insert("osgBTF.method", Imf::StringAttribute("lpca"));
        h.insert("osgBTF.version", Imf::IntAttribute(1));
    });
    EXPECT_EQ(errorOf([&] { loadFittedMaterial(layout); }),
              layout + ": texture 't' has unexpected channels (B, G, R); expected t.R, t.G, t.B");

    const std::string depth = dir.file("depth.exr");
    writeRawExr(depth, {"t.Y"}, [](Imf::Header& h) {
        h.insert("osgBTF.method", Imf::StringAttribute("lpca"));
        h.insert("osgBTF.version", Imf::IntAttribute(1));
        h.insert("osgBTF.depth", Imf::IntAttribute(3));
    });
    EXPECT_EQ(errorOf([&] { loadFittedMaterial(depth); }),
              depth + ": texture 't' has 2 rows, not a multiple of its depth 3");

    const std::string views = dir.file("views.exr");
    writeRawExr(views, {"t.Y"}, [](Imf::Header& h) {
        h.insert("osgBTF.method", Imf::StringAttribute("lpca"));
        h.insert("osgBTF.version", Imf::IntAttribute(1));
        h.insert("osgBTF.views", Imf::StringAttribute("bonn;0,0;garbage"));
    });
    const std::string message = errorOf([&] { loadFittedMaterial(views); });
    EXPECT_EQ(message.rfind(views + ": osgBTF.views: malformed direction set", 0), 0u) << message;
}

}  // namespace OSGBTF_TEST_FILE
