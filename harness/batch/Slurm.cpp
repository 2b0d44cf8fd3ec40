// `btf batch run RESULTS --slurm`: the jobs as Slurm array tasks, each one `btf batch job`, and
// what squeue says about them.
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <ctime>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <set>
#include <sstream>
#include <thread>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/Progress.h"
#include "harness/FitRunner.h"
#include "harness/batch/BatchFiles.h"

namespace osgBTF::batch {

namespace fs = std::filesystem;

namespace {

std::string shellQuote(const std::string& text) {
    std::string out = "'";
    for (const char c : text) out += c == '\'' ? std::string("'\\''") : std::string(1, c);
    return out + "'";
}

struct Output {
    int status = -1;
    std::string text;
};

/** Runs a shell command line, stdout and stderr captured. */
Output capture(const std::string& command) {
    Output out;
    FILE* pipe = popen((command + " 2>&1").c_str(), "r");
    if (!pipe) return out;
    char buffer[4096];
    std::size_t n = 0;
    while ((n = fread(buffer, 1, sizeof buffer, pipe)) > 0) out.text.append(buffer, n);
    const int status = pclose(pipe);
    out.status = WIFEXITED(status) ? WEXITSTATUS(status) : -1;
    return out;
}

std::string slurmFolder(const std::string& resultsDir) {
    return (fs::path(resultsDir) / "slurm").string();
}

nlohmann::json readSubmissions(const std::string& resultsDir) {
    std::ifstream in(fs::path(slurmFolder(resultsDir)) / "submissions.json");
    if (!in) return nlohmann::json::array();
    try {
        return nlohmann::json::parse(in);
    } catch (const std::exception&) {
        return nlohmann::json::array();
    }
}

/** The array task's job: line task + 1 of the submission's list. */
std::string jobOfTask(const nlohmann::json& submission, std::size_t task) {
    const auto& jobs = submission.at("jobs");
    return task < jobs.size() ? jobs[task].get<std::string>() : std::string();
}

std::uint64_t memoryBucketMiB(std::uint64_t bytes) {
    std::uint64_t mib = 64;
    while (mib * (std::uint64_t(1) << 20) < bytes) mib *= 2;
    return mib;
}

const char* kTaskScript = R"(#!/bin/sh
# One Slurm array task of `btf batch run --slurm` (written by btf): line SLURM_ARRAY_TASK_ID + 1
# of LIST names the job; `btf batch job` fits and scores it and writes jobs/<id>/result.json.
# Usage: task.sh LIST RESULTS BTF [global btf options...]
list="$1"; results="$2"; tool="$3"; shift 3
id=$(sed -n "$((SLURM_ARRAY_TASK_ID + 1))p" "$list")
[ -n "$id" ] || { echo "task.sh: no line $((SLURM_ARRAY_TASK_ID + 1)) in $list" >&2; exit 2; }
exec "$tool" "$@" --no-progress batch job "$results" "$id"
)";

}  // namespace

bool haveSlurm() {
    const char* path = std::getenv("PATH");
    std::istringstream dirs(path ? path : "");
    std::string dir;
    while (std::getline(dirs, dir, ':'))
        if (!dir.empty() && access((fs::path(dir) / "sbatch").c_str(), X_OK) == 0) return true;
    return false;
}

namespace {

/** Fills `states` from squeue; false when squeue itself fails (slurmctld down or busy). All of
 *  this user's osgbtf-batch tasks are listed and matched here: a `-j` list with one job Slurm
 *  has forgotten makes squeue fail for all of them. */
bool querySlurm(const std::string& resultsDir, std::map<std::string, std::string>& states) {
    states.clear();
    const nlohmann::json submissions = readSubmissions(resultsDir);
    if (submissions.empty()) return true;
    std::map<std::string, const nlohmann::json*> byId;
    for (const auto& s : submissions) byId[s.at("slurm_job").get<std::string>()] = &s;
    // -r: one line per array task, pending ones too ("123_4 PENDING").
    const Output out = capture("squeue -h -r --me -n osgbtf-batch -o '%i %T'");
    if (out.status != 0) return false;
    std::istringstream lines(out.text);
    std::string task, state;
    while (lines >> task >> state) {
        const auto underscore = task.find('_');
        if (underscore == std::string::npos) continue;
        const auto submission = byId.find(task.substr(0, underscore));
        if (submission == byId.end()) continue;
        try {
            const std::string job =
                jobOfTask(*submission->second, std::stoul(task.substr(underscore + 1)));
            if (!job.empty()) states[job] = state + " (" + task + ")";
        } catch (const std::exception&) {
        }
    }
    return true;
}

}  // namespace

std::map<std::string, std::string> slurmStates(const std::string& resultsDir) {
    std::map<std::string, std::string> states;
    if (haveSlurm() && !querySlurm(resultsDir, states)) states.clear();
    return states;
}

std::map<std::string, std::string> slurmTasks(const std::string& resultsDir) {
    std::map<std::string, std::string> tasks;
    for (const auto& s : readSubmissions(resultsDir)) {
        const auto& jobs = s.at("jobs");
        for (std::size_t i = 0; i < jobs.size(); ++i)
            tasks[jobs[i].get<std::string>()] =
                s.at("slurm_job").get<std::string>() + "_" + std::to_string(i);
    }
    return tasks;
}

