// BSVTF streaming (streaming/TileFetcher.h): the folder and HTTP sources and the background
// fetcher, against a stock nginx started by the fixture on a free local port with its own
// configuration (no system service is touched). Failure cases first, with their exact messages.
// Without nginx (a developer machine) the HTTP tests are skipped; CI installs it.
#include <gtest/gtest.h>

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <spawn.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>
#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <map>
#include <random>
#include <thread>

#include <osg/ref_ptr>  // before NotifyCapture.h, which uses it

#include "streaming/TileFetcher.h"
#include "tests/NotifyCapture.h"
#include "tests/TestUtil.h"

extern char** environ;

using namespace osgBTF;
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

/** A TCP socket on 127.0.0.1 bound to a free port. */
int boundSocket(int& port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return -1;
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address.sin_port = 0;
    socklen_t length = sizeof address;
    if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) != 0 ||
        ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) {
        ::close(fd);
        return -1;
    }
    port = ntohs(address.sin_port);
    return fd;
}

/** A port nobody listens on (bound, then released: another process could take it meanwhile, but
 *  the kernel hands out ephemeral ports in turn, so not soon). */
int freePort() {
    int port = 0;
    const int fd = boundSocket(port);
    if (fd >= 0) ::close(fd);
    return port;
}

bool acceptsConnections(int port) {
    const int fd = ::socket(AF_INET, SOCK_STREAM | SOCK_CLOEXEC, 0);
    if (fd < 0) return false;
    sockaddr_in address{};
    address.sin_family = AF_INET;
    address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
    address.sin_port = htons(std::uint16_t(port));
    const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
    ::close(fd);
    return ok;
}

