// osgBTF tests: a stock nginx serving a folder on a free port of 127.0.0.1, for the HTTP tests of
// BSVTF streaming (tests/streaming_fetch_test.cpp, tests/streaming_http_test.cpp). It runs as a
// child of the test with its own configuration, logs and temp folders in a scratch folder: no
// system service or system configuration is touched.
//
// Besides the files under root(), the server answers (for the failure cases):
//   /broken/...   HTTP 500
//   /loop/...     302 to /loop/ (a redirect loop)
//   /stall/...    a request proxied to a socket that accepts connections and never answers, so
//                 the transfer stalls (nginx's proxy_read_timeout is 60 s)
// and whatever the test adds before start() (answer(), stall(), addConfig()).
//
// Tests skip when nginx is not installed (a developer machine; CI installs it):
//   if (NginxServer::executable().empty()) GTEST_SKIP() << "nginx is not installed";
#pragma once

#include <sys/types.h>

#include <string>

#include "tests/TestUtil.h"

namespace osgBTF::test {

/** A TCP port of 127.0.0.1 nobody listens on (bound, then released: another process could take
 *  it meanwhile, but the kernel hands out ephemeral ports in turn, so not soon); 0 on failure. */
int freeLocalPort();

class NginxServer {
public:
    /** /usr/sbin/nginx or the first nginx on PATH; empty when none is installed. */
    static std::string executable();

    /** A server for the folder `root` (created if missing); an empty `root` serves the folder
     *  root() inside the server's scratch folder. Nothing runs before start(). */
    explicit NginxServer(std::string root = {});
    /** Stops nginx (stop()). */
    ~NginxServer();
    NginxServer(const NginxServer&) = delete;
    NginxServer& operator=(const NginxServer&) = delete;

    /** Lines for nginx's server block (before start()), e.g. "location = /a { return 404; }". */
    void addConfig(const std::string& lines);
    /** GET `path` (exactly, e.g. "/set/tiles/0/3/2_1.tile") is answered with `status` (and, for a
     *  3xx status, `target` as the location). Before start(). */
    void answer(const std::string& path, int status, const std::string& target = {});
    /** GET `path` (exactly) stalls: connected, no byte ever comes. Before start(). */
    void stall(const std::string& path);

    /** Starts nginx on a free port (another one is tried, up to 3, when the port was taken
     *  meanwhile) and waits until it accepts connections. Returns "" when it runs, else the
     *  problem (nginx's output when it exited, or that it did not listen within 5 s, in which
     *  case it is killed). Needs executable(). Also sets no_proxy for 127.0.0.1, so that libcurl
     *  does not send the tests' requests to a proxy from the environment. On Linux nginx is
     *  killed when the thread that started it ends (a crashed test leaves no server behind). */
    std::string start();
    /** Starts nginx again after stop(), on the port it had (a server that comes back after a
     *  crash or a restart). Returns "" when it runs, else the problem. */
    std::string restart();
    /** Kills nginx (SIGKILL: open connections are reset at once, as when a server crashes or a
     *  network drops) and waits for it. Nothing when it is not running. */
    void stop();
    bool running() const { return _pid > 0; }

    int port() const { return _port; }
    /** "http://127.0.0.1:PORT" followed by `path` (which starts with '/', or is empty). */
    std::string url(const std::string& path = {}) const;
    /** The folder served. */
    const std::string& root() const { return _root; }
    /** nginx's access log so far: one line per request ("... \"GET /set/index.bsvtf HTTP/1.1\"
     *  200 ..."), e.g. to count the requests of a URL. */
    std::string accessLog() const;
    /** How many requests for `path` (e.g. "/set/index.bsvtf") the access log holds. */
    int requestCount(const std::string& path) const;

private:
    std::string config(int port) const;
    /** Starts the process; true once it accepts connections, false with its output in `log`
     *  when it exited, or with the problem in `log` and `failed` set when it cannot start. */
    bool launch(std::string& log, bool& failed);

    TempDir _dir;
    std::string _root;
    std::string _extraConfig;
    pid_t _pid = -1;
    int _port = 0;
    int _blackhole = -1, _blackholePort = 0;
};

}  // namespace osgBTF::test
