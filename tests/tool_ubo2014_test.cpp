// The `btf` tool on UBO2014 files, which it uses as stored: `btf info` from
// the header and factors, `--stats` streamed through the factors; on hand-written files
// (tests/HandWrittenUbo2014.h), so the expected figures come from the format's formulas.
#include <algorithm>
#include <cmath>
#include <filesystem>
#include <limits>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/FloatImage.h"
#include "loaders/Ubo2014.h"
#include "materials/fmf/Fmf.h"
#include "streaming/TileSet.h"
#include "tests/HandWrittenUbo2014.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF::test;

namespace {

CommandResult btf(const std::string& arguments) {
    return runCommand(builtTool("btf") + " --no-progress " + arguments);
}
/** For commands that open an OpenGL context (Mesa's EGL leaks a little per context). */
CommandResult btfWithGl(const std::string& arguments) {
    return runCommand("ASAN_OPTIONS=detect_leaks=0 " + builtTool("btf") + " --no-progress " +
                      arguments);
}

nlohmann::json infoJson(const std::string& arguments) {
    const CommandResult r = btf("info --json " + arguments);
    EXPECT_EQ(r.exitCode, 0) << r.output;
    try {
        return nlohmann::json::parse(r.output);
    } catch (const std::exception& e) {
        ADD_FAILURE() << e.what() << "\n" << r.output;
        return {};
    }
}

/** Minimum, maximum and mean per channel over every value of the hand-written file. */
struct Expected {
    double minimum[3], maximum[3], mean[3];
};
Expected expectedStats(const HandWrittenBtf& f) {
    Expected e;
    double sum[3] = {0, 0, 0};
    for (int c = 0; c < 3; ++c) {
        e.minimum[c] = std::numeric_limits<double>::infinity();
        e.maximum[c] = -e.minimum[c];
    }
    std::size_t n = 0;
    for (int v = 0; v < int(f.views.size()); ++v)
        for (int l = 0; l < int(f.lights.size()); ++l)
            for (int y = 0; y < f.height; ++y)
                for (int x = 0; x < f.width; ++x, ++n) {
                    const auto rgb = f.value(v, l, x, y);
                    for (int c = 0; c < 3; ++c) {
                        e.minimum[c] = std::min(e.minimum[c], rgb[std::size_t(c)]);
                        e.maximum[c] = std::max(e.maximum[c], rgb[std::size_t(c)]);
                        sum[c] += rgb[std::size_t(c)];
                    }
                }
    for (int c = 0; c < 3; ++c) e.mean[c] = sum[c] / double(n);
    return e;
}

}  // namespace

TEST(BtfToolUbo2014, InfoDescribesTheFactorsWithoutDecoding) {
    TempDir dir;
    const HandWrittenBtf f = handWrittenDfmf11();
    const std::string path = dir.file("dfmf11.btf");
    writeTextFile(path, f.bytes);
    const nlohmann::json info = infoJson(shellQuote(path));
    EXPECT_EQ(info["format"], "UBO2014 DFMF");
    EXPECT_EQ(info["signature"], "!DFMF08FCR");
    EXPECT_EQ(info["width"], 4);
    EXPECT_EQ(info["height"], 3);
    EXPECT_EQ(info["views"]["count"], 7);
    EXPECT_EQ(info["lights"]["count"], 10);
    EXPECT_NEAR(info["lights"]["theta_max"].get<double>(), 75.0, 1e-3);
    EXPECT_EQ(info["images"], 70);
    EXPECT_EQ(info["ranks"], nlohmann::json({2, 3, 1}));
    EXPECT_EQ(info["color_model"]["id"], 11);
    EXPECT_EQ(info["scalar"], "float");
    EXPECT_EQ(info["cosine"], false);
    EXPECT_EQ(info["file_bytes"], f.bytes.size());
    // Factors as floats: per channel (70 + 12 texels + 1 S) x K values, K = 2 + 3 + 1.
    EXPECT_EQ(info["factor_bytes"], (70 + 12 + 1) * 6 * 4);
    EXPECT_EQ(info["decoded_float_bytes"], 70 * 12 * 3 * 4);
    EXPECT_EQ(info["meta"]["measurement_setup"], "hand-written test dome");
    EXPECT_FALSE(info.contains("range"));  // nothing decoded without --stats

    const CommandResult text = btf("info " + shellQuote(path));
    ASSERT_EQ(text.exitCode, 0) << text.output;
    EXPECT_NE(text.output.find("factors:  DFMF, ranks 2, 3, 1 (channels of colour model 11"),
              std::string::npos)
        << text.output;
}

