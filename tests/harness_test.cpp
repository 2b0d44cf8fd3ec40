// The comparison harness (`btf compare`, harness/): end to end on a tiny sample, with one method
// forced to fail, and the budget logic of the recommendation in-process. The tool runs as a child
// process (it opens an OpenGL context; leak checks are off for that child only, see
// tool_btf_test.cpp); the numbers it reports are recomputed here from its files.
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>
#include <nlohmann/json.hpp>

#include "core/ErrorMetrics.h"
#include "harness/Compare.h"
#include "harness/Pictures.h"
#include "harness/SoakSampling.h"
#include "loaders/LoadBtf.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;
namespace fs = std::filesystem;

namespace {

CommandResult btfWithGl(const std::string& arguments) {
    return runCommand("ASAN_OPTIONS=detect_leaks=0 " + builtTool("btf") + " --no-progress " +
                      arguments);
}

/** Folders beside `dir` whose name starts with dir's name (temporary work folders). */
std::vector<std::string> siblingsStartingWith(const fs::path& dir) {
    std::vector<std::string> found;
    for (const auto& entry : fs::directory_iterator(dir.parent_path()))
        if (entry.path().filename().string().rfind(dir.filename().string(), 0) == 0)
            found.push_back(entry.path().string());
    return found;
}

const nlohmann::json& methodEntry(const nlohmann::json& results, const std::string& method) {
    for (const auto& m : results["methods"])
        if (m["method"] == method) return m;
    static const nlohmann::json none;
    ADD_FAILURE() << "no entry for " << method;
    return none;
}

std::size_t count(const std::string& text, const std::string& what) {
    std::size_t n = 0;
    for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
    return n;
}

}  // namespace

TEST(Harness, BadInputIsAClearErrorAndCreatesNoFolder) {
    TempDir dir;
    const fs::path out = dir.path() / "cmp";
    const CommandResult r =
        btfWithGl("compare /nonexistent/x.zip --out " + shellQuote(out.string()));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("btf: error: /nonexistent/x.zip: "), std::string::npos) << r.output;
    EXPECT_TRUE(siblingsStartingWith(out).empty()) << siblingsStartingWith(out).front();
}

TEST(Harness, UnknownMethodOrMalformedSettingIsAClearError) {
    TempDir dir;
    const std::string zip = dir.file("s.zip");
    ASSERT_EQ(runCommand(builtTool("btf") + " sample --size 8 -o " + shellQuote(zip)).exitCode, 0);
    const fs::path out = dir.path() / "cmp";
    CommandResult r = btfWithGl("compare " + shellQuote(zip) + " --methods pca,nope --out " +
                                shellQuote(out.string()));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("btf: error: unknown method 'nope' (known: "), std::string::npos)
        << r.output;
    r = btfWithGl("compare " + shellQuote(zip) + " --set components=3 --out " +
                  shellQuote(out.string()));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("btf: error: --set: 'components=3' is not METHOD:KEY=VALUE"),
              std::string::npos)
        << r.output;
    r = btfWithGl("compare " + shellQuote(zip) + " --methods pca --set lpca:clusters=3 --out " +
                  shellQuote(out.string()));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("btf: error: options given for method 'lpca', which is not among the "
                            "compared methods"),
              std::string::npos)
        << r.output;
    r = btfWithGl("compare " + shellQuote(zip) + " --methods pca --targets rgba8,rgb10 --out " +
                  shellQuote(out.string()));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("btf: error: --targets: pass target 'rgb10': must be rgba8, rgba16f "
                            "or rgba32f"),
              std::string::npos)
        << r.output;
    EXPECT_TRUE(siblingsStartingWith(out).empty());
}

