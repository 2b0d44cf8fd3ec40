// `btf batch`: held-out directions (their split, the source without them, the error on them),
// then the tool end to end on tiny generated materials: clear errors first, stable ids, a run,
// resuming, a failed job kept with its reason, a killed run, two runs at once, the leaderboard's
// files. The Slurm path is tests/slurm/ (real daemons); the page in a browser is
// tests/viewer/leaderboard_test.cpp.
#include <gtest/gtest.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <set>
#include <thread>

#include <nlohmann/json.hpp>

#include "core/ErrorMetrics.h"
#include "core/MeasuredBtf.h"
#include "harness/batch/Batch.h"
#include "harness/batch/Holdout.h"
#include "materials/MethodRegistry.h"
#include "tests/HandMadeBatch.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using namespace osgBTF::batch;
using osgBTF::test::builtTool;
using osgBTF::test::CommandResult;
using osgBTF::test::errorOf;
using osgBTF::test::readTextFile;
using osgBTF::test::runCommand;
using osgBTF::test::shellQuote;
using osgBTF::test::TempDir;

namespace {

/** Every value names its texel, view, light and channel, so a wrong index shows. */
float code(std::size_t texel, std::size_t view, std::size_t light, int channel) {
    return float(texel * 10000 + view * 1000 + light * 10 + std::size_t(channel));
}

MeasuredBtf codedBtf(int width, int height, std::size_t views, std::size_t lights) {
    std::vector<Direction> v, l;
    for (std::size_t i = 0; i < views; ++i) v.push_back({float(i * 10), float(i * 40)});
    for (std::size_t i = 0; i < lights; ++i) l.push_back({float(i * 8), float(i * 30)});
    MeasuredBtf btf(width, height, DirectionSet("v", v), DirectionSet("l", l));
    for (std::size_t view = 0; view < views; ++view)
        for (std::size_t light = 0; light < lights; ++light)
            for (std::size_t t = 0; t < btf.texelCount(); ++t)
                for (int c = 0; c < 3; ++c)
                    btf.setValue(view, light, t, c, code(t, view, light, c));
    return btf;
}

}  // namespace

TEST(BatchHoldout, AFractionOutsideItsRangeOrTooFewLightsIsAnError) {
    EXPECT_EQ(errorOf([] { holdoutSplit(81, 81, 0.6); }),
              "held-out fraction 0.600000 is not in [0, 0.5]");
    EXPECT_EQ(errorOf([] { holdoutSplit(81, 2, 0.1); }),
              "cannot leave directions out of 2 lights (fewer than three)");
    const HoldoutSplit none = holdoutSplit(81, 2, 0.0);
    EXPECT_TRUE(none.leftOutPairs.empty());
    EXPECT_EQ(none.keptLights.size(), 2u);
}

TEST(BatchHoldout, SplitLeavesOutAboutTheFractionOfPairsTheSameEveryTime) {
    const HoldoutSplit split = holdoutSplit(81, 81, 0.1);
    // a = 1 - sqrt(0.9) = 0.0513 of 81 directions: 4 views and 4 lights, 81^2 - 77^2 pairs.
    EXPECT_EQ(split.keptViews.size(), 77u);
    EXPECT_EQ(split.keptLights.size(), 77u);
    EXPECT_EQ(split.leftOutPairs.size(), 81u * 81u - 77u * 77u);
    EXPECT_FALSE(split.viewLeftOut[0]);
    EXPECT_FALSE(split.lightLeftOut[0]);
    for (const std::size_t p : split.leftOutPairs)
        EXPECT_TRUE(split.viewLeftOut[p / 81] || split.lightLeftOut[p % 81]) << p;
    const HoldoutSplit again = holdoutSplit(81, 81, 0.1);
    EXPECT_EQ(again.leftOutPairs, split.leftOutPairs);
    // One view: only lights are left out, the fraction of them itself.
    const HoldoutSplit oneView = holdoutSplit(1, 40, 0.1);
    EXPECT_EQ(oneView.leftOutPairs.size(), 4u);
    EXPECT_EQ(oneView.keptViews.size(), 1u);
}

