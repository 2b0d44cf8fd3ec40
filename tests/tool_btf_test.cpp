// The `btf` tool end to end: what a user types, on files the test makes.
#include <cstdlib>
#include <filesystem>
#include <fstream>

#include <gtest/gtest.h>

#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF::test;

namespace {
CommandResult btf(const std::string& arguments) {
    return runCommand(builtTool("btf") + " --no-progress " + arguments);
}
/** For commands that open an OpenGL context: Mesa's EGL/llvmpipe leaks a few hundred bytes per
 *  context (docs: headless.md 8), which LeakSanitizer would report in sanitizer builds. */
CommandResult btfWithGl(const std::string& arguments) {
    return runCommand("ASAN_OPTIONS=detect_leaks=0 " + builtTool("btf") + " --no-progress " +
                      arguments);
}
}  // namespace

TEST(BtfTool, MissingInputIsAClearErrorWithNonZeroExit) {
    const CommandResult r = btf("info /nonexistent/x.zip");
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("btf: error: /nonexistent/x.zip: "), std::string::npos) << r.output;
}

TEST(BtfTool, UnknownOptionShowsUsage) {
    const CommandResult r = btf("info --bogus x.zip");
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--bogus"), std::string::npos) << r.output;
}

TEST(BtfTool, HelpDocumentsEveryCommand) {
    const CommandResult r = btf("--help");
    EXPECT_EQ(r.exitCode, 0);
    for (const char* command : {"info", "sample", "contact-sheet"})
        EXPECT_NE(r.output.find(command), std::string::npos) << command;
}

TEST(BtfTool, SampleInfoAndContactSheetEndToEnd) {
    TempDir dir;
    const std::string zip = dir.file("s.zip"), sheet = dir.file("sheet.png");
    CommandResult r = btf("sample --size 16 --format png -o " + shellQuote(zip));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    ASSERT_TRUE(std::filesystem::exists(zip));
    r = btf("info --json " + shellQuote(zip));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("\"width\": 16"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("\"count\": 81"), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("\"nan_count\": 0"), std::string::npos) << r.output;
    r = btf("contact-sheet " + shellQuote(zip) + " -o " + shellQuote(sheet) +
            " --views '0,0;60,90' --lights '0,0;45,0;75,180'");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    // 3 columns and 2 rows of 16-pixel cells with 2-pixel gaps.
    r = runCommand("oiiotool --info " + shellQuote(sheet));
    EXPECT_NE(r.output.find("56 x   38"), std::string::npos) << r.output;
}

// One measured view (an RTI capture): every asked view is that view, so the sheet has one row.
TEST(BtfTool, ContactSheetOfAOneViewCaptureHasOneRow) {
    TempDir dir;
    const std::string sheet = dir.file("sheet.png");
    const CommandResult r =
        btf("contact-sheet " + shellQuote(sourceDir() + "/tests/data/rti-icon-64") + " -o " +
            shellQuote(sheet) + " --lights '10,0;45,0;45,0'");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find(": 1 view x 2 lights of "), std::string::npos) << r.output;
    // 2 columns of 64-pixel cells, 1 row, 2-pixel gaps.
    const CommandResult info = runCommand("oiiotool --info " + shellQuote(sheet));
    EXPECT_NE(info.output.find("134 x   68"), std::string::npos) << info.output;
}

TEST(BtfTool, MemoryLimitRefusesALoadCleanly) {
    TempDir dir;
    const std::string zip = dir.file("s.zip");
    ASSERT_EQ(btf("sample --size 8 --format png -o " + shellQuote(zip)).exitCode, 0);
    const CommandResult r = btf("--memory-limit 1K info " + shellQuote(zip));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("more than the memory limit of 1.0 KiB"), std::string::npos)
        << r.output;
}

TEST(BtfTool, FitUnknownMethodOrOptionIsAClearError) {
    TempDir dir;
    const std::string zip = dir.file("s.zip");
    ASSERT_EQ(btf("sample --size 8 --format png -o " + shellQuote(zip)).exitCode, 0);
    CommandResult r =
        btf("fit " + shellQuote(zip) + " -m nope -o " + shellQuote(dir.file("x.exr")));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("unknown method 'nope' (known: "), std::string::npos) << r.output;
    r = btf("fit " + shellQuote(zip) + " -m lambert --set bogus=1 -o " +
            shellQuote(dir.file("x.exr")));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("lambert: option bogus is unknown (known: none)"), std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("x.exr")));
}

TEST(BtfTool, FitThenEvalMatchesTheCpuReference) {
    TempDir dir;
    const std::string zip = dir.file("s.zip"), fitted = dir.file("l.exr");
    ASSERT_EQ(btf("sample --size 8 --format png -o " + shellQuote(zip)).exitCode, 0);
    CommandResult r = btf("fit " + shellQuote(zip) + " -m lambert -o " + shellQuote(fitted));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("per-texel error (Meseth et al. 2003, sec. 4.1): avg "),
              std::string::npos);
    EXPECT_NE(r.output.find("3.00 values, 6.00 bytes per texel"), std::string::npos) << r.output;
    r = btfWithGl("eval " + shellQuote(fitted) + " --view 45,0 --light 60,90 -o " +
                  shellQuote(dir.file("gpu.exr")));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("largest GPU-CPU difference 0"), std::string::npos) << r.output;
    r = btfWithGl("eval " + shellQuote(fitted) + " --view 95,0 -o " +
                  shellQuote(dir.file("bad.exr")));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("--view: theta 95"), std::string::npos) << r.output;
}

