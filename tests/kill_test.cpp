// SIGKILL at random moments while `btf fit -o`, `btf compare --out` and the plugin's fit-cache
// write run, and two processes filling one cache entry at once. After every
// kill, what is under a final name must load completely (or not exist); temporaries sit only under
// names no reader opens (NAME.tmp<pid>, NAME.old<pid>), and the next run removes those of dead
// processes. The cache writer is this test executable itself, started again with a filter that
// runs only KillChild.DISABLED_ReadsThroughThePlugin (so it works in the sanitizer build too).
#include <fcntl.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <fstream>
#include <functional>
#include <random>
#include <regex>
#include <set>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include "core/FloatImage.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/fmf/Fmf.h"
#include "streaming/TileSet.h"
#include "tests/PluginTestUtil.h"
#include "tests/RandomFactors.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

extern char** environ;  // POSIX: the process environment, for the children

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;
namespace fs = std::filesystem;

namespace {

using Clock = std::chrono::steady_clock;

/** Starts `args` with `extraEnvironment` added, stdout and stderr into `log` (default:
 *  discarded). */
pid_t start(const std::vector<std::string>& args,
            const std::vector<std::string>& extraEnvironment = {},
            const std::string& log = "/dev/null") {
    std::vector<std::string> environment(extraEnvironment);
    // Not GoogleTest's sharding (tests/run-sharded.sh): a child that is this program, started for
    // one named test, would run it only in the shard that test falls into, and nothing elsewhere.
    for (char** e = environ; *e; ++e)
        if (std::string_view(*e).rfind("GTEST_", 0) != 0) environment.emplace_back(*e);
    std::vector<char*> argv, envp;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    for (std::string& e : environment) envp.push_back(e.data());
    argv.push_back(nullptr);
    envp.push_back(nullptr);
    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    pid_t pid = -1;
    const int error = posix_spawn(&pid, argv[0], &actions, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&actions);
    return error == 0 ? pid : -1;
}

int waitFor(pid_t pid) {
    int status = 0;
    while (waitpid(pid, &status, 0) < 0 && errno == EINTR) {
    }
    return status;
}

/** One kind of writer: how to start it, its final name, and what makes that name complete. */
struct Writer {
    std::string name;
    std::vector<std::string> args;
    std::vector<std::string> environment;
    fs::path folder;  ///< where it writes its final name and temporaries
    /** Empty when everything under a final name in `folder` is complete, else the problem. */
    std::function<std::string()> checkFinal;
    /** Final names in `folder`: removed before some kills, so both "new" and "replace" happen. */
    std::function<void()> removeFinal;
    /** True for a name in `folder` that is a final name (not a temporary). */
    std::function<bool(const std::string&)> isFinal;
};

const std::regex kTemporary(R"(.+\.(tmp|old)[0-9]+)");

/** Everything in the folder is a final name or a temporary of the writer's patterns. */
std::string strayNames(const Writer& writer, int& temporaries) {
    temporaries = 0;
    std::string stray;
    for (const auto& entry : fs::directory_iterator(writer.folder)) {
        const std::string name = entry.path().filename().string();
        if (writer.isFinal(name)) continue;
        if (std::regex_match(name, kTemporary))
            ++temporaries;
        else
            stray += " " + name;
    }
    return stray;
}

/** Loads every fitted material of `paths`; the first problem, or empty. */
std::string loadAll(const std::vector<fs::path>& paths) {
    for (const fs::path& path : paths) {
        const std::string problem = errorOf([&] { loadMaterial(path.string()); });
        if (problem != "no error") return path.string() + ": " + problem;
    }
    return {};
}

/** No running process names `text` in its command line (a compare's orphaned fit would). */
bool processMentions(const std::string& text) {
    for (const auto& entry : fs::directory_iterator("/proc")) {
        std::ifstream in(entry.path() / "cmdline", std::ios::binary);
        const std::string line((std::istreambuf_iterator<char>(in)), {});
        if (line.find(text) != std::string::npos && entry.path().filename() != "self" &&
            entry.path().filename() != std::to_string(getpid()))
            return true;
    }
    return false;
}

double runToEnd(const Writer& writer) {
    const auto begin = Clock::now();
    const pid_t pid = start(writer.args, writer.environment);
    EXPECT_GT(pid, 0) << writer.name;
    const int status = waitFor(pid);
    EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0)
        << writer.name << " failed with status " << status;
    return std::chrono::duration<double>(Clock::now() - begin).count();
}