TEST(BtfToolUbo2014, InfoOfAnFmfFile) {
    TempDir dir;
    const HandWrittenBtf f = handWrittenFmfDrrCosine();
    const std::string path = dir.file("fmf.bin");  // found by its first byte, not its name
    writeTextFile(path, f.bytes);
    const nlohmann::json info = infoJson(shellQuote(path));
    EXPECT_EQ(info["format"], "UBO2014 FMF");
    EXPECT_EQ(info["ranks"], nlohmann::json({3, 3, 3}));
    EXPECT_EQ(info["dynamic_range_reduction"], true);
    EXPECT_EQ(info["cosine"], true);
    EXPECT_EQ(info["header_version"], 1);
    EXPECT_EQ(info["scalar"], "half");
    EXPECT_FALSE(info.contains("color_model"));
}

TEST(BtfToolUbo2014, StatsStreamEveryDecodedValue) {
    TempDir dir;
    for (const HandWrittenBtf& f : {handWrittenDfmf11(), handWrittenFmfDrrCosine()}) {
        SCOPED_TRACE(f.signature);
        const std::string path = dir.file("f.btf");
        writeTextFile(path, f.bytes);
        const nlohmann::json info = infoJson("--stats " + shellQuote(path));
        const Expected e = expectedStats(f);
        EXPECT_EQ(info["nan_count"], 0);
        EXPECT_EQ(info["inf_count"], 0);
        for (int c = 0; c < 3; ++c) {
            const auto& r = info["range"][c == 0 ? "R" : c == 1 ? "G" : "B"];
            // Float factor sums and expf against the double formula: relative 1e-5.
            auto tolerance = [](double x) { return 1e-5 * std::max(1.0, std::abs(x)); };
            EXPECT_NEAR(r["min"].get<double>(), e.minimum[c], tolerance(e.minimum[c]));
            EXPECT_NEAR(r["max"].get<double>(), e.maximum[c], tolerance(e.maximum[c]));
            EXPECT_NEAR(r["mean"].get<double>(), e.mean[c], tolerance(e.mean[c]));
        }
    }
}

TEST(BtfToolUbo2014, InfoNeedsNoMemoryForTheDecodedData) {
    TempDir dir;
    const HandWrittenBtf f = handWrittenDfmf11();
    const std::string path = dir.file("dfmf11.btf");
    writeTextFile(path, f.bytes);
    // 3 KiB: more than the factors (1992 bytes), less than the decoded values (10080 bytes).
    CommandResult r = btf("--memory-limit 3K info --stats " + shellQuote(path));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    r = btf("--memory-limit 3K contact-sheet " + shellQuote(path) + " -o " +
            shellQuote(dir.file("sheet.png")));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("more than the memory limit of 3.0 KiB"), std::string::npos)
        << r.output;
}

// fits read a UBO2014 file's factors block by block, so a memory limit
// below the decoded size refuses nothing; the reported error is on a stated subsample.
TEST(BtfToolUbo2014, FitNeedsNoMemoryForTheDecodedData) {
    TempDir dir;
    const HandWrittenBtf f = handWrittenDfmf11();
    const std::string path = dir.file("dfmf11.btf");
    writeTextFile(path, f.bytes);
    // 9.5 KiB: more than the factors (1992 bytes) held beside the largest fit here (pca's 2 x 7
    // Eigen-Textures and weights, and one view's images per worker: 7.4 KiB), less than the
    // decoded values (10080 bytes).
    for (const std::string method : {"lambert", "pca --components 2"}) {
        const std::string out = dir.file(method.substr(0, 3) + ".btfmat");
        CommandResult r = btf("--memory-limit 9.5K fit " + shellQuote(path) + " -m " + method +
                              " -o " + shellQuote(out) + " --error-texels 5");
        EXPECT_EQ(r.exitCode, 0) << r.output;
        // Mip-mapped by default: the 4 x 3 base and its 2 x 1 and 1 x 1 levels in a 6 x 3 atlas.
        EXPECT_NE(r.output.find("error over a random subsample of 5 of 18 texels"),
                  std::string::npos)
            << r.output;
        EXPECT_TRUE(std::filesystem::exists(out)) << method;
    }
    // --error-texels 0: every texel.
    const CommandResult r =
        btf("--memory-limit 6K fit " + shellQuote(path) + " -m lambert -o " +
            shellQuote(dir.file("no.btfmat")) + " --storage half --error-texels 0 --no-mipmap");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(r.output.find("subsample"), std::string::npos) << r.output;
}

