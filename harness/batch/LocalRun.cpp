// `btf batch run RESULTS`: the jobs on this machine, as `btf batch job` child processes, as many
// at once as --jobs and the memory budget allow.
#include <sys/resource.h>
#include <sys/wait.h>

#include <cerrno>
#include <cstring>
#include <filesystem>
#include <iostream>
#include <map>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/MeasuredBtf.h"
#include "core/Progress.h"
#include "harness/FitRunner.h"
#include "harness/batch/BatchFiles.h"

namespace osgBTF::batch {

namespace fs = std::filesystem;

RunSummary runLocal(const Manifest& manifest, const std::string& resultsDir,
                    const LocalRunOptions& options) {
    const std::string tool = options.tool.empty() ? defaultFitTool() : options.tool;
    const std::uint64_t budget = options.memoryBudget ? options.memoryBudget : memoryLimit();
    const std::size_t parallel = std::size_t(std::max(1, options.jobs));
    RunSummary summary;
    std::vector<const BatchJob*> todo;
    for (const BatchJob& job : manifest.jobs) {
        const JobResult previous = readJobResult(resultsDir, job.id);
        if (previous.state == JobState::Done)
            ++summary.alreadyDone;
        else if (previous.state == JobState::Running)
            ++summary.runningElsewhere;
        else
            todo.push_back(&job);
    }

    struct Child {
        const BatchJob* job;
        std::uint64_t bytes;
    };
    std::map<pid_t, Child> running;
    std::uint64_t inUse = 0;
    std::size_t next = 0;
    Progress progress("batch jobs", todo.size());
    while (next < todo.size() || !running.empty()) {
        while (next < todo.size() && running.size() < parallel) {
            const BatchJob& job = *todo[next];
            if (!running.empty() && inUse + job.estimatedPeakBytes > budget) break;
            if (job.estimatedPeakBytes > budget)
                std::cerr << "batch: warning: job " << job.id << " is estimated to need "
                          << formatBytes(job.estimatedPeakBytes) << ", more than the memory budget "
                          << formatBytes(budget) << "; it runs alone\n";
            const std::string folder = jobFolder(resultsDir, job.id);
            if (jobLockHeld((fs::path(folder) / "lock").string())) {
                // Another run on the folder has it (checked here, not only by the child, so
                // that the child's log does not replace the running one's).
                ++summary.runningElsewhere;
                progress.advance();
                ++next;
                continue;
            }
            std::error_code ec;
            fs::create_directories(folder, ec);
            std::vector<std::string> args{tool};
            args.insert(args.end(), options.globalArguments.begin(), options.globalArguments.end());
            args.insert(args.end(), {"--no-progress", "batch", "job", resultsDir, job.id});
            pid_t pid = -1;
            try {
                pid = spawnChild(args, (fs::path(folder) / "log.txt").string());
            } catch (const Error& e) {
                // Recorded as the job's failure (a tool replaced while the run goes on); the
                // others are still tried.
                JobResult failed;
                failed.id = job.id;
                failed.state = JobState::Failed;
                failed.failure = e.what();
                writeTextAtomically((fs::path(folder) / "result.json").string(),
                                    jobResultToJson(failed).dump(2) + "\n");
                std::cerr << "batch: " << job.id << " failed: " << failed.failure << "\n";
                ++summary.ran;
                ++summary.failed;
                progress.advance();
                ++next;
                continue;
            }
            running[pid] = Child{&job, job.estimatedPeakBytes};
            inUse += job.estimatedPeakBytes;
            ++next;
        }
        if (running.empty()) continue;  // every job left was running elsewhere
        int status = 0;
        struct rusage usage {};
        const pid_t pid = wait4(-1, &status, 0, &usage);
        if (pid < 0) {
            if (errno == EINTR) continue;
            throw Error(std::string("batch: waiting for the jobs failed: ") + std::strerror(errno));
        }
        const auto child = running.find(pid);
        if (child == running.end()) continue;  // not one of ours
        const BatchJob& job = *child->second.job;
        inUse -= child->second.bytes;
        running.erase(child);
        ++summary.ran;
        JobResult result = readJobResult(resultsDir, job.id);
        if (result.state == JobState::Running) {
            // Another run on the folder took the job first; its child found the lock held.
            --summary.ran;
            ++summary.runningElsewhere;
            progress.advance();
            continue;
        }
        if (result.state != JobState::Done && result.state != JobState::Failed) {
            // Killed or crashed before it could write its result: record why.
            const std::string folder = jobFolder(resultsDir, job.id);
            result = JobResult{};
            result.id = job.id;
            result.state = JobState::Failed;
            result.failure = childFailure(status, (fs::path(folder) / "log.txt").string());
            result.peakRssBytes = std::uint64_t(usage.ru_maxrss) * 1024u;
            writeTextAtomically((fs::path(folder) / "result.json").string(),
                                jobResultToJson(result).dump(2) + "\n");
        }
        if (result.state == JobState::Done) {
            ++summary.done;
        } else {
            ++summary.failed;
            // Above the progress bar's line, so the reason is seen while the others go on.
            if (Progress::enabled()) std::cerr << "\n";
            std::cerr << "batch: " << job.id << " failed: " << result.failure << "\n";
        }
        progress.advance();
    }
    return summary;
}

}  // namespace osgBTF::batch