/** Starts `writer` until `kills` SIGKILLs have hit it running (at most three times as many
 *  starts), at moments drawn uniformly over one complete run's duration, and checks its folder
 *  after each. A run that ends before its moment shortens that duration: the first, measured run
 *  is often the slowest (cold caches, other tests starting on a loaded machine). Returns how many
 *  kills hit a running writer. */
int killRepeatedly(const Writer& writer, int kills, std::mt19937& random) {
    double full = runToEnd(writer);
    EXPECT_EQ(writer.checkFinal(), "") << writer.name << " after a complete run";
    std::uniform_real_distribution<double> moment(0.0, full);
    int hits = 0;
    for (int k = 0; k < 3 * kills && hits < kills; ++k) {
        if (k % 2 == 0) writer.removeFinal();
        const pid_t pid = start(writer.args, writer.environment);
        EXPECT_GT(pid, 0);
        const double delay = moment(random);
        std::this_thread::sleep_for(std::chrono::duration<double>(delay));
        int status = 0;
        if (waitpid(pid, &status, WNOHANG) == pid) {
            // Finished already: runs got faster (warm caches, less load) than the one measured.
            full = std::min(full, delay);
            moment = std::uniform_real_distribution<double>(0.0, full);
        } else {
            kill(pid, SIGKILL);
            status = waitFor(pid);
            if (WIFSIGNALED(status) && WTERMSIG(status) == SIGKILL) ++hits;
        }
        EXPECT_EQ(writer.checkFinal(), "") << writer.name << " after kill " << k;
        int temporaries = 0;
        EXPECT_EQ(strayNames(writer, temporaries), "") << writer.name << " after kill " << k;
    }
    // A complete run afterwards replaces the result and removes the dead runs' temporaries.
    writer.removeFinal();
    runToEnd(writer);
    EXPECT_EQ(writer.checkFinal(), "") << writer.name << " after the last run";
    int temporaries = 0;
    EXPECT_EQ(strayNames(writer, temporaries), "");
    EXPECT_EQ(temporaries, 0) << writer.name << ": temporaries of killed runs are left";
    return hits;
}

std::string makeSample(const TempDir& dir) {
    return writeSmallSampleZip(dir.file("sample.zip"));
}

std::vector<fs::path> filesEndingIn(const fs::path& folder, const std::string& suffix) {
    std::vector<fs::path> found;
    for (const auto& entry : fs::directory_iterator(folder)) {
        const std::string name = entry.path().filename().string();
        if (name.size() >= suffix.size() &&
            name.compare(name.size() - suffix.size(), suffix.size(), suffix) == 0)
            found.push_back(entry.path());
    }
    return found;
}

/** The cache writer: this executable reading `zip` through the plugin with the cache in
 *  `cache`. */
Writer cacheWriter(const std::string& zip, const fs::path& cache) {
    Writer w;
    w.name = "plugin fit cache";
    w.args = {"/proc/self/exe", "--gtest_filter=KillChild.DISABLED_ReadsThroughThePlugin",
              "--gtest_also_run_disabled_tests"};
    // /proc/self/exe is resolved by the child itself: read the link here instead.
    w.args[0] = fs::read_symlink("/proc/self/exe").string();
    w.environment = {"OSGBTF_KILL_TEST_READ=" + zip,
                     "OSGBTF_KILL_TEST_OPTIONS=method=lambert cache=" + cache.string()};
    w.folder = cache;
    w.isFinal = [](const std::string& name) {
        return std::regex_match(name, std::regex(".*\\.btfmat"));
    };
    w.checkFinal = [cache] { return loadAll(filesEndingIn(cache, ".btfmat")); };
    w.removeFinal = [cache] {
        for (const fs::path& p : filesEndingIn(cache, ".btfmat")) fs::remove(p);
    };
    return w;
}

}  // namespace