TEST(Harness, TinySampleWritesEveryFileAndTablesMatchTheMethodApis) {
    TempDir dir;
    const std::string zip = dir.file("s.zip");
    ASSERT_EQ(runCommand(builtTool("btf") + " sample --size 8 -o " + shellQuote(zip)).exitCode, 0);
    const fs::path out = dir.path() / "cmp";
    // lpca with clusters=0 must fail; pca and the lambert baseline must complete anyway.
    const CommandResult r = btfWithGl(
        "compare " + shellQuote(zip) + " --methods pca,lpca --set pca:components=3 --set " +
        "lpca:clusters=0 --resolution 32 --frames 1 --calibration-fetches 4 --sphere-size 32 " +
        "--out " + shellQuote(out.string()));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("wrote " + out.string() + "/report.md"), std::string::npos) << r.output;

    for (const char* file :
         {"report.md", "results.csv", "results.json", "pictures/spheres.png",
          "pictures/error-maps.png", "pictures/measured-vs-model.png",
          "pictures/error-vs-memory.svg", "fits/lambert.exr", "fits/pca.exr", "fits/lpca.log"})
        EXPECT_TRUE(fs::is_regular_file(out / file)) << file;
    EXPECT_FALSE(fs::exists(out / "fits/lpca.exr"));
    EXPECT_EQ(siblingsStartingWith(out).size(), 1u);  // no temporary folder left behind

    std::ifstream in(out / "results.json");
    const nlohmann::json results = nlohmann::json::parse(in);
    const std::string failure = "failed: lpca: option clusters must be an integer in 1..256, got 0";
    const nlohmann::json& lpca = methodEntry(results, "lpca");
    EXPECT_EQ(lpca["status"], "failed");
    EXPECT_EQ(lpca["message"], failure);
    const std::string report = readTextFile((out / "report.md").string());
    // Error, held-out, memory, pass cost and fitting tables each show the failure.
    EXPECT_EQ(count(report, "| lpca | clusters=0 | " + failure + " |"), 1u) << report;
    EXPECT_EQ(count(report, "| lpca | " + failure + " |"), 4u) << report;
    EXPECT_NE(readTextFile((out / "results.csv").string())
                  .find("lpca,failed,\"" + failure + "\",clusters=0,"),
              std::string::npos);

    // Recomputed independently: the fitted files against the input.
    const MeasuredBtf btf = loadMeasuredBtf(zip);
    for (const char* method : {"lambert", "pca"}) {
        SCOPED_TRACE(method);
        const nlohmann::json& entry = methodEntry(results, method);
        ASSERT_EQ(entry["status"], "ok") << entry.dump();
        osg::ref_ptr<Material> material =
            loadMaterial((out / "fits" / (std::string(method) + ".exr")).string());
        const ErrorSummary e = computeError(
            btf, [&](std::size_t t, float* abrdf) { material->evaluateMeasured(t, abrdf); });
        EXPECT_DOUBLE_EQ(entry["error"]["average"].get<double>(), e.average);
        EXPECT_DOUBLE_EQ(entry["error"]["minimum"].get<double>(), e.minimum);
        EXPECT_DOUBLE_EQ(entry["error"]["maximum"].get<double>(), e.maximum);
        EXPECT_DOUBLE_EQ(entry["error"]["rmse"].get<double>(), e.rmse);
        EXPECT_DOUBLE_EQ(entry["error"]["psnr_db"].get<double>(), e.psnr);
        const MemoryFootprint memory = material->memory();
        EXPECT_DOUBLE_EQ(entry["memory"]["bytes_per_texel"].get<double>(), memory.bytesPerTexel);
        EXPECT_DOUBLE_EQ(entry["memory"]["values_per_texel"].get<double>(), memory.valuesPerTexel);
        EXPECT_EQ(entry["memory"]["total_bytes"].get<std::uint64_t>(), memory.totalBytes);
        EXPECT_EQ(entry["memory"]["shared_bytes"].get<std::uint64_t>(), memory.sharedBytes);
        EXPECT_DOUBLE_EQ(entry["memory"]["compression_ratio"].get<double>(),
                         81.0 * 81.0 * 3.0 / memory.bytesPerTexel);
        EXPECT_EQ(entry["fit"]["seconds"].get<double>(),
                  std::stod(material->fitInfo.at("seconds")));
        EXPECT_GT(entry["fit"]["peak_rss_bytes"].get<std::uint64_t>(), 1000000u);
        EXPECT_EQ(entry["fit"]["reused"], false);
        // GPU path agrees with the CPU evaluator on llvmpipe (texelFetch everywhere).
        EXPECT_LT(entry["error"]["gpu_cpu_max_diff"].get<double>(), 1e-3);
        // One time per target, set against that target's empty and calibration passes. Only
        // the arithmetic is checked: timings never pass or fail.
        const nlohmann::json& times = entry["pass"]["targets"];
        ASSERT_EQ(times.size(), 2u) << entry.dump();
        for (std::size_t i = 0; i < times.size(); ++i) {
            const nlohmann::json& t = times[i];
            const nlohmann::json& calibration = results["calibrations"][i];
            EXPECT_EQ(t["target"], i == 0 ? "RGBA8" : "RGBA16F");
            EXPECT_EQ(calibration["target"], t["target"]);
            EXPECT_GT(t["ms"].get<double>(), 0.0);
            EXPECT_EQ(t["empty_ms"].get<double>(), calibration["empty_ms"].get<double>());
            EXPECT_EQ(t["shading_ms"].get<double>(),
                      t["ms"].get<double>() - t["empty_ms"].get<double>());
            const double readMs =
                calibration["fetch_ms"].get<double>() - calibration["empty_ms"].get<double>();
            if (readMs > 0) {
                EXPECT_DOUBLE_EQ(calibration["fetches_per_second"].get<double>(),
                                 4.0 * 32 * 32 / (readMs * 1e-3));
                // lambert and pca are counted: TEX total x pixels / rate.
                EXPECT_DOUBLE_EQ(t["floor_ms"].get<double>(),
                                 entry["pass"]["tex_total"].get<double>() * 32 * 32 /
                                     calibration["fetches_per_second"].get<double>() * 1e3);
                EXPECT_DOUBLE_EQ(t["floor_ratio"].get<double>(),
                                 t["shading_ms"].get<double>() / t["floor_ms"].get<double>());
            }
        }
    }
    EXPECT_EQ(results["pass"]["targets"], nlohmann::json::array({"RGBA8", "RGBA16F"}));
    // The printed table has both targets and the empty pass; the CSV one column per header.
    EXPECT_NE(r.output.find("RGBA8 ms   - empty  x floor   RGBA16F ms   - empty  x floor"),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("(empty pass)"), std::string::npos) << r.output;
    EXPECT_NE(report.find("| *empty pass* | 0 + 0 | 0 + 0 | 0 | 0 | no material |"),
              std::string::npos);
    {
        std::istringstream csv(readTextFile((out / "results.csv").string()));
        std::string header, row;
        std::getline(csv, header);
        EXPECT_NE(header.find(",rgba8_ms,rgba8_empty_ms,rgba8_shading_ms,rgba8_floor_ms,"
                              "rgba8_floor_ratio,rgba16f_ms,"),
                  std::string::npos)
            << header;
        const auto fields = [](const std::string& line) {
            std::size_t n = 1;
            bool quoted = false;
            for (char c : line) {
                if (c == '"') quoted = !quoted;
                n += !quoted && c == ',';
            }
            return n;
        };
        while (std::getline(csv, row)) EXPECT_EQ(fields(row), fields(header)) << row;
    }
    EXPECT_EQ(methodEntry(results, "pca")["options"]["components"], "3");

    // A second run reuses both fits (same options, newer than the input) and fits lpca again.
    const auto pcaTime = fs::last_write_time(out / "fits/pca.exr");
    const CommandResult again = btfWithGl(
        "compare " + shellQuote(zip) + " --methods pca,lpca --set pca:components=3 --set " +
        "lpca:clusters=0 --no-gpu --out " + shellQuote(out.string()));
    ASSERT_EQ(again.exitCode, 0) << again.output;
    std::ifstream in2(out / "results.json");
    const nlohmann::json second = nlohmann::json::parse(in2);
    EXPECT_EQ(methodEntry(second, "pca")["fit"]["reused"], true);
    EXPECT_EQ(methodEntry(second, "lambert")["fit"]["reused"], true);
    EXPECT_EQ(methodEntry(second, "lpca")["status"], "failed");
    EXPECT_EQ(methodEntry(second, "pca")["error"]["average"],
              methodEntry(results, "pca")["error"]["average"]);
    EXPECT_EQ(fs::last_write_time(out / "fits/pca.exr"), pcaTime);
    EXPECT_FALSE(second["gpu"]["ran"].get<bool>());
}