std::size_t submitSlurm(const Manifest& manifest, const std::string& resultsDir,
                        const SlurmOptions& options, RunSummary* summary) {
    if (!haveSlurm())
        throw Error(
            "--slurm: sbatch is not on PATH (Slurm is not installed here); run without --slurm "
            "to use this machine");
    const std::string tool =
        fs::absolute(options.tool.empty() ? defaultFitTool() : options.tool).string();
    const std::string results = fs::absolute(resultsDir).lexically_normal().string();
    std::map<std::string, std::string> queued;
    if (!querySlurm(results, queued))
        throw Error("--slurm: squeue failed (is slurmctld running? see SLURM_CONF)");
    std::map<std::uint64_t, std::vector<const BatchJob*>> groups;
    RunSummary local;
    for (const BatchJob& job : manifest.jobs) {
        const JobResult previous = readJobResult(results, job.id);
        if (previous.state == JobState::Done)
            ++local.alreadyDone;
        else if (previous.state == JobState::Running || queued.count(job.id))
            ++local.runningElsewhere;
        else
            groups[memoryBucketMiB(job.estimatedPeakBytes)].push_back(&job);
    }
    const std::string folder = slurmFolder(results);
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) fail(folder, "cannot create: " + ec.message());
    const std::string script = (fs::path(folder) / "task.sh").string();
    writeTextAtomically(script, kTaskScript);
    fs::permissions(script, fs::perms::owner_all | fs::perms::group_read | fs::perms::others_read |
                                fs::perms::group_exec | fs::perms::others_exec);

    nlohmann::json submissions = readSubmissions(results);
    std::vector<std::string> submitted;
    std::size_t tasks = 0;
    const std::string stamp = std::to_string(std::time(nullptr)) + "-" + std::to_string(getpid());
    for (const auto& [mib, jobs] : groups) {
        const std::string list =
            (fs::path(folder) / ("jobs-" + stamp + "-" + std::to_string(mib) + "M.txt")).string();
        std::string text;
        for (const BatchJob* job : jobs) text += job->id + "\n";
        writeTextAtomically(list, text);
        std::string command = "sbatch --parsable --job-name=osgbtf-batch --array=0-" +
                              std::to_string(jobs.size() - 1) + " --mem=" + std::to_string(mib) +
                              "M --output=" + shellQuote(folder + "/%A_%a.out");
        if (!options.partition.empty()) command += " --partition=" + shellQuote(options.partition);
        if (!options.time.empty()) command += " --time=" + shellQuote(options.time);
        for (const std::string& a : options.sbatchArguments) command += " " + shellQuote(a);
        command += " " + shellQuote(script) + " " + shellQuote(list) + " " + shellQuote(results) +
                   " " + shellQuote(tool);
        for (const std::string& a : options.globalArguments) command += " " + shellQuote(a);
        const Output out = capture(command);
        std::string id = out.text.substr(0, out.text.find_first_of(";\n"));
        if (out.status != 0 || id.empty() ||
            id.find_first_not_of("0123456789") != std::string::npos)
            throw Error("--slurm: sbatch refused the array of " + std::to_string(jobs.size()) +
                        " jobs at --mem=" + std::to_string(mib) + "M: " + out.text);
        nlohmann::json record = {
            {"slurm_job", id}, {"mem_mib", mib}, {"list", list}, {"jobs", nlohmann::json::array()}};
        for (const BatchJob* job : jobs) record["jobs"].push_back(job->id);
        submissions.push_back(record);
        // Recorded after every array: a refusal of the next must not lose this one.
        writeTextAtomically((fs::path(folder) / "submissions.json").string(),
                            submissions.dump(2) + "\n");
        submitted.push_back(id);
        tasks += jobs.size();
        std::cout << "submitted Slurm job " << id << ": " << jobs.size()
                  << " tasks at --mem=" << mib << "M\n";
    }

    if (options.wait && tasks) {
        Progress progress("batch jobs (Slurm)", tasks);
        std::set<std::string> mine;
        for (const auto& [mib, jobs] : groups)
            for (const BatchJob* job : jobs) mine.insert(job->id);
        std::size_t reported = 0;
        bool warned = false;
        for (;;) {
            std::this_thread::sleep_for(std::chrono::duration<double>(options.pollSeconds));
            std::map<std::string, std::string> states;
            if (!querySlurm(results, states)) {
                // slurmctld restarting or busy: ask again, the tasks are still Slurm's.
                if (!warned) std::cerr << "batch: squeue failed; still waiting\n";
                warned = true;
                continue;
            }
            std::size_t left = 0;
            for (const std::string& id : mine) left += states.count(id);
            if (tasks - left > reported) {
                progress.advance(tasks - left - reported);
                reported = tasks - left;
            }
            if (!left) break;
        }
    }
    if (summary) {
        *summary = local;
        summary->ran = tasks;
        if (options.wait)
            for (const auto& [mib, jobs] : groups)
                for (const BatchJob* job : jobs)
                    ++(readJobResult(results, job->id).state == JobState::Done ? summary->done
                                                                               : summary->failed);
    }
    return tasks;
}

}  // namespace osgBTF::batch
