#include "tests/NginxServer.h"

#include <arpa/inet.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <signal.h>
#include <sys/socket.h>
#include <sys/wait.h>
#include <unistd.h>
#ifdef __linux__
#include <sys/prctl.h>
#endif

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <thread>
#include <vector>

extern char** environ;

namespace osgBTF::test {

namespace {

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

std::string readIfExists(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    return std::string(std::istreambuf_iterator<char>(in), {});
}

/** A path as an nginx configuration string (the scratch folders have no quotes or '$'). */
std::string quoted(const std::string& text) {
    return "\"" + text + "\"";
}

}  // namespace

int freeLocalPort() {
    int port = 0;
    const int fd = boundSocket(port);
    if (fd < 0) return 0;
    ::close(fd);
    return port;
}

std::string NginxServer::executable() {
    std::vector<std::string> candidates{"/usr/sbin/nginx"};
    if (const char* path = std::getenv("PATH")) {
        const std::string list = path;
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

NginxServer::NginxServer(std::string root)
    : _root(root.empty() ? _dir.file("www") : std::move(root)) {
    std::error_code ignored;
    std::filesystem::create_directories(_root, ignored);
    // The stalled upstream: connections complete in the kernel's backlog, nothing answers.
    _blackhole = boundSocket(_blackholePort);
    if (_blackhole >= 0 && ::listen(_blackhole, 64) != 0) {
        ::close(_blackhole);
        _blackhole = -1;
    }
}

NginxServer::~NginxServer() {
    stop();
    if (_blackhole >= 0) ::close(_blackhole);
}

void NginxServer::addConfig(const std::string& lines) {
    _extraConfig += "        " + lines + "\n";
}

void NginxServer::answer(const std::string& path, int status, const std::string& target) {
    addConfig("location = " + path + " { return " + std::to_string(status) +
              (target.empty() ? "" : " " + target) + "; }");
}

void NginxServer::stall(const std::string& path) {
    addConfig("location = " + path + " { proxy_pass http://127.0.0.1:" +
              std::to_string(_blackholePort) + "; proxy_read_timeout 60s; }");
}

std::string NginxServer::url(const std::string& path) const {
    return "http://127.0.0.1:" + std::to_string(_port) + path;
}

std::string NginxServer::accessLog() const {
    return readIfExists(_dir.file("access.log"));
}

int NginxServer::requestCount(const std::string& path) const {
    const std::string log = accessLog(), needle = "\"GET " + path + " HTTP/";
    int count = 0;
    for (std::size_t at = log.find(needle); at != std::string::npos;
         at = log.find(needle, at + needle.size()))
        ++count;
    return count;
}

std::string NginxServer::config(int port) const {
    const std::string nginx = executable();
    const std::string version = runCommand(shellQuote(nginx) + " -V").output;
    std::string temp;
    for (const char* module : {"client_body", "proxy", "fastcgi", "uwsgi", "scgi"}) {
        const std::string name = module;
        if (name != "client_body" && name != "proxy" &&
            version.find("--without-http_" + name + "_module") != std::string::npos)
            continue;
        std::filesystem::create_directories(_dir.path() / "temp" / name);
        temp += "    " + name + "_temp_path " + quoted(_dir.file("temp/" + name)) + ";\n";
    }
    return std::string(::geteuid() == 0 ? "user root;\n" : "") +  // else nginx warns
           "daemon off;\n"
           "master_process off;\n"
           "worker_processes 1;\n"
           "pid " +
           quoted(_dir.file("nginx.pid")) + ";\nerror_log " + quoted(_dir.file("error.log")) +
           ";\n"
           "events { worker_connections 64; }\n"
           "http {\n"
           "    access_log " +
           quoted(_dir.file("access.log")) + ";\n" + temp +
           "    default_type application/octet-stream;\n"
           "    server {\n"
           "        listen 127.0.0.1:" +
           std::to_string(port) + ";\n        root " + quoted(_root) +
           ";\n"
           "        location /broken/ { return 500; }\n"
           "        location /loop/ { return 302 /loop/; }\n"
           "        location /stall/ {\n"
           "            proxy_pass http://127.0.0.1:" +
           std::to_string(_blackholePort) +
           ";\n"
           "            proxy_read_timeout 60s;\n"
           "        }\n" +
           _extraConfig +
           "    }\n"
           "}\n";
}

std::string NginxServer::start() {
    if (running()) return "";
    const std::string nginx = executable();
    if (nginx.empty()) return "nginx is not installed";
    if (_blackhole < 0) return "cannot open a listening socket on 127.0.0.1 (for /stall/)";
    ::setenv("no_proxy", "127.0.0.1", 1);
    ::setenv("NO_PROXY", "127.0.0.1", 1);
    // The free port may be taken by another process (ctest -j) before nginx binds it: then nginx
    // exits at once, and another port is tried.
    std::string log;
    for (int attempt = 0; attempt < 3; ++attempt) {
        _port = freeLocalPort();
        if (_port == 0) return "no free port on 127.0.0.1";
        writeTextFile(_dir.file("nginx.conf"), config(_port));
        bool failed = false;
        if (launch(log, failed)) return "";
        if (failed) return log;
    }
    return "nginx exited:\n" + log;
}

std::string NginxServer::restart() {
    if (running()) return "";
    if (_port == 0) return "the server never ran: start() it first";
    std::string log;
    bool failed = false;
    if (launch(log, failed)) return "";
    return "nginx exited:\n" + log;
}

bool NginxServer::launch(std::string& log, bool& failed) {
    const std::string nginx = executable();
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
    // fork + exec rather than posix_spawn: the child asks to be killed when the test dies. Only
    // async-signal-safe calls between fork and exec (the test may have other threads).
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid < 0) {
        failed = true;
        log = "cannot start " + nginx + ": " + std::strerror(errno);
        return false;
    }
    if (pid == 0) {
#ifdef __linux__
        ::prctl(PR_SET_PDEATHSIG, SIGKILL);
#endif
        if (::getppid() != parent) ::_exit(127);
        const int out = ::open(outPath.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
        if (out >= 0) {
            ::dup2(out, 1);
            ::dup2(out, 2);
            if (out > 2) ::close(out);
        }
        ::execve(nginx.c_str(), argv.data(), environ);
        ::_exit(127);
    }
    _pid = pid;
    using Clock = std::chrono::steady_clock;
    const auto begin = Clock::now();
    while (!acceptsConnections(_port)) {
        int status = 0;
        if (::waitpid(_pid, &status, WNOHANG) == _pid) {
            _pid = -1;
            log = readIfExists(outPath) + readIfExists(_dir.file("error.log"));
            if (WIFEXITED(status) && WEXITSTATUS(status) == 127 && log.empty()) {
                failed = true;
                log = "cannot run " + nginx;
            }
            return false;
        }
        if (Clock::now() - begin > std::chrono::seconds(5)) {
            stop();
            failed = true;
            log = "nginx does not accept connections in 5 s";
            return false;
        }
        std::this_thread::sleep_for(std::chrono::milliseconds(5));
    }
    return true;
}

void NginxServer::stop() {
    if (_pid <= 0) return;
    ::kill(_pid, SIGKILL);
    int status = 0;
    while (::waitpid(_pid, &status, 0) < 0 && errno == EINTR) {
    }
    _pid = -1;
}

}  // namespace osgBTF::test
