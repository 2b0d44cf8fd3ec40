// BSVTF streaming (streaming/TileFetcher.h): the folder and HTTP sources and the background
// fetcher, against a stock nginx started by the fixture on a free local port with its own
// configuration (tests/NginxServer.h; no system service is touched). Failure cases first, with
// their exact messages. Without nginx (a developer machine) the HTTP tests are skipped; CI
// installs it.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <thread>

#include <osg/ref_ptr>  // before NotifyCapture.h, which uses it

#include "streaming/TileFetcher.h"
#include "tests/NginxServer.h"
#include "tests/NotifyCapture.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::NginxServer;
using osgBTF::test::ScopedNotifyCapture;
using osgBTF::test::TempDir;
using Clock = std::chrono::steady_clock;

namespace {

double secondsSince(Clock::time_point start) {
    return std::chrono::duration<double>(Clock::now() - start).count();
}

std::vector<std::uint8_t> randomBytes(std::size_t size, unsigned seed) {
    std::mt19937 random(seed);
    std::vector<std::uint8_t> bytes(size);
    for (std::uint8_t& b : bytes) b = std::uint8_t(random());
    return bytes;
}

void writeBytes(const std::filesystem::path& path, const std::vector<std::uint8_t>& bytes) {
    std::filesystem::create_directories(path.parent_path());
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    ASSERT_TRUE(out.good()) << path;
}

// ---------------------------------------------------------------------------------------------
// Local folders

TEST(FolderTileSource, ReportsAMissingFileAndAFolder) {
    TempDir dir;
    std::filesystem::create_directories(dir.path() / "tiles");
    FolderTileSource source(dir.path().string());
    FetchResult missing = source.fetch("tiles/0/0/9_9.tile");
    EXPECT_FALSE(missing.ok);
    EXPECT_TRUE(missing.data.empty());
    EXPECT_EQ(missing.error,
              dir.file("tiles/0/0/9_9.tile") + ": cannot open: No such file or directory");
    EXPECT_EQ(source.fetch("tiles").error, dir.file("tiles") + ": cannot open: Is a directory");
}

TEST(FolderTileSource, ReadsTheBytes) {
    TempDir dir;
    const auto bytes = randomBytes(200000, 1);
    writeBytes(dir.path() / "tiles/0/1/1_0.tile", bytes);
    writeBytes(dir.path() / "empty", {});
    FolderTileSource source(dir.path().string());
    EXPECT_EQ(source.describe("tiles/0/1/1_0.tile"), dir.file("tiles/0/1/1_0.tile"));
    FetchResult result = source.fetch("tiles/0/1/1_0.tile");
    EXPECT_TRUE(result.ok) << result.error;
    EXPECT_EQ(result.error, "");
    EXPECT_EQ(result.data, bytes);
    FetchResult empty = source.fetch("empty");
    EXPECT_TRUE(empty.ok) << empty.error;
    EXPECT_TRUE(empty.data.empty());
}

TEST(OpenTileSource, ChoosesHttpByTheSchemeAndAFolderOtherwise) {
    EXPECT_NE(dynamic_cast<HttpTileSource*>(openTileSource("http://example.org/a").get()), nullptr);
    EXPECT_NE(dynamic_cast<HttpTileSource*>(openTileSource("HTTPS://example.org/a").get()),
              nullptr);
    EXPECT_NE(dynamic_cast<FolderTileSource*>(openTileSource("/data/http://x").get()), nullptr);
    EXPECT_NE(dynamic_cast<FolderTileSource*>(openTileSource("httpdata").get()), nullptr);
    EXPECT_EQ(openTileSource("http://example.org/a/")->describe("tiles/0/0/0_0.tile"),
              "http://example.org/a/tiles/0/0/0_0.tile");
    EXPECT_EQ(openTileSource("http://h")->describe("/a b/c%d.tile"), "http://h/a%20b/c%25d.tile");
    EXPECT_EQ(openTileSource("data/wool")->describe("index.bsvtf"), "data/wool/index.bsvtf");
}

TEST(HttpTileSource, ReportsARefusedConnection) {
    const int port = osgBTF::test::freeLocalPort();
    ASSERT_NE(port, 0);
    const std::string base = "http://127.0.0.1:" + std::to_string(port) + "/x";
    HttpTileSource source(base);
    FetchResult result = source.fetch("tiles/0/0/0_0.tile");
    EXPECT_FALSE(result.ok);
    EXPECT_EQ(result.error, base + "/tiles/0/0/0_0.tile: connection refused");
}

TEST(TileFetcher, DeliversEveryFileOfAFolderWithAPool) {
    TempDir dir;
    std::map<std::string, std::vector<std::uint8_t>> files;
    for (int i = 0; i < 40; ++i) {
        const std::string path = "tiles/0/2/" + std::to_string(i) + "_0.tile";
        files[path] = randomBytes(1000 + std::size_t(i) * 37, unsigned(i));
        writeBytes(dir.path() / path, files[path]);
    }
    std::uint64_t total = 0;
    for (const auto& file : files) total += file.second.size();

    TileFetcher fetcher(std::make_shared<FolderTileSource>(dir.path().string()),
                        TileFetcherOptions{3, false});
    std::uint64_t key = 0;
    for (const auto& file : files) {
        fetcher.request(key, file.first, double(key % 7));
        ++key;
    }
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(5)));
    std::vector<FetchedItem> items = fetcher.takeCompleted();
    ASSERT_EQ(items.size(), files.size());
    for (const FetchedItem& item : items) {
        EXPECT_TRUE(item.result.ok) << item.result.error;
        EXPECT_EQ(item.result.data, files[item.path]) << item.path;
    }
    EXPECT_EQ(fetcher.bytesReceived(), total);
    EXPECT_EQ(fetcher.pending(), 0u);
    EXPECT_EQ(fetcher.inFlight(), 0u);
    EXPECT_TRUE(fetcher.takeCompleted().empty());
}

