#include "harness/FitRunner.h"

#include <fcntl.h>
#include <spawn.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <sstream>

#include <nlohmann/json.hpp>

#include "core/Error.h"
#include "core/FloatImage.h"

extern char** environ;

namespace osgBTF {

namespace fs = std::filesystem;

namespace {

std::vector<std::string> commandLine(const FitJob& job) {
    std::vector<std::string> args{job.tool};
    args.insert(args.end(), job.globalArguments.begin(), job.globalArguments.end());
    // --no-mipmap: the base level, `btf fit`'s default before mip-mapping was; the tables measure
    // each method against the measured texels, as the papers do (a mip-mapped fit's texels are an
    // atlas of every level).
    args.insert(args.end(), {"--no-progress", "fit", job.input, "-m", job.method, "--no-mipmap"});
    for (const auto& [key, value] : job.options)
        args.insert(args.end(), {"--set", key + "=" + value});
    args.insert(args.end(), job.extraArguments.begin(), job.extraArguments.end());
    args.insert(args.end(), {"-o", job.output});
    return args;
}

/** The child's own error line ("btf: error: X" -> "X"), or its last non-empty line. */
std::string failureText(const std::string& logPath) {
    std::ifstream in(logPath);
    std::string line, last, error;
    while (std::getline(in, line)) {
        if (line.empty()) continue;
        last = line;
        for (const char* prefix : {"btf: error: ", "btf: unexpected error: "})
            if (line.rfind(prefix, 0) == 0) error = line.substr(std::strlen(prefix));
    }
    return error.empty() ? last : error;
}

/** Newest modification time of a file, or of a folder and the files directly in it. */
fs::file_time_type newestTime(const std::string& path) {
    fs::file_time_type newest = fs::last_write_time(path);
    if (fs::is_directory(path))
        for (const auto& entry : fs::directory_iterator(path))
            newest = std::max(newest, entry.last_write_time());
    return newest;
}

nlohmann::json jobKey(const FitJob& job) {
    std::error_code ec;
    const fs::path input = fs::weakly_canonical(job.input, ec);
    return {{"input", ec ? job.input : input.string()},
            {"method", job.method},
            {"options", job.options},
            {"extra_arguments", job.extraArguments},
            {"global_arguments", job.globalArguments}};
}

}  // namespace

pid_t spawnChild(const std::vector<std::string>& args, const std::string& log) {
    if (access(args.at(0).c_str(), X_OK) != 0)
        throw Error(args[0] + ": the btf tool to run with is missing or not executable");
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);

    posix_spawn_file_actions_t actions;
    posix_spawn_file_actions_init(&actions);
    posix_spawn_file_actions_addopen(&actions, STDOUT_FILENO, log.c_str(),
                                     O_WRONLY | O_CREAT | O_TRUNC, 0644);
    posix_spawn_file_actions_adddup2(&actions, STDOUT_FILENO, STDERR_FILENO);
    posix_spawn_file_actions_addopen(&actions, STDIN_FILENO, "/dev/null", O_RDONLY, 0);
    pid_t pid = 0;
    // The child dies with this process (tools/btf/main.cpp reads OSGBTF_PARENT_PID).
    std::vector<std::string> environment;
    for (char** e = environ; *e; ++e)
        if (std::strncmp(*e, "OSGBTF_PARENT_PID=", 18) != 0) environment.emplace_back(*e);
    environment.push_back("OSGBTF_PARENT_PID=" + std::to_string(getpid()));
    std::vector<char*> envp;
    for (std::string& e : environment) envp.push_back(e.data());
    envp.push_back(nullptr);
    const int spawnError =
        posix_spawn(&pid, args[0].c_str(), &actions, nullptr, argv.data(), envp.data());
    posix_spawn_file_actions_destroy(&actions);
    if (spawnError != 0) throw Error(args[0] + ": cannot start: " + std::strerror(spawnError));
    return pid;
}

std::string childFailure(int status, const std::string& logPath) {
    std::string text = failureText(logPath);
    if (WIFSIGNALED(status))
        return "crashed (signal " + std::to_string(WTERMSIG(status)) + ", " +
               strsignal(WTERMSIG(status)) + ")" + (text.empty() ? "" : ": " + text);
    if (text.empty()) text = "exited with status " + std::to_string(WEXITSTATUS(status));
    return text;
}

FitProcessResult runFitProcess(const FitJob& job) {
    const auto start = std::chrono::steady_clock::now();
    const pid_t pid = spawnChild(commandLine(job), job.log);

    int status = 0;
    struct rusage usage {};
    pid_t waited = -1;
    do {
        waited = wait4(pid, &status, 0, &usage);
    } while (waited < 0 && errno == EINTR);
    FitProcessResult result;
    result.wallSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    result.peakRssBytes = std::uint64_t(usage.ru_maxrss) * 1024u;  // Linux: kilobytes
    if (waited < 0) {
        result.message = std::string("wait4 failed: ") + std::strerror(errno);
    } else if (WIFEXITED(status) && WEXITSTATUS(status) == 0) {
        result.ok = fs::exists(job.output);
        if (!result.ok) result.message = "btf fit exited 0 but wrote no " + job.output;
    } else {
        result.message = childFailure(status, job.log);
    }
    return result;
}

void writeFitRecord(const FitJob& job, const FitProcessResult& result, const std::string& path) {
    nlohmann::json record = jobKey(job);
    record["wall_seconds"] = result.wallSeconds;
    record["peak_rss_bytes"] = result.peakRssBytes;
    writeTextAtomically(path, record.dump(2) + "\n");
}

bool canReuseFit(const FitJob& job, const std::string& previousOutput, FitProcessResult& result) {
    std::error_code ec;
    const std::string recordPath = previousOutput + ".json";
    if (!fs::is_regular_file(previousOutput, ec) || !fs::is_regular_file(recordPath, ec))
        return false;
    try {
        if (fs::last_write_time(previousOutput) <= newestTime(job.input)) return false;
        std::ifstream in(recordPath);
        const nlohmann::json record = nlohmann::json::parse(in);
        const nlohmann::json key = jobKey(job);
        for (const auto& [name, value] : key.items())
            if (!record.contains(name) || record[name] != value) return false;
        result = FitProcessResult{};
        result.ok = true;
        result.reused = true;
        result.wallSeconds = record.value("wall_seconds", 0.0);
        result.peakRssBytes = record.value("peak_rss_bytes", std::uint64_t(0));
        return true;
    } catch (const std::exception&) {
        return false;  // an unreadable record: fit again
    }
}

std::string defaultFitTool() {
    std::error_code ec;
    const fs::path self = fs::read_symlink("/proc/self/exe", ec);
    if (ec) return "btf";
    if (self.filename() == "btf") return self.string();
    return (self.parent_path() / "btf").string();
}

}  // namespace osgBTF