TEST(Harness, RecommendationPicksTheLowestErrorWithinBothBudgets) {
    CompareResult result;
    auto add = [&](const std::string& name, double error, double bytes, double ms, bool failed) {
        MethodResult m;
        m.method = name;
        m.error.average = error;
        m.memory.bytesPerTexel = bytes;
        MethodPass pass;
        pass.target = passTarget("rgba8");
        pass.pass.ms = ms;
        m.passes.push_back(pass);
        m.failed = failed;
        result.methods.push_back(m);
    };
    add("cheap", 0.10, 6, 1.0, false);
    add("big", 0.02, 4000, 2.0, false);
    add("slow", 0.04, 100, 50.0, false);
    add("broken", 0.001, 1, 0.1, true);  // failed methods never win
    recommend(result);
    EXPECT_EQ(result.recommended, "big");
    result.maxBytesPerTexel = 1000;
    recommend(result);
    EXPECT_EQ(result.recommended, "slow");
    result.maxMsPerPass = 10;
    recommend(result);
    EXPECT_EQ(result.recommended, "cheap");
    result.maxBytesPerTexel = 5;
    recommend(result);
    EXPECT_EQ(result.recommended, "");
    EXPECT_EQ(result.recommendation,
              "Recommendation: none; no completed method fits the budgets (at most 5 bytes per "
              "texel and at most 10 ms per pass (RGBA8, 256x256, 1 light))");
    // A time budget needs a measured time.
    result.maxBytesPerTexel = 0;
    result.methods[0].passes[0].pass.ms = -1;
    recommend(result);
    EXPECT_EQ(result.recommended, "big") << "2 ms fits; 'cheap' has no measured time";
}