// ---------------------------------------------------------------------------------------------
// A stock nginx on a free local port

class NginxTileServer : public ::testing::Test {
protected:
    void SetUp() override {
        if (NginxServer::executable().empty())
            GTEST_SKIP() << "nginx is not installed (CI installs it)";
        const std::filesystem::path www = _server.root();
        tile = randomBytes(100000, 7);
        writeBytes(www / "set/tiles/0/0/0_0.tile", tile);
        writeBytes(www / "set/big.half", randomBytes(10000, 8));
        for (int i = 0; i < kFiles; ++i)
            writeBytes(www / ("set/f/" + std::to_string(i)), fileBytes(i));
        _server.answer("/moved.tile", 301, "/set/tiles/0/0/0_0.tile");
        const std::string problem = _server.start();
        ASSERT_EQ(problem, "");
    }

    void stopServer() { _server.stop(); }
    std::string restartServer() { return _server.restart(); }
    int requestCount(const std::string& path) const { return _server.requestCount(path); }

    /** The tile set's URL. */
    std::string base() const { return _server.url("/set"); }
    std::string root() const { return _server.url(); }
    static std::vector<std::uint8_t> fileBytes(int i) {
        return randomBytes(500 + std::size_t(i) * 11, unsigned(100 + i));
    }

    static constexpr int kFiles = 24;
    std::vector<std::uint8_t> tile;

private:
    NginxServer _server;  // its own scratch folder: root(), configuration, logs
};

TEST_F(NginxTileServer, ReportsMissingFilesServerErrorsAndRedirectLoops) {
    HttpTileSource source(base());
    FetchResult missing = source.fetch("tiles/0/0/5_5.tile");
    EXPECT_FALSE(missing.ok);
    EXPECT_TRUE(missing.data.empty());
    EXPECT_EQ(missing.error, base() + "/tiles/0/0/5_5.tile: HTTP 404");
    EXPECT_FALSE(missing.transient);  // the same request gets the same answer

    HttpTileSource server(root());
    const FetchResult broken = server.fetch("broken/x.tile");
    EXPECT_EQ(broken.error, root() + "/broken/x.tile: HTTP 500");
    EXPECT_TRUE(broken.transient);  // the server's state: worth another try
    const FetchResult loop = server.fetch("loop/x");
    EXPECT_EQ(loop.error, root() + "/loop/x: more than 3 redirects");
    EXPECT_FALSE(loop.transient);
}

