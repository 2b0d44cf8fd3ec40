// core/CoordinateMap: the reader against files written directly with OpenEXR from the format
// description (not by writeCoordinateMap), its refusals with their exact messages, the writer's
// round trip, and the materialised BTF.
#include <filesystem>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>

#include "core/CoordinateMap.h"
#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::errorOf;
using osgBTF::test::TempDir;

namespace {

struct RawMap {
    int width = 0, height = 0;
    std::vector<float> r, g;  // file order: top row first
    std::vector<std::pair<std::string, int>> attributes;
    bool withGreen = true;
};

void writeRaw(const RawMap& raw, const std::string& path) {
    Imf::Header header(raw.width, raw.height);
    header.channels().insert("R", Imf::Channel(Imf::FLOAT));
    if (raw.withGreen) header.channels().insert("G", Imf::Channel(Imf::FLOAT));
    for (const auto& [name, value] : raw.attributes) header.insert(name, Imf::IntAttribute(value));
    Imf::OutputFile file(path.c_str(), header);
    Imf::FrameBuffer frame;
    const std::size_t row = sizeof(float) * raw.width;
    frame.insert("R", Imf::Slice(Imf::FLOAT, (char*)raw.r.data(), sizeof(float), row));
    if (raw.withGreen)
        frame.insert("G", Imf::Slice(Imf::FLOAT, (char*)raw.g.data(), sizeof(float), row));
    file.setFrameBuffer(frame);
    file.writePixels(raw.height);
}

/** A 3x2 map into a 4x5 sample; file rows top-down: the top row is map row y = 1. */
RawMap validRaw() {
    RawMap raw;
    raw.width = 3;
    raw.height = 2;
    raw.r = {0, 1, 2, 3, 3, 0};
    raw.g = {4, 4, 4, 0, 1, 2};
    raw.attributes = {
        {"osgBTF.coordinateMap", 1}, {"osgBTF.sampleWidth", 4}, {"osgBTF.sampleHeight", 5}};
    return raw;
}

}  // namespace

TEST(CoordinateMap, MissingFileIsNamed) {
    TempDir dir;
    const std::string path = dir.file("none.exr");
    EXPECT_EQ(errorOf([&] { readCoordinateMap(path); }), path + ": no such file");
}

TEST(CoordinateMap, PlainExrIsNotAMap) {
    TempDir dir;
    RawMap raw = validRaw();
    raw.attributes.clear();
    writeRaw(raw, dir.file("plain.exr"));
    EXPECT_EQ(errorOf([&] { readCoordinateMap(dir.file("plain.exr")); }),
              dir.file("plain.exr") +
                  ": not an osgBTF coordinate map (no osgBTF.coordinateMap attribute)");
}

TEST(CoordinateMap, OtherVersionIsRefused) {
    TempDir dir;
    RawMap raw = validRaw();
    raw.attributes[0].second = 2;
    writeRaw(raw, dir.file("v2.exr"));
    EXPECT_EQ(errorOf([&] { readCoordinateMap(dir.file("v2.exr")); }),
              dir.file("v2.exr") +
                  ": coordinate map version 2 is not supported (this build reads version 1)");
}

TEST(CoordinateMap, MissingSampleSizeIsRefused) {
    TempDir dir;
    RawMap raw = validRaw();
    raw.attributes.pop_back();
    writeRaw(raw, dir.file("nosize.exr"));
    EXPECT_EQ(
        errorOf([&] { readCoordinateMap(dir.file("nosize.exr")); }),
        dir.file("nosize.exr") + ": coordinate map without an int attribute osgBTF.sampleHeight");
}

TEST(CoordinateMap, MissingChannelIsRefused) {
    TempDir dir;
    RawMap raw = validRaw();
    raw.withGreen = false;
    writeRaw(raw, dir.file("red.exr"));
    EXPECT_EQ(errorOf([&] { readCoordinateMap(dir.file("red.exr")); }),
              dir.file("red.exr") + ": coordinate map without R and G channels");
}

TEST(CoordinateMap, FractionalOrNonFiniteEntriesAreRefused) {
    TempDir dir;
    RawMap raw = validRaw();
    raw.r[4] = 1.5f;  // file row 1 = map row 0, x = 1
    writeRaw(raw, dir.file("half.exr"));
    EXPECT_EQ(errorOf([&] { readCoordinateMap(dir.file("half.exr")); }),
              dir.file("half.exr") + ": entry (1, 0) is not a pair of integers");
    raw = validRaw();
    raw.g[0] = std::numeric_limits<float>::quiet_NaN();
    writeRaw(raw, dir.file("nan.exr"));
    EXPECT_EQ(errorOf([&] { readCoordinateMap(dir.file("nan.exr")); }),
              dir.file("nan.exr") + ": entry (0, 1) is not a pair of integers");
}