TEST(BtfToolUbo2014, EvalRendersTheStoredFactors) {
    TempDir dir;
    const HandWrittenBtf f = handWrittenDfmf11();
    const std::string path = dir.file("dfmf11.btf");
    writeTextFile(path, f.bytes);
    const osgBTF::Ubo2014Factors factors = osgBTF::readUbo2014(path);
    // View 2 (40, 120) and light 5 (60, 150) of the file: a measured pair.
    const std::size_t view = 2, light = 5;
    for (const char* mode : {"", " --cpu"}) {
        SCOPED_TRACE(mode);
        const std::string image = dir.file("eval.exr");
        const CommandResult r =
            btfWithGl("eval " + shellQuote(path) + " --view 40,120 --light 60,150 -o " +
                      shellQuote(image) + mode);
        ASSERT_EQ(r.exitCode, 0) << r.output;
        EXPECT_NE(r.output.find("(fmf, 4x3, "), std::string::npos) << r.output;
        EXPECT_EQ(r.output.find("GPU"), *mode ? std::string::npos : r.output.find("GPU: "))
            << r.output;
        const osgBTF::FloatImage got = osgBTF::readFloatImage(image);
        ASSERT_EQ(got.width, 4);
        ASSERT_EQ(got.height, 3);
        // Image rows top-down; FactoredBtf::value counts y from the bottom. Same float math on
        // both sides except the GPU's: 1e-3 relative.
        for (int row = 0; row < 3; ++row)
            for (int x = 0; x < 4; ++x) {
                const glm::vec3 want = factors.value(view, light, x, 2 - row);
                for (int c = 0; c < 3; ++c)
                    EXPECT_NEAR(got.at(x, row, c), want[c],
                                1e-3 * std::max(1.0f, std::abs(want[c])))
                        << "x " << x << " row " << row << " channel " << c;
            }
    }
}

TEST(BtfToolUbo2014, EvalCpuOpensNoOpenGlContext) {
    // With no EGL vendor library glvnd has no EGL at all: the GPU path fails, --cpu works.
    TempDir dir;
    const std::string path = dir.file("dfmf11.btf");
    writeTextFile(path, handWrittenDfmf11().bytes);
    const std::string noEgl = "__EGL_VENDOR_LIBRARY_FILENAMES=" + dir.file("none.json") + " ";
    const std::string eval = "eval " + shellQuote(path) + " --view 40,120 --light 60,150 -o " +
                             shellQuote(dir.file("eval.exr"));
    const CommandResult gpu = runCommand("ASAN_OPTIONS=detect_leaks=0 " + noEgl + builtTool("btf") +
                                         " --no-progress " + eval);
    EXPECT_EQ(gpu.exitCode, 1) << gpu.output;
    EXPECT_NE(gpu.output.find("EGL"), std::string::npos) << gpu.output;
    const CommandResult cpu =
        runCommand(noEgl + builtTool("btf") + " --no-progress " + eval + " --cpu");
    EXPECT_EQ(cpu.exitCode, 0) << cpu.output;
    EXPECT_NE(cpu.output.find("(fmf, 4x3, CPU)"), std::string::npos) << cpu.output;
}

