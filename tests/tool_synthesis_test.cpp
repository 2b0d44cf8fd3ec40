// `btf synthesize` and `btf make-tileable` end to end, on a 16x16 sample the test writes.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <regex>

#include <gtest/gtest.h>

#include "core/CoordinateMap.h"
#include "loaders/LoadBtf.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

CommandResult btf(const std::string& arguments) {
    return runCommand(builtTool("btf") + " --no-progress " + arguments);
}

/** The 16x16 built-in sample as a zip, written once per test process. */
class BtfSynthesizeTool : public ::testing::Test {
protected:
    static void SetUpTestSuite() {
        dir = new TempDir;
        zip = dir->file("s.zip");
        const CommandResult r = btf("sample --size 16 --format png -o " + shellQuote(zip));
        ASSERT_EQ(r.exitCode, 0) << r.output;
    }
    static void TearDownTestSuite() {
        delete dir;
        dir = nullptr;
    }
    static TempDir* dir;
    static std::string zip;
};
TempDir* BtfSynthesizeTool::dir = nullptr;
std::string BtfSynthesizeTool::zip;

double figure(const std::string& output, const std::string& name) {
    std::smatch match;
    if (!std::regex_search(output, match, std::regex(name + " ([0-9.]+)"))) return -1;
    return std::stod(match[1]);
}

}  // namespace

TEST_F(BtfSynthesizeTool, OptionAndInputErrors) {
    const std::string map = dir->file("bad.exr");
    CommandResult r = btf("synthesize " + shellQuote(zip) + " --size 32 -o " + shellQuote(map));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("btf: error: " + zip +
                            ": --levels 3: the coarsest level of the 16x16 sample is 4x4, smaller "
                            "than the 5x5 neighbourhood of --neighbourhood 2; use fewer levels"),
              std::string::npos)
        << r.output;
    r = btf("synthesize " + shellQuote(zip) + " --k 0 -o " + shellQuote(map));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--k: Value 0 not in range 1 to 64"), std::string::npos) << r.output;
    r = btf("synthesize /nonexistent/x.zip -o " + shellQuote(map));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("btf: error: /nonexistent/x.zip: "), std::string::npos) << r.output;
    r = btf("synthesize " + shellQuote(zip) + " -o /nonexistent/folder/m.exr");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("btf: error: /nonexistent/folder/m.exr: folder '/nonexistent/folder' "
                            "does not exist"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(map));
    const std::string tiles = dir->file("bad.zip");
    r = btf("make-tileable " + shellQuote(zip) + " --border 9 -o " + shellQuote(tiles));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("btf: error: " + zip +
                            ": --border 9: must be in 1..8 (half the 16x16 sample's smaller side)"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(tiles));
    r = btf("synthesize --help");
    EXPECT_EQ(r.exitCode, 0);
    for (const char* option : {"--size", "--k", "--neighbourhood", "--levels", "--seed", "--images",
                               "--textons", "--dimensions", "--patch"})
        EXPECT_NE(r.output.find(option), std::string::npos) << option;
}

// One test for both commands: every test of this file runs in its own process (ctest), which
// writes the sample again (6561 members).
TEST_F(BtfSynthesizeTool, DeterministicMapQualityFiguresAndMakeTileable) {
    const std::string a = dir->file("a.exr"), b = dir->file("b.exr");
    const std::string options = " --size 48 --levels 2 --k 3 --seed 5 --images 200 -o ";
    CommandResult r = btf("synthesize " + shellQuote(zip) + options + shellQuote(a));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("synthesised 48x48 texels from "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("200 images: 600 values per texel, projected to 64"), std::string::npos)
        << r.output;
    // The sample tiles (two weave repeats per side): a synthesis without visible seams.
    const double seam = figure(r.output, "seam ratio"), rate = figure(r.output, "coherence rate");
    EXPECT_GE(seam, 0.0) << r.output;
    EXPECT_LE(seam, 2.0) << r.output;
    EXPECT_GT(rate, 0.0) << r.output;
    EXPECT_LE(rate, 1.0) << r.output;
    r = btf("synthesize " + shellQuote(zip) + options + shellQuote(b));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const CoordinateMap first = readCoordinateMap(a), second = readCoordinateMap(b);
    EXPECT_EQ(first.width, 48);
    EXPECT_EQ(first.sampleWidth, 16);
    EXPECT_EQ(first.sampleHeight, 16);
    EXPECT_EQ(first.coordinates, second.coordinates);

    // make-tileable blends only the border.
    const std::string out = dir->file("t.zip");
    r = btf("make-tileable " + shellQuote(zip) + " --border 3 --format png -o " + shellQuote(out));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("over 3 texels per side"), std::string::npos) << r.output;
    const MeasuredBtf in = loadMeasuredBtf(zip), blended = loadMeasuredBtf(out);
    ASSERT_EQ(blended.width(), 16);
    ASSERT_EQ(blended.imageCount(), in.imageCount());
    // 8-bit PNG members: the interior's values k/255 come back bit for bit, and the left-right
    // jump of every row of every image is at most 2/7 of the largest one before (Tileable.h),
    // plus the rounding of its two ends to 8 bits (1/255).
    float before = 0, after = 0;
    for (std::size_t v = 0; v < in.viewCount(); v += 20)
        for (std::size_t l = 0; l < in.lightCount(); l += 20)
            for (int y = 0; y < 16; ++y)
                for (int c = 0; c < 3; ++c) {
                    for (int x = 3; x < 13 && y >= 3 && y < 13; ++x) {
                        ASSERT_EQ(blended.value(v, l, std::size_t(y) * 16 + x, c),
                                  in.value(v, l, std::size_t(y) * 16 + x, c));
                    }
                    const std::size_t left = std::size_t(y) * 16, right = left + 15;
                    before = std::max(before,
                                      std::abs(in.value(v, l, right, c) - in.value(v, l, left, c)));
                    after = std::max(after, std::abs(blended.value(v, l, right, c) -
                                                     blended.value(v, l, left, c)));
                }
    EXPECT_LE(after, 2.0f * before / 7.0f + 1.0f / 255.0f + 1e-6f);
}

}  // namespace OSGBTF_TEST_FILE