TEST(BatchHoldout, SubsetSourceReadsTheKeptDirectionsValues) {
    const MeasuredBtf btf = codedBtf(3, 2, 5, 7);
    const HoldoutSplit split = holdoutSplit(5, 7, 0.3);
    const DirectionSubsetSource kept(btf, split);
    ASSERT_EQ(kept.viewCount(), split.keptViews.size());
    ASSERT_EQ(kept.lightCount(), split.keptLights.size());
    ASSERT_LT(kept.imageCount(), btf.imageCount());
    for (std::size_t i = 0; i < kept.viewCount(); ++i)
        EXPECT_EQ(kept.views()[i].theta, btf.views()[split.keptViews[i]].theta);

    std::vector<float> images(kept.imageCount() * 6 * 3);
    kept.readImages(0, kept.imageCount(), images.data());
    std::vector<float> abrdfs(6 * kept.imageCount() * 3);
    kept.readAbrdfRange(0, 6, abrdfs.data());
    for (std::size_t v = 0; v < kept.viewCount(); ++v)
        for (std::size_t l = 0; l < kept.lightCount(); ++l)
            for (std::size_t t = 0; t < 6; ++t)
                for (int c = 0; c < 3; ++c) {
                    const float expected = code(t, split.keptViews[v], split.keptLights[l], c);
                    const std::size_t image = v * kept.lightCount() + l;
                    EXPECT_EQ(images[(image * 6 + t) * 3 + c], expected);
                    EXPECT_EQ(abrdfs[(t * kept.imageCount() + image) * 3 + c], expected);
                }
}

TEST(BatchHoldout, ErrorOnChosenPairsCountsOnlyThem) {
    MeasuredBtf btf(4, 4, DirectionSet::bonn81(), DirectionSet::bonn81());
    for (std::size_t v = 0; v < 81; ++v)
        for (std::size_t l = 0; l < 81; ++l)
            for (std::size_t t = 0; t < 16; ++t)
                for (int c = 0; c < 3; ++c) btf.setValue(v, l, t, c, 0.25f * float(c));
    const std::vector<std::size_t> pairs{1, 700, 6000};
    // Off by 2^-7 per channel on the chosen pairs (exact in float), garbage elsewhere, which
    // must not count: average sqrt(3) 2^-7, RMSE 2^-7.
    const ErrorSummary e = computeError(
        btf,
        [&](std::size_t, float* out) {
            for (std::size_t p = 0; p < btf.imageCount(); ++p)
                for (int c = 0; c < 3; ++c) out[p * 3 + c] = 1e6f;
            for (const std::size_t p : pairs)
                for (int c = 0; c < 3; ++c) out[p * 3 + c] = 0.25f * float(c) + 0.0078125f;
        },
        nullptr, &pairs);
    EXPECT_NEAR(e.average, 0.0078125 * std::sqrt(3.0), 1e-9);
    EXPECT_NEAR(e.rmse, 0.0078125, 1e-9);
}

TEST(BatchHoldout, AnExactModelPredictsTheLeftOutDirections) {
    // Lambert data (albedo x cos(light theta), any view), albedos exact in half: the lambert fit
    // without the left-out directions predicts them; the error is float rounding only.
    MeasuredBtf btf(4, 4, DirectionSet::bonn81(), DirectionSet::bonn81());
    for (std::size_t v = 0; v < btf.viewCount(); ++v)
        for (std::size_t l = 0; l < btf.lightCount(); ++l)
            for (std::size_t t = 0; t < btf.texelCount(); ++t)
                for (int c = 0; c < 3; ++c)
                    btf.setValue(v, l, t, c,
                                 float(0.125 * double(1 + (t + c) % 7)) * btf.lights().vector(l).z);
    const HoldoutSplit split = holdoutSplit(81, 81, 0.1);
    const DirectionSubsetSource kept(btf, split);
    const osg::ref_ptr<Material> fitted = findMethod("lambert").fit(kept, FitOptions());
    const ErrorSummary e = computeError(
        btf,
        [&](std::size_t t, float* out) {
            for (const std::size_t p : split.leftOutPairs) {
                const glm::vec3 value =
                    fitted->evaluate(int(t % 4), int(t / 4), btf.views().vector(p / 81),
                                     btf.lights().vector(p % 81));
                for (int c = 0; c < 3; ++c) out[p * 3 + c] = value[c];
            }
        },
        nullptr, &split.leftOutPairs);
    EXPECT_LT(e.average, 1e-6);
}