TEST(Harness, ErrorMapColoursAndPlotAreWellFormed) {
    EXPECT_EQ(errorOf([] {
                  colourMappedErrors({1, 2, 3}, 2, 2, 1.0);
              }),
              "colourMappedErrors: 3 values for a 2x2 map");
    // Rows bottom-up in, top-down out; 0 maps to the dark end, the maximum to the bright end.
    const FloatImage map = colourMappedErrors({0.0f, 1.0f, INFINITY, NAN}, 2, 2, 1.0);
    ASSERT_EQ(map.width, 2);
    EXPECT_LT(map.at(0, 1, 1), 0.1f);  // texel (0, 0) = 0: dark
    EXPECT_GT(map.at(1, 1, 0), 0.9f);  // texel (1, 0) = 1: yellow
    EXPECT_GT(map.at(1, 1, 1), 0.8f);
    EXPECT_EQ(map.at(0, 0, 0), 1.0f);  // texel (0, 1) = Inf: magenta
    EXPECT_EQ(map.at(0, 0, 1), 0.0f);
    EXPECT_EQ(map.at(1, 0, 0), 0.5f);  // texel (1, 1) = NaN, not compared: grey
    EXPECT_EQ(map.at(1, 0, 1), 0.5f);
    const std::string svg = errorMemorySvg({{"a<b", 6, 0.1}, {"pca", 3888, 0.02}}, "t");
    EXPECT_EQ(svg.rfind("<svg ", 0), 0u);
    EXPECT_NE(svg.find("a&lt;b"), std::string::npos);
    EXPECT_NE(svg.find(">pca</text>"), std::string::npos);
    EXPECT_EQ(count(svg, "<circle"), 2u);
}

namespace {

SoakSample soakSample(int frame, int textures, double rssMiB = 100) {
    SoakSample s;
    s.frame = frame;
    s.textures = textures;
    s.osgTextureObjects = unsigned(textures);
    s.rssMiB = rssMiB;
    return s;
}

std::string soakGrowth(const std::vector<SoakSample>& samples) {
    return growthAfterWarmup(
        samples, [](const SoakSample& s) { return s.frame <= 300; }, 3.0, 0);
}

}  // namespace

TEST(SoakGrowth, OneLateDeletionIsNotGrowthButATextureThatStaysIs) {
    // Warm-up at 5 textures. One sample at 6 and back to 5 (OSG deleted a reload's texture a
    // frame late): flat. 6 from then on: grown, named at the first frame it stayed.
    EXPECT_EQ(soakGrowth({soakSample(0, 5), soakSample(300, 5), soakSample(600, 6),
                          soakSample(650, 5), soakSample(700, 5)}),
              "");
    EXPECT_EQ(soakGrowth({soakSample(0, 5), soakSample(300, 5), soakSample(600, 6),
                          soakSample(650, 6), soakSample(700, 6)}),
              "frame 600: GL textures 6 > 5 + 0; frame 600: OSG texture objects 6 > 5 + 0; "
              "frame 650: GL textures 6 > 5 + 0; frame 650: OSG texture objects 6 > 5 + 0; ");
    // The RSS is judged sample by sample, as before.
    EXPECT_EQ(soakGrowth({soakSample(0, 5), soakSample(300, 5), soakSample(600, 5, 104),
                          soakSample(650, 5)}),
              "frame 600: RSS MiB 104 > 100 + 3; ");
}

}  // namespace OSGBTF_TEST_FILE