TEST_F(NginxTileServer, RefusesAResponseLargerThanTheLimit) {
    HttpOptions options;
    options.maxBytes = 1000;
    HttpTileSource source(base(), options);
    FetchResult result = source.fetch("big.half");
    EXPECT_FALSE(result.ok);
    EXPECT_TRUE(result.data.empty());
    EXPECT_EQ(result.error, base() + "/big.half: response larger than 1000 bytes");
    options.maxBytes = 10000;  // exactly the size: fine
    EXPECT_TRUE(HttpTileSource(base(), options).fetch("big.half").ok);
}

TEST_F(NginxTileServer, TimesOutAStalledTransfer) {
    HttpOptions options;
    options.stallSeconds = 1;
    HttpTileSource source(root(), options);
    const auto start = Clock::now();
    FetchResult result = source.fetch("stall/x.tile");
    const double seconds = secondsSince(start);
    EXPECT_FALSE(result.ok);
    EXPECT_EQ(result.error, root() + "/stall/x.tile: timed out (no data for 1 s)");
    EXPECT_TRUE(result.transient);
    EXPECT_GE(seconds, 0.9);
    EXPECT_LT(seconds, 3.0);
}

TEST_F(NginxTileServer, ReportsAStoppedServer) {
    HttpTileSource source(base());
    ASSERT_TRUE(source.fetch("tiles/0/0/0_0.tile").ok);  // a kept-alive connection, then
    stopServer();
    FetchResult result = source.fetch("tiles/0/0/0_0.tile");
    EXPECT_FALSE(result.ok);
    EXPECT_EQ(result.error, base() + "/tiles/0/0/0_0.tile: connection refused");
    EXPECT_TRUE(result.transient);

    // Tried 5 times (delays 20, 40, 80, 160 ms), then failed with one warning.
    TileFetcherOptions options;
    options.retryDelay = std::chrono::milliseconds(20);
    TileFetcher fetcher(std::make_shared<HttpTileSource>(base()), options);
    ScopedNotifyCapture capture;
    fetcher.request(1, "f/0", 1.0);
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(10)));
    std::vector<FetchedItem> items = fetcher.takeCompleted();
    ASSERT_EQ(items.size(), 1u);
    EXPECT_EQ(items[0].result.error, base() + "/f/0: connection refused (5 tries)");
    EXPECT_EQ(capture.text(), "osgBTF: " + base() + "/f/0: connection refused (5 tries)\n");
    EXPECT_EQ(fetcher.retries(), 4u);

    TileFetcherOptions once;
    once.tries = 1;
    TileFetcher impatient(std::make_shared<HttpTileSource>(base()), once);
    impatient.request(1, "f/0", 1.0);
    ASSERT_TRUE(impatient.waitIdle(std::chrono::seconds(5)));
    items = impatient.takeCompleted();
    ASSERT_EQ(items.size(), 1u);
    EXPECT_EQ(items[0].result.error, base() + "/f/0: connection refused");
    EXPECT_EQ(impatient.retries(), 0u);
}

// A server that dies and comes back on its port within the retry delays: the files requested
// meanwhile arrive, with no warning, each fetched once from the server that came back.
TEST_F(NginxTileServer, FetcherUsesAServerThatComesBack) {
    ASSERT_TRUE(HttpTileSource(base()).fetch("f/1").ok);
    stopServer();
    TileFetcherOptions options;
    options.threads = 2;
    options.retryDelay = std::chrono::milliseconds(200);  // tries at 0, 0.2, 0.6, 1.4, 3.0 s
    ScopedNotifyCapture capture;
    TileFetcher fetcher(std::make_shared<HttpTileSource>(base()), options);
    for (int i = 0; i < 4; ++i) fetcher.request(std::uint64_t(i), "f/" + std::to_string(i), i);
    // Refused at least once each before the server is back.
    const auto start = Clock::now();
    while (fetcher.retries() < 4 && secondsSince(start) < 5)
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    ASSERT_GE(fetcher.retries(), 4u);
    EXPECT_EQ(fetcher.pending(), 4u);  // waiting for their next try
    const int before = requestCount("/set/f/0");
    ASSERT_EQ(restartServer(), "");
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(10)));
    const std::vector<FetchedItem> items = fetcher.takeCompleted();
    ASSERT_EQ(items.size(), 4u);
    for (const FetchedItem& item : items) {
        EXPECT_TRUE(item.result.ok) << item.result.error;
        EXPECT_EQ(item.result.data, fileBytes(int(item.key)));
    }
    EXPECT_EQ(requestCount("/set/f/0") - before, 1);
    EXPECT_EQ(capture.text(), "");
}