namespace {

std::string btf() {
    return builtTool("btf") + " --no-progress";
}

/** Two tiny materials: DIR/fabric/wool01.zip and DIR/stone02.zip (8x8, the Bonn directions). */
void makeDatabase(const fs::path& dir) {
    fs::create_directories(dir / "fabric");
    for (const auto& [file, variation] :
         {std::pair{"fabric/wool01.zip", "0"}, std::pair{"stone02.zip", "0.8"}}) {
        const CommandResult r =
            runCommand(btf() + " sample -o " + shellQuote((dir / file).string()) +
                       " --size 8 --variation " + variation);
        ASSERT_EQ(r.exitCode, 0) << r.output;
    }
}

nlohmann::json readJson(const fs::path& path) {
    std::ifstream in(path);
    return nlohmann::json::parse(in);
}

std::set<std::string> jobIds(const fs::path& results) {
    std::set<std::string> ids;
    const nlohmann::json manifest = readJson(results / "manifest.json");
    for (const auto& job : manifest["jobs"]) ids.insert(job["id"].get<std::string>());
    return ids;
}

std::string state(const fs::path& results, const std::string& id) {
    const fs::path file = results / "jobs" / id / "result.json";
    return fs::exists(file) ? readJson(file)["state"].get<std::string>() : "none";
}

/** Files under `folder` whose name has a writer's temporary suffix (".tmp<pid>"). */
std::vector<std::string> temporaries(const fs::path& folder) {
    std::vector<std::string> found;
    for (const auto& entry : fs::recursive_directory_iterator(folder))
        if (entry.path().filename().string().find(".tmp") != std::string::npos)
            found.push_back(entry.path().string());
    return found;
}

}  // namespace