TEST(CoordinateMap, EntriesOutsideTheSampleAreRefused) {
    TempDir dir;
    RawMap raw = validRaw();
    raw.r[2] = 4;  // the sample is 4 wide
    writeRaw(raw, dir.file("out.exr"));
    EXPECT_EQ(errorOf([&] { readCoordinateMap(dir.file("out.exr")); }),
              dir.file("out.exr") + ": entry (2, 1) points to (4, 4), outside the 4x5 sample");
}

TEST(CoordinateMap, TruncatedFileIsRefused) {
    TempDir dir;
    writeRaw(validRaw(), dir.file("whole.exr"));
    const auto size = std::filesystem::file_size(dir.file("whole.exr"));
    std::filesystem::copy_file(dir.file("whole.exr"), dir.file("cut.exr"));
    std::filesystem::resize_file(dir.file("cut.exr"), size - 20);
    const std::string message = errorOf([&] { readCoordinateMap(dir.file("cut.exr")); });
    EXPECT_EQ(message.rfind(dir.file("cut.exr") + ": ", 0), 0u) << message;
}

TEST(CoordinateMap, ReadsAHandWrittenFileBottomUp) {
    TempDir dir;
    writeRaw(validRaw(), dir.file("map.exr"));
    const CoordinateMap map = readCoordinateMap(dir.file("map.exr"));
    EXPECT_EQ(map.width, 3);
    EXPECT_EQ(map.height, 2);
    EXPECT_EQ(map.sampleWidth, 4);
    EXPECT_EQ(map.sampleHeight, 5);
    // Map row 0 is the file's second (bottom) row.
    EXPECT_EQ(map.sampleX(0, 0), 3);
    EXPECT_EQ(map.sampleY(0, 0), 0);
    EXPECT_EQ(map.sampleX(2, 0), 0);
    EXPECT_EQ(map.sampleY(2, 0), 2);
    EXPECT_EQ(map.sampleX(1, 1), 1);
    EXPECT_EQ(map.sampleY(1, 1), 4);
    EXPECT_EQ(map.sampleTexel(2, 0), 2u * 4u + 0u);
}

TEST(CoordinateMap, WriterRoundTripsAndNeverLeavesAPartialFile) {
    TempDir dir;
    CoordinateMap map(5, 3, 7, 2);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x) {
            map.sampleX(x, y) = (x * 3 + y) % 7;
            map.sampleY(x, y) = (x + y) % 2;
        }
    writeCoordinateMap(map, dir.file("m.exr"));
    const CoordinateMap back = readCoordinateMap(dir.file("m.exr"));
    EXPECT_EQ(back.coordinates, map.coordinates);
    EXPECT_EQ(back.sampleWidth, 7);
    EXPECT_EQ(back.sampleHeight, 2);

    map.sampleY(4, 2) = 2;
    EXPECT_EQ(errorOf([&] { writeCoordinateMap(map, dir.file("bad.exr")); }),
              dir.file("bad.exr") + ": entry (4, 2) points to (0, 2), outside the 7x2 sample");
    EXPECT_FALSE(std::filesystem::exists(dir.file("bad.exr")));
}

TEST(CoordinateMap, MaterialisedBtfCopiesTheMappedTexelForEveryViewAndLight) {
    const DirectionSet views("two", {{0, 0}, {30, 0}});
    const DirectionSet lights("three", {{0, 0}, {30, 0}, {30, 90}});
    MeasuredBtf sample(3, 2, views, lights);
    for (std::size_t v = 0; v < 2; ++v)
        for (std::size_t l = 0; l < 3; ++l)
            for (std::size_t t = 0; t < 6; ++t)
                for (int c = 0; c < 3; ++c)
                    sample.setValue(v, l, t, c, float(1000 * v + 100 * l + 10 * t + c));
    CoordinateMap map(4, 4, 3, 2);
    for (int y = 0; y < 4; ++y)
        for (int x = 0; x < 4; ++x) {
            map.sampleX(x, y) = (x + 2 * y) % 3;
            map.sampleY(x, y) = (x * y) % 2;
        }
    const MeasuredBtf big = materialiseCoordinateMap(sample, map);
    ASSERT_EQ(big.width(), 4);
    ASSERT_EQ(big.height(), 4);
    for (std::size_t v = 0; v < 2; ++v)
        for (std::size_t l = 0; l < 3; ++l)
            for (int y = 0; y < 4; ++y)
                for (int x = 0; x < 4; ++x)
                    for (int c = 0; c < 3; ++c) {
                        const std::size_t from = std::size_t((x * y) % 2) * 3 + (x + 2 * y) % 3;
                        EXPECT_EQ(big.value(v, l, std::size_t(y) * 4 + x, c),
                                  float(1000 * v + 100 * l + 10 * from + c));
                    }

    CoordinateMap wrong(2, 2, 4, 2);
    EXPECT_EQ(errorOf([&] { materialiseCoordinateMap(sample, wrong); }),
              "coordinate map: made for a 4x2 sample, not 3x2");
}

}  // namespace OSGBTF_TEST_FILE