namespace {

/** "RMSE <x>" from `btf tiles`'s conversion line; NaN when missing. */
double statedRmse(const std::string& output) {
    const std::string key = "converted to FMF with ";
    const std::size_t line = output.find(key);
    const std::size_t at = output.find("RMSE ", line == std::string::npos ? 0 : line);
    if (line == std::string::npos || at == std::string::npos)
        return std::numeric_limits<double>::quiet_NaN();
    return std::stod(output.substr(at + 5));
}

/** RMSE of a tile set's finest material against the hand-written file's values (its own
 *  decoder, HandWrittenBtf::value), over every texel and (view, light) pair; also the largest
 *  |value|. */
double tileSetRmse(const std::string& folder, const HandWrittenBtf& f, double& largest) {
    const osg::ref_ptr<osgBTF::FmfMaterial> m = osgBTF::loadTileSetFinest(folder);
    const std::size_t nV = f.views.size(), nL = f.lights.size();
    EXPECT_EQ(m->views().size(), nV);
    EXPECT_EQ(m->lights().size(), nL);
    std::vector<float> abrdf(nV * nL * 3);
    double squared = 0;
    std::size_t n = 0;
    largest = 0;
    for (int y = 0; y < f.height; ++y)
        for (int x = 0; x < f.width; ++x) {
            m->evaluateMeasured(std::size_t(y * f.width + x), abrdf.data());
            for (std::size_t v = 0; v < nV; ++v)
                for (std::size_t l = 0; l < nL; ++l) {
                    const auto want = f.value(int(v), int(l), x, f.height - 1 - y);
                    for (int c = 0; c < 3; ++c, ++n) {
                        const double d = abrdf[(v * nL + l) * 3 + std::size_t(c)] - want[c];
                        squared += d * d;
                        largest = std::max(largest, std::abs(want[c]));
                    }
                }
        }
    return std::sqrt(squared / double(n));
}

}  // namespace

// A DFMF file (colour model 11, non-linear: no recombination of its factors is FMF) is converted
// by an fmf fit of its decoded values, whose stated error is checked against the file's own
// decoder: at full rank (12 = its texels) the tiles reproduce it up to half rounding; at rank 2
// the stated RMSE is what the tile set measures against the hand-written values.
TEST(BtfToolUbo2014, TilesConvertADfmfFileAndStateTheError) {
    TempDir dir;
    const HandWrittenBtf f = handWrittenDfmf11();
    const std::string path = dir.file("dfmf11.btf");
    writeTextFile(path, f.bytes);
    const std::string common = " --codec raw --tile-size 8 --padding 0";

    const CommandResult full = btf("tiles " + shellQuote(path) + " -o " +
                                   shellQuote(dir.file("full")) + common + " --components 12");
    ASSERT_EQ(full.exitCode, 0) << full.output;
    EXPECT_NE(full.output.find("DFMF (ranks 2, 3, 1, colour model 11) converted to FMF with 12 "
                               "components"),
              std::string::npos)
        << full.output;
    double largest = 0;
    const double fullRmse = tileSetRmse(dir.file("full"), f, largest);
    // Half tiles: U and SxV each within 2^-11 relative; the sums stay well inside 1e-3.
    EXPECT_LT(fullRmse, 1e-3 * largest);
    EXPECT_LT(statedRmse(full.output), 1e-5 * largest) << full.output;  // a float fit, full rank

    const CommandResult two = btf("tiles " + shellQuote(path) + " -o " +
                                  shellQuote(dir.file("two")) + common + " --components 2");
    ASSERT_EQ(two.exitCode, 0) << two.output;
    const double stated = statedRmse(two.output);
    const double measured = tileSetRmse(dir.file("two"), f, largest);
    EXPECT_GT(stated, 10 * fullRmse) << two.output;  // rank 2 does not hold this data
    EXPECT_NEAR(measured, stated, 0.02 * stated + 1e-3 * largest) << two.output;

    // An FMF input needs no conversion, and says so when asked for one.
    const HandWrittenBtf fmf = handWrittenFmfDrrCosine();
    writeTextFile(dir.file("fmf.btf"), fmf.bytes);
    const CommandResult refused = btf("tiles " + shellQuote(dir.file("fmf.btf")) + " -o " +
                                      shellQuote(dir.file("f")) + common + " --components 2");
    EXPECT_NE(refused.exitCode, 0);
    EXPECT_NE(refused.output.find(dir.file("fmf.btf") +
                                  ": --components converts DFMF input; this material is FMF "
                                  "already"),
              std::string::npos)
        << refused.output;
}

}  // namespace OSGBTF_TEST_FILE