TEST(BtfBatch, PlanOfAFolderWithoutBtfsIsAClearError) {
    TempDir dir;
    fs::create_directories(dir.path() / "empty");
    const CommandResult r = runCommand(btf() + " batch plan " + shellQuote(dir.file("empty")) +
                                       " --out " + shellQuote(dir.file("results")));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("btf: error: " + dir.file("empty") +
                            ": no measured BTF found (UBO2014 .btf files, UBO2003/ATRIUM zips, "
                            "folders of UBO2003-named images, RTI sets: images with their .lp "
                            "file)"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(fs::exists(dir.file("results")));
}

// RTI capture sets in a database: a folder of photos with its .lp file (the real capture's crop)
// is one material, as is a zip of the same; the folder is not searched further.
TEST(BtfBatch, PlanFindsRtiSetsAsFoldersAndZips) {
    TempDir dir;
    const fs::path db = dir.path() / "db";
    const fs::path capture = fs::path(test::sourceDir()) / "tests/data/rti-icon-64";
    fs::create_directories(db / "icons");
    fs::copy(capture, db / "icons" / "icon01");
    std::string members;
    for (const auto& entry : fs::directory_iterator(capture))
        if (entry.path().extension() == ".jpg" || entry.path().extension() == ".lp")
            members += " " + shellQuote(entry.path().filename().string());
    ASSERT_EQ(runCommand("cd " + shellQuote(capture.string()) + " && zip -q " +
                         shellQuote((db / "icon02.zip").string()) + members)
                  .exitCode,
              0);
    const CommandResult plan = runCommand(btf() + " batch plan " + shellQuote(db.string()) +
                                          " --out " + shellQuote(dir.file("r")) + " --methods hsh");
    ASSERT_EQ(plan.exitCode, 0) << plan.output;
    EXPECT_NE(plan.output.find("planned 2 jobs: 2 materials x 1 methods"), std::string::npos)
        << plan.output;
    const nlohmann::json manifest = readJson(dir.path() / "r" / "manifest.json");
    std::set<std::string> inputs, names;
    for (const auto& material : manifest["materials"]) {
        inputs.insert(material["input"].get<std::string>());
        names.insert(material["name"].get<std::string>());
        EXPECT_EQ(material["views"], 1);
        EXPECT_EQ(material["lights"], 72);
    }
    EXPECT_EQ(inputs, (std::set<std::string>{(db / "icon02.zip").string(),
                                             (db / "icons" / "icon01").string()}))
        << manifest.dump(1);
    EXPECT_EQ(names, (std::set<std::string>{"icon01", "icon02"}));

    // Named by its .lp file, the set is its folder's material.
    const CommandResult byLp = runCommand(
        btf() + " batch plan " + shellQuote((db / "icons" / "icon01" / "dirs.lp").string()) +
        " --out " + shellQuote(dir.file("r2")) + " --methods hsh");
    ASSERT_EQ(byLp.exitCode, 0) << byLp.output;
    EXPECT_EQ(readJson(dir.path() / "r2" / "manifest.json")["materials"][0]["name"], "icon01");
}

TEST(BtfBatch, RunWithoutAPlanAndUnknownMethodsAreClearErrors) {
    TempDir dir;
    const CommandResult run = runCommand(btf() + " batch run " + shellQuote(dir.file("none")));
    EXPECT_EQ(run.exitCode, 1);
    EXPECT_NE(run.output.find("btf: error: " + dir.file("none") +
                              ": no manifest.json (run `btf batch plan` first)"),
              std::string::npos)
        << run.output;
    makeDatabase(dir.path() / "db");
    const CommandResult plan =
        runCommand(btf() + " batch plan " + shellQuote(dir.file("db")) + " --out " +
                   shellQuote(dir.file("r")) + " --methods lambert,nosuch");
    EXPECT_EQ(plan.exitCode, 1);
    EXPECT_NE(plan.output.find("unknown method 'nosuch'"), std::string::npos) << plan.output;
    EXPECT_FALSE(fs::exists(dir.file("r")));
}

TEST(BtfBatch, PlansStableIdsRunsResumesAndReports) {
    TempDir dir;
    makeDatabase(dir.path() / "db");
    const fs::path results = dir.path() / "results";
    const std::string plan = btf() + " batch plan " + shellQuote(dir.file("db")) + " --out " +
                             shellQuote(results.string()) + " --methods lambert,pca";
    CommandResult r = runCommand(plan);
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const std::set<std::string> expected{"wool01--lambert", "wool01--pca", "stone02--lambert",
                                         "stone02--pca"};
    EXPECT_EQ(jobIds(results), expected);
    const nlohmann::json manifest = readJson(results / "manifest.json");
    for (const auto& m : manifest["materials"])
        EXPECT_EQ(m["class"], m["name"] == "wool01" ? "fabric" : "stone") << m;
    for (const auto& j : manifest["jobs"]) EXPECT_GT(j["estimated_peak_bytes"].get<double>(), 0);

    r = runCommand(btf() + " batch run " + shellQuote(results.string()) + " -j 2");
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("batch: 4 jobs run (4 done, 0 failed); 0 were done before"),
              std::string::npos)
        << r.output;
    for (const std::string& id : expected) {
        const nlohmann::json result = readJson(results / "jobs" / id / "result.json");
        EXPECT_EQ(result["state"], "done") << id;
        EXPECT_GT(result["heldout_pairs"].get<int>(), 0) << id;
        // The held-out pairs are predicted, not stored: no better than the stored ones.
        EXPECT_GE(result["heldout_avg"].get<double>(), result["avg"].get<double>() * 0.9) << id;
        EXPECT_TRUE(fs::exists(results / "jobs" / id / "fit.btfmat")) << id;
    }

    // Planned again: the same ids, and the results stay.
    ASSERT_EQ(runCommand(plan).exitCode, 0);
    EXPECT_EQ(jobIds(results), expected);
    r = runCommand(btf() + " batch run " + shellQuote(results.string()));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("batch: 0 jobs run (0 done, 0 failed); 4 were done before"),
              std::string::npos)
        << r.output;

    // A job whose result is gone, with what a killed writer left: only it runs again.
    fs::remove(results / "jobs" / "stone02--pca" / "result.json");
    test::writeTextFile((results / "jobs" / "stone02--pca" / "result.json.tmp999999").string(),
                        "{");
    r = runCommand(btf() + " batch run " + shellQuote(results.string()));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("batch: 1 jobs run (1 done, 0 failed); 3 were done before"),
              std::string::npos)
        << r.output;
    EXPECT_TRUE(temporaries(results).empty());

    r = runCommand(btf() + " batch report " + shellQuote(results.string()));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const nlohmann::json report = readJson(results / "results.json");
    ASSERT_EQ(report["rows"].size(), 4u);
    for (const auto& row : report["rows"]) EXPECT_EQ(row["status"], "done") << row;
    const std::string csv = readTextFile((results / "results.csv").string());
    EXPECT_EQ(std::count(csv.begin(), csv.end(), '\n'), 5) << csv;
    const std::string page = readTextFile((results / "index.html").string());
    EXPECT_EQ(page.find("/*OSGBTF_LEADERBOARD_DATA*/null"), std::string::npos);
    EXPECT_NE(page.find("\"job\":\"wool01--pca\""), std::string::npos);
    EXPECT_NE(readTextFile((results / "report.md").string()).find("| fabric | 1 |"),
              std::string::npos);
}