TEST(BtfTool, MipMappedFitIsTheDefaultAndEvaluatesItsBaseLevel) {
    TempDir dir;
    const std::string zip = dir.file("s.zip"), fitted = dir.file("m.btfmat");
    ASSERT_EQ(btf("sample --size 8 --format png -o " + shellQuote(zip)).exitCode, 0);
    CommandResult r =
        btf("fit " + shellQuote(zip) + " -m lambert --mipmap --no-mipmap -o " + shellQuote(fitted));
    EXPECT_NE(r.exitCode, 0);
    EXPECT_NE(r.output.find("--mipmap excludes --no-mipmap"), std::string::npos) << r.output;
    EXPECT_FALSE(std::filesystem::exists(fitted));
    r = btf("fit " + shellQuote(zip) + " -m lambert --no-mipmap -o " + shellQuote(fitted));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("(8x8 texels, 81x81 directions)"), std::string::npos) << r.output;
    // No flag: mip-mapped.
    r = btf("fit " + shellQuote(zip) + " -m lambert -o " + shellQuote(fitted));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    // 8x8: levels of 4x4, 2x2 and 1x1 in a column of 4 beside the base.
    EXPECT_NE(r.output.find("(8x8 texels, 4 mip levels in 12x8, 81x81 directions)"),
              std::string::npos)
        << r.output;
    r = btfWithGl("eval " + shellQuote(fitted) + " --view 45,0 --light 60,90 -o " +
                  shellQuote(dir.file("gpu.exr")));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("(lambert, 8x8 base of 4 mip levels, "), std::string::npos) << r.output;
    EXPECT_NE(r.output.find("largest GPU-CPU difference 0"), std::string::npos) << r.output;
    r = btf("fit " + shellQuote(zip) + " -m fmf --mipmap -o " + shellQuote(dir.file("m.btf")));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("m.btf: a UBO2014 .btf file has no mip levels; save a --mipmap fit "
                            "as .btfmat or .exr"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("m.btf")));
}

TEST(BtfTool, EvalWithAnEnvironment) {
    // A white environment (radiance 1, RGBE 128 128 128 129, flat 8 x 4 Radiance file), pca
    // through its folded program against the CPU's sum_i g_i BTF(x, v, l_i): float sums of ~81
    // terms of values <= ~1, 1e-4. (The other methods' GPU path: tests/gl/environment_test.cpp.)
    TempDir dir;
    const std::string zip = dir.file("s.zip"), sky = dir.file("white.hdr");
    const std::string fitted = dir.file("pca.btfmat");
    {
        std::ofstream out(sky, std::ios::binary);
        out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n";
        for (int i = 0; i < 32; ++i) out.write("\x80\x80\x80\x81", 4);
    }
    ASSERT_EQ(btf("sample --size 4 --format png -o " + shellQuote(zip)).exitCode, 0);
    CommandResult r =
        btf("fit " + shellQuote(zip) + " -m pca --components 4 -o " + shellQuote(fitted));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = btfWithGl("eval " + shellQuote(fitted) + " --env " + shellQuote(sky) +
                  " --exposure 0.5 --rotation 30 --view 30,0 -o " + shellQuote(dir.file("e.exr")));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::string key = "largest GPU-CPU difference ";
    const std::size_t at = r.output.find(key);
    ASSERT_NE(at, std::string::npos) << r.output;
    EXPECT_NE(r.output.find("environment " + sky), std::string::npos) << r.output;
    EXPECT_LT(std::atof(r.output.c_str() + at + key.size()), 1e-4) << r.output;
    EXPECT_TRUE(std::filesystem::exists(dir.file("e.exr")));
    // A missing map (eval and btfviewer say the same): compare checks it before any fit.
    r = btf("compare " + shellQuote(zip) + " --out " + shellQuote(dir.file("cmp")) + " --env " +
            shellQuote(dir.file("none.hdr")));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("--env: " + dir.file("none.hdr") + ": file not found"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(dir.file("cmp")));
}

// A user runs the tool from the build tree with no OSG_LIBRARY_PATH: an EXR
// environment is read by this project's osgdb_btfexr, which OSG's own folders do not hold, so the
// tool has to find its plugins itself (useOwnPlugins, scene/OwnPlugins.h). Before, this failed
// with "white.exr: no osgDB plugin could read it as an image".
TEST(BtfTool, FindsItsOwnPluginsWithoutOsgLibraryPath) {
    TempDir dir;
    const std::string zip = dir.file("s.zip"), hdr = dir.file("white.hdr");
    const std::string sky = dir.file("white.exr"), fitted = dir.file("lambert.btfmat");
    {
        std::ofstream out(hdr, std::ios::binary);
        out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y 4 +X 8\n";
        for (int i = 0; i < 32; ++i) out.write("\x80\x80\x80\x81", 4);
    }
    ASSERT_EQ(runCommand("oiiotool " + shellQuote(hdr) + " -d half -o " + shellQuote(sky)).exitCode,
              0);
    ASSERT_EQ(btf("sample --size 4 --format png -o " + shellQuote(zip)).exitCode, 0);
    ASSERT_EQ(btf("fit " + shellQuote(zip) + " -m lambert -o " + shellQuote(fitted)).exitCode, 0);
    const CommandResult r =
        runCommand("env -u OSG_LIBRARY_PATH -u LD_LIBRARY_PATH ASAN_OPTIONS=detect_leaks=0 " +
                   builtTool("btf") + " --no-progress eval " + shellQuote(fitted) + " --env " +
                   shellQuote(sky) + " --view 30,0 -o " + shellQuote(dir.file("e.exr")));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("environment " + sky), std::string::npos) << r.output;
}

}  // namespace OSGBTF_TEST_FILE