// Not a test by itself: the process the cache tests start (and kill).
TEST(KillChild, DISABLED_ReadsThroughThePlugin) {
    const char* file = std::getenv("OSGBTF_KILL_TEST_READ");
    const char* options = std::getenv("OSGBTF_KILL_TEST_OPTIONS");
    if (!file || !options) GTEST_SKIP() << "started by the kill tests only";
    // Several children start their reads together when told to (a file appearing).
    if (const char* go = std::getenv("OSGBTF_KILL_TEST_GO")) {
        writeTextFile(std::string(go) + ".ready" + std::to_string(getpid()), "");
        const auto deadline = Clock::now() + std::chrono::seconds(30);
        while (!fs::exists(go) && Clock::now() < deadline)
            std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    const auto result = readNode(file, options);
    ASSERT_NE(asMaterialNode(result), nullptr) << result.message();
}

TEST(Kills, FitOutputIsCompleteOrAbsentAfterEveryKill) {
    TempDir dir;
    const std::string zip = makeSample(dir);
    const fs::path out = dir.path() / "out";
    fs::create_directory(out);
    const fs::path material = out / "fit.btfmat";
    Writer w;
    w.name = "btf fit -o";
    w.args = {builtTool("btf"), "--no-progress", "fit", zip, "-m", "lambert", "-o",
              material.string()};
    w.folder = out;
    w.isFinal = [](const std::string& name) { return name == "fit.btfmat"; };
    w.checkFinal = [material] {
        return fs::exists(material) ? loadAll({material}) : std::string();
    };
    w.removeFinal = [material] { fs::remove(material); };
    std::mt19937 random(16031);
    EXPECT_EQ(killRepeatedly(w, 4, random), 4) << "kills should land while it runs";
}

TEST(Kills, CompareFolderIsCompleteOrAbsentAfterEveryKill) {
    TempDir dir;
    const std::string zip = makeSample(dir);
    const fs::path out = dir.path() / "out";
    fs::create_directory(out);
    const fs::path report = out / "report";
    Writer w;
    w.name = "btf compare --out";
    // No held-out fits: each is one more child of the same kind (CI time; what is killed is the
    // folder's publication, which they do not change).
    w.args = {builtTool("btf"), "--no-progress",      "compare", zip,     "--methods",    "lambert",
              "--no-gpu",       "--holdout-fraction", "0",       "--out", report.string()};
    w.folder = out;
    w.isFinal = [](const std::string& name) { return name == "report"; };
    // What a complete run writes (recorded from the first one): every file, and the fits load.
    auto expected = std::make_shared<std::set<std::string>>();
    auto listing = [report] {
        std::set<std::string> files;
        for (const auto& e : fs::recursive_directory_iterator(report))
            if (e.is_regular_file()) files.insert(fs::relative(e.path(), report).string());
        return files;
    };
    w.checkFinal = [report, expected, listing]() -> std::string {
        if (!fs::exists(report)) return {};
        const std::set<std::string> files = listing();
        if (expected->empty()) *expected = files;
        if (files != *expected) return "the folder holds other files than a complete run's";
        for (const char* name : {"report.md", "results.csv", "results.json"})
            if (fs::file_size(report / name) == 0) return std::string(name) + " is empty";
        return loadAll(filesEndingIn(report / "fits", ".exr"));
    };
    w.removeFinal = [report] { fs::remove_all(report); };
    std::mt19937 random(16032);
    EXPECT_EQ(killRepeatedly(w, 4, random), 4) << "kills should land while it runs";
    EXPECT_TRUE(expected->count("results.json")) << "the complete run's listing was recorded";
    EXPECT_TRUE(expected->count("fits/lambert.exr"));
    // The fits compare started died with it (OSGBTF_PARENT_PID): nothing still writes there.
    std::this_thread::sleep_for(std::chrono::milliseconds(200));
    EXPECT_FALSE(processMentions(report.string() + ".tmp"));
}

TEST(Kills, TileSetFolderIsCompleteOrAbsentAfterEveryKill) {
    TempDir dir;
    // Large enough for kills to land while it runs (a full run takes ~4 s under the sanitizers):
    // 8 groups x 21 tiles of 64 + 4 texels.
    const std::string material = dir.file("m.btfmat");
    saveMaterial(
        *FmfMaterial::fromFactors(randomFactors(FactorModel::Fmf, {32, 0, 0}, 256, 256, 7)),
        material);
    const fs::path out = dir.path() / "out";
    fs::create_directory(out);
    const fs::path tiles = out / "tiles";
    Writer w;
    w.name = "btf tiles -o";
    w.args = {builtTool("btf"), "--no-progress", "tiles", material, "-o", tiles.string()};
    w.folder = out;
    w.isFinal = [](const std::string& name) { return name == "tiles"; };
    // Complete: the index reads and every file it lists is there, of its size and CRC, and
    // decodes (loadTileSetFinest reads them all).
    w.checkFinal = [tiles]() -> std::string {
        if (!fs::exists(tiles)) return {};
        const std::string problem = errorOf([&] { loadTileSetFinest(tiles.string()); });
        return problem == "no error" ? std::string() : problem;
    };
    w.removeFinal = [tiles] { fs::remove_all(tiles); };
    std::mt19937 random(16033);
    EXPECT_EQ(killRepeatedly(w, 4, random), 4) << "kills should land while it runs";
}

TEST(Kills, PluginCacheEntryIsCompleteOrAbsentAfterEveryKill) {
    TempDir dir;
    const std::string zip = makeSample(dir);
    const fs::path cache = dir.path() / "cache";
    fs::create_directory(cache);
    std::mt19937 random(16033);
    EXPECT_EQ(killRepeatedly(cacheWriter(zip, cache), 4, random), 4)
        << "kills should land while it runs";
}

TEST(Kills, TwoProcessesFillingOneCacheEntryBothSucceed) {
    TempDir dir;
    const std::string zip = makeSample(dir);
    const fs::path cache = dir.path() / "cache";
    fs::create_directory(cache);
    const Writer w = cacheWriter(zip, cache);
    // Both started together find no entry, fit and write it; one file results. Every round must
    // hold that; a round where one child was scheduled so late that it found the other's entry
    // (it says "using the cached fit") does not count as both filling it, so up to five rounds
    // are run until one has both fitting at once.
    bool bothFitted = false;
    for (int round = 0; round < 5 && !bothFitted; ++round) {
        w.removeFinal();
        const std::string go = dir.file("go" + std::to_string(round));
        const std::string logA = go + ".a.log", logB = go + ".b.log";
        std::vector<std::string> environment = w.environment;
        environment.push_back("OSGBTF_KILL_TEST_GO=" + go);
        const pid_t a = start(w.args, environment, logA), b = start(w.args, environment, logB);
        ASSERT_GT(a, 0);
        ASSERT_GT(b, 0);
        // Polled, not spun: a busy loop here starved the two children on a two-core machine.
        for (const auto deadline = Clock::now() + std::chrono::seconds(120);
             !(fs::exists(go + ".ready" + std::to_string(a)) &&
               fs::exists(go + ".ready" + std::to_string(b)));
             std::this_thread::sleep_for(std::chrono::milliseconds(5)))
            ASSERT_LT(Clock::now(), deadline) << "the children did not start";
        writeTextFile(go, "");
        for (const pid_t pid : {a, b}) {
            const int status = waitFor(pid);
            EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << "status " << status;
        }
        bothFitted = true;
        for (const std::string& log : {logA, logB})
            if (readTextFile(log).find("fitting method 'lambert'") == std::string::npos)
                bothFitted = false;
        std::vector<std::string> names;
        for (const auto& e : fs::directory_iterator(cache)) names.push_back(e.path().filename());
        ASSERT_EQ(names.size(), 1u) << "one entry, no temporaries (round " << round << ")";
        EXPECT_EQ(w.checkFinal(), "");
    }
    EXPECT_TRUE(bothFitted) << "in no round did both processes fit at once";
}

TEST(Kills, StaleTemporariesOfDeadProcessesOnlyAreRemoved) {
    TempDir dir;
    // A pid that no longer runs: a child that has exited and been waited for.
    const pid_t dead = start({"/bin/true"});
    ASSERT_GT(dead, 0);
    waitFor(dead);
    const std::string deadSuffix = std::to_string(dead), liveSuffix = std::to_string(getppid());
    for (const std::string& name : std::vector<std::string>{
             "a.btfmat.tmp" + deadSuffix, "a.btfmat.tmp" + liveSuffix, "a.btfmat.old" + deadSuffix,
             "b.btfmat.tmp" + deadSuffix, "a.btfmat", "a.btfmat.tmpx", "a.btfmattmp" + deadSuffix})
        writeTextFile(dir.file(name), "x");
    fs::create_directory(dir.file("a.btfmat.tmp" + deadSuffix + "0"));  // a folder, pid unknown
    const std::size_t removed = removeStaleTemporaries(
        dir.path().string(), [](const std::string& stem) { return stem == "a.btfmat"; });
    std::set<std::string> left;
    for (const auto& e : fs::directory_iterator(dir.path())) left.insert(e.path().filename());
    const std::set<std::string> expected{"a.btfmat.tmp" + liveSuffix, "b.btfmat.tmp" + deadSuffix,
                                         "a.btfmat", "a.btfmat.tmpx", "a.btfmattmp" + deadSuffix};
    // The folder named with pid*10: removed only if that pid happens not to run either.
    const bool folderLeft = left.erase("a.btfmat.tmp" + deadSuffix + "0") == 1;
    EXPECT_EQ(left, expected);
    EXPECT_EQ(removed, folderLeft ? 2u : 3u);
}

}  // namespace OSGBTF_TEST_FILE