TEST(BtfBatch, AFailedJobKeepsItsReasonAndTheOthersComplete) {
    TempDir dir;
    makeDatabase(dir.path() / "db");
    const fs::path results = dir.path() / "results";
    ASSERT_EQ(runCommand(btf() + " batch plan " + shellQuote(dir.file("db")) + " --out " +
                         shellQuote(results.string()) + " --methods lambert --holdout-fraction 0")
                  .exitCode,
              0);
    // The input of one material breaks after the plan.
    const std::string broken = dir.file("db/stone02.zip");
    fs::rename(broken, broken + ".away");
    CommandResult r = runCommand(btf() + " batch run " + shellQuote(results.string()));
    EXPECT_EQ(r.exitCode, 1) << r.output;
    EXPECT_NE(r.output.find("batch: stone02--lambert failed: " + broken + ": no such file"),
              std::string::npos)
        << r.output;
    EXPECT_NE(r.output.find("btf: error: 1 jobs failed"), std::string::npos) << r.output;
    EXPECT_EQ(state(results, "wool01--lambert"), "done");
    EXPECT_EQ(state(results, "stone02--lambert"), "failed");
    r = runCommand(btf() + " batch status " + shellQuote(results.string()));
    EXPECT_NE(r.output.find("failed: " + broken + ": no such file"), std::string::npos) << r.output;

    fs::rename(broken + ".away", broken);
    r = runCommand(btf() + " batch run " + shellQuote(results.string()));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_EQ(state(results, "stone02--lambert"), "done");
}

TEST(BtfBatch, AKilledRunLeavesNoPartialResultAndTheNextRunCompletes) {
    TempDir dir;
    makeDatabase(dir.path() / "db");
    const fs::path results = dir.path() / "results";
    ASSERT_EQ(runCommand(btf() + " batch plan " + shellQuote(dir.file("db")) + " --out " +
                         shellQuote(results.string()) + " --methods lambert,pca,ptm")
                  .exitCode,
              0);
    // Its own process group, so that one kill -9 takes the run and the job it is running.
    const pid_t run = fork();
    ASSERT_GE(run, 0);
    if (run == 0) {
        setpgid(0, 0);
        execl("/bin/sh", "sh", "-c",
              (btf() + " batch run " + shellQuote(results.string()) + " >/dev/null 2>&1").c_str(),
              static_cast<char*>(nullptr));
        _exit(127);
    }
    setpgid(run, run);
    // Killed once the first result is there and the second job is under way (or sooner).
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    while (std::chrono::steady_clock::now() < deadline) {
        std::size_t done = 0;
        for (const std::string& id : jobIds(results)) done += state(results, id) != "none";
        if (done >= 1) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(20));
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(150));
    kill(-run, SIGKILL);
    int status = 0;
    waitpid(run, &status, 0);
    std::size_t finished = 0;
    for (const std::string& id : jobIds(results)) {
        const std::string s = state(results, id);  // parses: never half a file
        EXPECT_TRUE(s == "none" || s == "done") << id << ": " << s;
        finished += s == "done";
    }
    EXPECT_LT(finished, jobIds(results).size()) << "the run ended before the kill";

    const CommandResult r = runCommand(btf() + " batch run " + shellQuote(results.string()));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    for (const std::string& id : jobIds(results)) EXPECT_EQ(state(results, id), "done") << id;
    EXPECT_TRUE(temporaries(results).empty());
}