std::string findNginx() {
    std::vector<std::string> candidates{"/usr/sbin/nginx"};
    if (const char* path = std::getenv("PATH")) {
        std::string list = path;
        std::size_t start = 0;
        while (start <= list.size()) {
            const std::size_t end = std::min(list.find(':', start), list.size());
            if (end > start) candidates.push_back(list.substr(start, end - start) + "/nginx");
            start = end + 1;
        }
    }
    for (const std::string& candidate : candidates)
        if (::access(candidate.c_str(), X_OK) == 0) return candidate;
    return {};
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
    const int port = freePort();
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
        const std::string nginx = findNginx();
        if (nginx.empty()) GTEST_SKIP() << "nginx is not installed (CI installs it)";
        // Requests to the local server must not go to a proxy from the environment.
        ::setenv("no_proxy", "127.0.0.1", 1);
        ::setenv("NO_PROXY", "127.0.0.1", 1);

        tile = randomBytes(100000, 7);
        writeBytes(_dir.path() / "www/set/tiles/0/0/0_0.tile", tile);
        writeBytes(_dir.path() / "www/set/big.half", randomBytes(10000, 8));
        for (int i = 0; i < kFiles; ++i)
            writeBytes(_dir.path() / ("www/set/f/" + std::to_string(i)), fileBytes(i));

        // The stalled upstream: connections complete in the kernel's backlog, nothing answers.
        int blackholePort = 0;
        _blackhole = boundSocket(blackholePort);
        ASSERT_GE(_blackhole, 0);
        ASSERT_EQ(::listen(_blackhole, 64), 0);

        const std::string version =
            osgBTF::test::runCommand(osgBTF::test::shellQuote(nginx) + " -V").output;
        std::string temp;
        for (const char* module : {"client_body", "proxy", "fastcgi", "uwsgi", "scgi"}) {
            const std::string name = module;
            if (name != "client_body" && name != "proxy" &&
                version.find("--without-http_" + name + "_module") != std::string::npos)
                continue;
            std::filesystem::create_directories(_dir.path() / "temp" / name);
            temp += "    " + name + "_temp_path " + _dir.file("temp/" + name) + ";\n";
        }
        // The free port may be taken by another process (ctest -j) before nginx binds it: then
        // nginx exits at once, and another port is tried.
        std::string log;
        for (int attempt = 0; attempt < 3; ++attempt) {
            _port = freePort();
            ASSERT_NE(_port, 0);
            osgBTF::test::writeTextFile(_dir.file("nginx.conf"),
                                        config(_port, blackholePort, temp));
            if (start(nginx, log) || HasFailure()) return;
        }
        FAIL() << "nginx exited:\n" << log;
    }

    std::string config(int port, int blackholePort, const std::string& temp) const {
        return std::string(::geteuid() == 0 ? "user root;\n" : "") +  // else nginx warns
               "daemon off;\n"
               "master_process off;\n"
               "worker_processes 1;\n"
               "pid " +
               _dir.file("nginx.pid") + ";\nerror_log " + _dir.file("error.log") +
               ";\n"
               "events { worker_connections 64; }\n"
               "http {\n"
               "    access_log " +
               _dir.file("access.log") + ";\n" + temp +
               "    default_type application/octet-stream;\n"
               "    server {\n"
               "        listen 127.0.0.1:" +
               std::to_string(port) + ";\n        root " + _dir.file("www") +
               ";\n"
               "        location /broken/ { return 500; }\n"
               "        location /loop/ { return 302 /loop/; }\n"
               "        location = /moved.tile { return 301 /set/tiles/0/0/0_0.tile; }\n"
               "        location /stall/ {\n"
               "            proxy_pass http://127.0.0.1:" +
               std::to_string(blackholePort) +
               ";\n"
               "            proxy_read_timeout 60s;\n"
               "        }\n"
               "    }\n"
               "}\n";
    }

    /** Starts nginx as a child process; true once it accepts connections, false (with its
     *  output in `log`) when it exited. Fails the test when it does neither within 5 s. */
    bool start(const std::string& nginx, std::string& log) {
        const std::vector<std::string> args{nginx,
                                            "-p",
                                            _dir.path().string() + "/",
                                            "-c",
                                            _dir.file("nginx.conf"),
                                            "-e",
                                            _dir.file("error.log")};
        std::vector<char*> argv;
        for (const std::string& arg : args) argv.push_back(const_cast<char*>(arg.c_str()));
        argv.push_back(nullptr);
        const std::string outPath = _dir.file("nginx.out");
        posix_spawn_file_actions_t actions;
        posix_spawn_file_actions_init(&actions);
        posix_spawn_file_actions_addopen(&actions, 1, outPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC,
                                         0644);
        posix_spawn_file_actions_adddup2(&actions, 1, 2);
        const int spawned =
            posix_spawn(&_pid, nginx.c_str(), &actions, nullptr, argv.data(), environ);
        posix_spawn_file_actions_destroy(&actions);
        if (spawned != 0) {
            _pid = -1;
            ADD_FAILURE() << "cannot start " << nginx << ": " << std::strerror(spawned);
            return false;
        }
        const auto begin = Clock::now();
        while (!acceptsConnections(_port)) {
            int status = 0;
            if (::waitpid(_pid, &status, WNOHANG) == _pid) {
                _pid = -1;
                log = readIfExists(outPath) + readIfExists(_dir.file("error.log"));
                return false;
            }
            if (secondsSince(begin) > 5) {
                ADD_FAILURE() << "nginx does not accept connections in 5 s";
                return false;
            }
            std::this_thread::sleep_for(std::chrono::milliseconds(5));
        }
        return true;
    }

    void TearDown() override {
        stopServer();
        if (_blackhole >= 0) ::close(_blackhole);
    }

    void stopServer() {
        if (_pid <= 0) return;
        ::kill(_pid, SIGKILL);
        int status = 0;
        ::waitpid(_pid, &status, 0);
        _pid = -1;
    }

    static std::string readIfExists(const std::string& path) {
        std::ifstream in(path);
        return std::string(std::istreambuf_iterator<char>(in), {});
    }

    /** The tile set's URL. */
    std::string base() const { return "http://127.0.0.1:" + std::to_string(_port) + "/set"; }
    std::string root() const { return "http://127.0.0.1:" + std::to_string(_port); }
    static std::vector<std::uint8_t> fileBytes(int i) {
        return randomBytes(500 + std::size_t(i) * 11, unsigned(100 + i));
    }

    static constexpr int kFiles = 24;
    std::vector<std::uint8_t> tile;

private:
    TempDir _dir;
    pid_t _pid = -1;
    int _port = 0;
    int _blackhole = -1;
};

TEST_F(NginxTileServer, ReportsMissingFilesServerErrorsAndRedirectLoops) {
    HttpTileSource source(base());
    FetchResult missing = source.fetch("tiles/0/0/5_5.tile");
    EXPECT_FALSE(missing.ok);
    EXPECT_TRUE(missing.data.empty());
    EXPECT_EQ(missing.error, base() + "/tiles/0/0/5_5.tile: HTTP 404");

    HttpTileSource server(root());
    EXPECT_EQ(server.fetch("broken/x.tile").error, root() + "/broken/x.tile: HTTP 500");
    EXPECT_EQ(server.fetch("loop/x").error, root() + "/loop/x: more than 3 redirects");
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

    TileFetcher fetcher(std::make_shared<HttpTileSource>(base()));
    ScopedNotifyCapture capture;
    fetcher.request(1, "f/0", 1.0);
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(5)));
    std::vector<FetchedItem> items = fetcher.takeCompleted();
    ASSERT_EQ(items.size(), 1u);
    EXPECT_EQ(items[0].result.error, base() + "/f/0: connection refused");
    EXPECT_EQ(capture.text(), "osgBTF: " + base() + "/f/0: connection refused\n");
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
    TileFetcher fetcher(std::make_shared<HttpTileSource>(root()), TileFetcherOptions{2, false});
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
    const std::string broken = "osgBTF: " + root() + "/broken/a: HTTP 500\n";
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