TEST_F(NginxTileServer, FetchesTheBytesAndFollowsARedirect) {
    HttpTileSource source(base());
    EXPECT_EQ(source.describe("tiles/0/0/0_0.tile"), base() + "/tiles/0/0/0_0.tile");
    FetchResult result = source.fetch("tiles/0/0/0_0.tile");
    EXPECT_TRUE(result.ok) << result.error;
    EXPECT_EQ(result.error, "");
    EXPECT_EQ(result.data, tile);
    FetchResult moved = HttpTileSource(root()).fetch("moved.tile");
    EXPECT_TRUE(moved.ok) << moved.error;
    EXPECT_EQ(moved.data, tile);
    FetchResult viaOpen = openTileSource(base() + "/")->fetch("f/3");
    EXPECT_TRUE(viaOpen.ok) << viaOpen.error;
    EXPECT_EQ(viaOpen.data, fileBytes(3));
}

// Order is testable with one thread: every request is queued while the fetcher is paused, so the
// worker sees the whole queue when it starts.
TEST_F(NginxTileServer, FetcherDeliversInPriorityOrder) {
    TileFetcher fetcher(std::make_shared<HttpTileSource>(base()), TileFetcherOptions{1, true});
    std::vector<double> priority(kFiles);
    std::mt19937 random(3);
    for (int i = 0; i < kFiles; ++i) priority[std::size_t(i)] = double(random() % 1000);
    priority[5] = priority[6];  // a tie: first requested first
    for (int i = 0; i < kFiles; ++i)
        fetcher.request(std::uint64_t(i), "f/" + std::to_string(i), priority[std::size_t(i)]);
    fetcher.request(7, "f/7", 5000.0);  // pending: re-prioritised to first
    priority[7] = 5000.0;
    fetcher.request(8, "f/8", std::nan(""));  // NaN: last
    priority[8] = -1.0;
    fetcher.cancel(9);
    fetcher.request(100, "missing", 1.5);  // a failure is delivered in its turn
    EXPECT_EQ(fetcher.pending(), std::size_t(kFiles));
    EXPECT_EQ(fetcher.inFlight(), 0u);
    EXPECT_TRUE(fetcher.takeCompleted().empty());

    std::vector<std::uint64_t> expected;
    for (int i = 0; i < kFiles; ++i)
        if (i != 9) expected.push_back(std::uint64_t(i));
    expected.push_back(100);
    priority.push_back(1.5);
    auto priorityOf = [&](std::uint64_t key) {
        return priority[std::min<std::size_t>(key, kFiles)];
    };
    std::stable_sort(expected.begin(), expected.end(), [&](std::uint64_t a, std::uint64_t b) {
        return priorityOf(a) > priorityOf(b);
    });

    ScopedNotifyCapture capture;
    fetcher.setPaused(false);
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(5)));
    std::vector<FetchedItem> items = fetcher.takeCompleted();
    std::vector<std::uint64_t> order;
    std::uint64_t total = 0;
    for (const FetchedItem& item : items) {
        order.push_back(item.key);
        if (item.key == 100) {
            EXPECT_FALSE(item.result.ok);
            EXPECT_EQ(item.path, "missing");
            EXPECT_EQ(item.result.error, base() + "/missing: HTTP 404");
            continue;
        }
        EXPECT_EQ(item.path, "f/" + std::to_string(item.key));
        EXPECT_TRUE(item.result.ok) << item.result.error;
        EXPECT_EQ(item.result.data, fileBytes(int(item.key)));
        total += item.result.data.size();
    }
    EXPECT_EQ(order, expected);
    EXPECT_EQ(fetcher.bytesReceived(), total);
    EXPECT_EQ(capture.text(), "osgBTF: " + base() + "/missing: HTTP 404\n");

    // Delivered keys are not fetched again until forgotten.
    fetcher.request(3, "f/3", 1.0);
    fetcher.request(100, "missing", 1.0);
    EXPECT_EQ(fetcher.pending(), 0u);
    fetcher.forget(3);
    fetcher.request(3, "f/3", 1.0);
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(5)));
    items = fetcher.takeCompleted();
    ASSERT_EQ(items.size(), 1u);
    EXPECT_EQ(items[0].key, 3u);
    EXPECT_EQ(items[0].result.data, fileBytes(3));
}