TEST(BtfBatch, TwoRunsAtOnceDoEveryJobOnce) {
    TempDir dir;
    makeDatabase(dir.path() / "db");
    const fs::path results = dir.path() / "results";
    ASSERT_EQ(
        runCommand(btf() + " batch plan " + shellQuote(dir.file("db")) + " --out " +
                   shellQuote(results.string()) + " --methods lambert,pca,ptm --holdout-fraction 0")
            .exitCode,
        0);
    const std::string run = btf() + " batch run " + shellQuote(results.string());
    const CommandResult r =
        runCommand("{ " + run + " >" + shellQuote(dir.file("a.log")) + " 2>&1 & " + run + " >" +
                   shellQuote(dir.file("b.log")) + " 2>&1; b=$?; wait $!; a=$?; echo \"$a $b\"; }");
    EXPECT_EQ(r.output, "0 0\n") << readTextFile(dir.file("a.log"))
                                 << readTextFile(dir.file("b.log"));
    for (const std::string& id : jobIds(results)) EXPECT_EQ(state(results, id), "done") << id;
    EXPECT_TRUE(temporaries(results).empty());
}

TEST(BtfBatch, ReportOfHandMadeResultsHasTheParetoFrontAndRecommendations) {
    TempDir dir;
    const fs::path results = dir.path() / "results";
    test::writeHandMadeBatch(results);
    const CommandResult r = runCommand(btf() + " batch report " + shellQuote(results.string()));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const nlohmann::json report = readJson(results / "results.json");
    std::map<std::string, nlohmann::json> rows;
    for (const auto& row : report["rows"]) rows[row["job"].get<std::string>()] = row;
    ASSERT_EQ(rows.size(), 9u);
    EXPECT_EQ(rows["wool02--pca"]["status"], "failed");
    EXPECT_EQ(rows["wool02--pca"]["failure"], "/data/fabric/wool02.zip: no such file <!--<script>");
    EXPECT_EQ(rows["stone01--ptm"]["status"], "pending");
    for (const auto& [id, row] : rows)
        EXPECT_EQ(row["pareto"].get<bool>(), row["status"] == "done" && id != "wool01--ptm") << id;
    std::map<std::string, std::string> recommended;
    for (const auto& c : report["classes"])
        recommended[c["class"].get<std::string>()] = c["recommended"].get<std::string>();
    EXPECT_EQ(recommended,
              (std::map<std::string, std::string>{{"fabric", "ptm"}, {"stone", "pca"}}));
    const std::string md = readTextFile((results / "report.md").string());
    EXPECT_NE(md.find("| fabric | 2 | ptm | lowest mean held-out average error (0.061)"),
              std::string::npos)
        << md;
    EXPECT_NE(md.find("3 materials, 9 jobs: 7 done, 1 failed, 1 pending"), std::string::npos) << md;
    // No value can end the page's script: the failure text's '<' is escaped.
    const std::string page = readTextFile((results / "index.html").string());
    EXPECT_EQ(page.find("<!--<script>"), std::string::npos);
    EXPECT_NE(page.find("no such file \\u003c!--\\u003cscript>"), std::string::npos);
}

}  // namespace OSGBTF_TEST_FILE