TEST_F(NginxTileServer, FetcherReportsEachFailureOnce) {
    ScopedNotifyCapture capture;
    TileFetcherOptions options{2, false};
    options.retryDelay = std::chrono::milliseconds(10);  // HTTP 500 is tried 5 times
    TileFetcher fetcher(std::make_shared<HttpTileSource>(root()), options);
    fetcher.request(1, "set/missing.tile", 1.0);
    fetcher.request(2, "set/missing.tile", 1.0);  // another key, the same URL
    fetcher.request(3, "broken/a", 1.0);
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(5)));
    EXPECT_EQ(fetcher.takeCompleted().size(), 3u);
    // Not retried by itself; retried, and not reported again, after forget().
    fetcher.request(1, "set/missing.tile", 1.0);
    EXPECT_EQ(fetcher.pending(), 0u);
    fetcher.forget(1);
    fetcher.forget(3);
    fetcher.request(1, "set/missing.tile", 1.0);
    fetcher.request(3, "broken/a", 1.0);
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(5)));
    std::vector<FetchedItem> again = fetcher.takeCompleted();
    ASSERT_EQ(again.size(), 2u);
    for (const FetchedItem& item : again) EXPECT_FALSE(item.result.ok);

    std::string text = capture.text();
    const std::string missing = "osgBTF: " + root() + "/set/missing.tile: HTTP 404\n";
    const std::string broken = "osgBTF: " + root() + "/broken/a: HTTP 500 (5 tries)\n";
    // Two workers: the two messages may come in either order.
    EXPECT_TRUE(text == missing + broken || text == broken + missing) << text;
    EXPECT_EQ(fetcher.bytesReceived(), 0u);
}

TEST_F(NginxTileServer, FetcherPoolDeliversEveryFileOnce) {
    TileFetcher fetcher(std::make_shared<HttpTileSource>(base()), TileFetcherOptions{4, false});
    for (int round = 0; round < 3; ++round)  // repeated requests are no-ops or updates
        for (int i = 0; i < kFiles; ++i)
            fetcher.request(std::uint64_t(i), "f/" + std::to_string(i), double(i + round));
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(5)));
    std::vector<FetchedItem> items = fetcher.takeCompleted();
    ASSERT_EQ(items.size(), std::size_t(kFiles));
    std::vector<bool> seen(kFiles, false);
    for (const FetchedItem& item : items) {
        ASSERT_LT(item.key, std::uint64_t(kFiles));
        EXPECT_FALSE(seen[item.key]) << item.key;
        seen[item.key] = true;
        EXPECT_EQ(item.result.data, fileBytes(int(item.key))) << item.result.error;
    }
}

TEST_F(NginxTileServer, FetcherDestructorReturnsPromptlyDuringAStalledTransfer) {
    ScopedNotifyCapture capture;
    Clock::time_point start;
    {
        TileFetcher fetcher(std::make_shared<HttpTileSource>(root()));  // stalls after 5 s
        fetcher.request(1, "stall/a.tile", 2.0);
        fetcher.request(2, "stall/b.tile", 1.0);
        const auto waitStart = Clock::now();
        while (fetcher.inFlight() == 0 && secondsSince(waitStart) < 2)
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        ASSERT_EQ(fetcher.inFlight(), 1u);
        EXPECT_EQ(fetcher.pending(), 1u);
        EXPECT_FALSE(fetcher.waitIdle(std::chrono::milliseconds(300)));  // connected, waiting
        EXPECT_TRUE(fetcher.takeCompleted().empty());
        start = Clock::now();
    }
    EXPECT_LT(secondsSince(start), 2.0);
    EXPECT_EQ(capture.text(), "");  // an aborted transfer is neither delivered nor reported
}

}  // namespace

}  // namespace OSGBTF_TEST_FILE
