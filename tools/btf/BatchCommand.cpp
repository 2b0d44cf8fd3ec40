// btf batch plan|run|job|status|report: every method on every measured BTF of a folder, on this
// machine or a Slurm cluster, resumable, and the leaderboard (the library side is
// harness/batch/Batch.h).
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "harness/Compare.h"
#include "harness/batch/Batch.h"
#include "materials/MethodRegistry.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

namespace {

std::vector<std::string> globalArguments(const CommonOptions& common) {
    if (common.memoryLimit.empty()) return {};
    return {"--memory-limit", common.memoryLimit};
}

void printSummary(const batch::RunSummary& s) {
    std::cout << "batch: " << s.ran << " jobs run (" << s.done << " done, " << s.failed
              << " failed); " << s.alreadyDone << " were done before";
    if (s.runningElsewhere) std::cout << ", " << s.runningElsewhere << " running elsewhere";
    std::cout << "\n";
}

}  // namespace

Runner addBatchCommand(CLI::App& app, CommonOptions& common) {
    auto* command = app.add_subcommand(
        "batch",
        "Fit and score every method on every measured BTF of a folder, on this machine or as "
        "Slurm array tasks; resumable; then a leaderboard (report.md, results.csv/json, "
        "index.html). Steps: plan, run, status, report (docs/batch.md)");
    command->require_subcommand(1);
    struct Options {
        std::vector<std::string> inputs;
        std::string results, methods = "all", id;
        std::vector<std::string> settings;
        double holdout = 0.1;
        long long errorTexels = -1;
        int jobs = 1;
        bool slurm = false, wait = false;
        std::string partition, time;
        std::vector<std::string> sbatch;
    };
    auto options = std::make_shared<Options>();
    std::string methodList;
    for (const std::string& m : allCompareMethods()) methodList += "," + m;

    auto* plan = command->add_subcommand(
        "plan",
        "Find the measured BTFs (UBO2014 .btf, UBO2003/ATRIUM zips and folders) in DIR or LIST "
        "(a .txt file, one path per line) and write RESULTS/manifest.json: one job per material "
        "and method, with a stable id and its estimated peak memory");
    plan->add_option("INPUT", options->inputs, "Folders, list files (.txt) or measured BTFs")
        ->required();
    plan->add_option("--out", options->results, "Results folder")->required();
    plan->add_option(
            "--methods", options->methods,
            "Comma-separated methods, or 'all' (" + baselineMethod().name + methodList + ")")
        ->capture_default_str();
    plan->add_option("--set", options->settings,
                     "METHOD:KEY=VALUE, one method's fit option (repeatable; `btf fit --help`)");
    plan->add_option("--holdout-fraction", options->holdout,
                     "Fraction of the (view, light) pairs each job also leaves out of a second "
                     "fit and scores (whole directions; 0: none)")
        ->check(CLI::Range(0.0, 0.5))
        ->capture_default_str();
    plan->add_option("--error-texels", options->errorTexels,
                     "Score this many random texels (all pairs each); 0 = all. Default: all for "
                     "data in memory, 4096 for a UBO2014 file")
        ->check(CLI::NonNegativeNumber);
    addLoadOptions(*plan, common);

    auto* run = command->add_subcommand(
        "run",
        "Run every job of RESULTS that is not done (failed and killed ones again): here, as "
        "child processes within --jobs and the memory budget (the global --memory-limit, "
        "default 3/4 of RAM), or with --slurm as Slurm array tasks");
    run->add_option("RESULTS", options->results, "Results folder (btf batch plan)")->required();
    run->add_option("-j,--jobs", options->jobs, "Jobs at once on this machine")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    run->add_flag("--slurm", options->slurm,
                  "Submit the jobs as Slurm job arrays (sbatch --array, --mem from each job's "
                  "estimate) instead of running them here");
    run->add_option("--partition", options->partition, "--slurm: the partition");
    run->add_option("--time", options->time, "--slurm: the time limit per task (sbatch --time)");
    run->add_option("--sbatch-arg", options->sbatch,
                    "--slurm: one more sbatch argument, e.g. --sbatch-arg=--account=x "
                    "(repeatable)");
    run->add_flag("--wait", options->wait,
                  "--slurm: wait until every submitted task has left the queue");

    auto* job = command->add_subcommand(
        "job", "Run one job in this process (what `run` and each Slurm task start)");
    job->add_option("RESULTS", options->results, "Results folder")->required();
    job->add_option("ID", options->id, "Job id (manifest.json)")->required();

    auto* status = command->add_subcommand(
        "status",
        "Each job's state: done, failed (with the reason), running, queued in Slurm, "
        "pending");
    status->add_option("RESULTS", options->results, "Results folder")->required();

    auto* report = command->add_subcommand(
        "report",
        "Write the leaderboard: RESULTS/report.md, results.csv, results.json and index.html "
        "(sortable tables, error-vs-bytes plots and the Pareto front per material, a "
        "recommended method per class; opens from disk, no network)");
    report->add_option("RESULTS", options->results, "Results folder")->required();

    return [&common, options, plan, run, job, status, report] {
        if (plan->parsed()) {
            batch::PlanOptions p;
            p.inputs = options->inputs;
            p.methods =
                options->methods == "all" ? allCompareMethods() : splitList(options->methods);
            if (options->methods == "all")
                p.methods.insert(p.methods.begin(), baselineMethod().name);
            addMethodSettings(options->settings, p.methodOptions);
            p.holdoutFraction = options->holdout;
            p.errorTexels = options->errorTexels;
            p.storage = common.storage;
            p.decode = common.decode;
            const batch::Manifest manifest = batch::planBatch(p);
            batch::writeManifest(manifest, options->results);
            std::uint64_t largest = 0;
            for (const batch::BatchJob& j : manifest.jobs)
                largest = std::max(largest, j.estimatedPeakBytes);
            std::cout << "planned " << manifest.jobs.size()
                      << " jobs: " << manifest.materials.size() << " materials x "
                      << p.methods.size() << " methods; largest estimated peak "
                      << formatBytes(largest) << "\nwrote " << options->results
                      << "/manifest.json\n";
        } else if (run->parsed()) {
            const batch::Manifest manifest = batch::readManifest(options->results);
            batch::RunSummary summary;
            if (options->slurm) {
                batch::SlurmOptions s;
                s.partition = options->partition;
                s.time = options->time;
                s.sbatchArguments = options->sbatch;
                s.globalArguments = globalArguments(common);
                s.wait = options->wait;
                const std::size_t tasks =
                    batch::submitSlurm(manifest, options->results, s, &summary);
                if (!options->wait) {
                    std::cout << "batch: " << tasks << " Slurm tasks submitted; "
                              << summary.alreadyDone << " jobs were done before. `btf batch "
                              << "status " << options->results << "` follows them\n";
                    return;
                }
            } else {
                batch::LocalRunOptions l;
                l.jobs = options->jobs;
                l.globalArguments = globalArguments(common);
                summary = batch::runLocal(manifest, options->results, l);
            }
            printSummary(summary);
            if (summary.failed)
                throw Error(std::to_string(summary.failed) +
                            " jobs failed (reasons above and in `btf batch status`); the others "
                            "are done. Run again to retry the failed ones");
        } else if (job->parsed()) {
            const batch::Manifest manifest = batch::readManifest(options->results);
            const batch::JobResult r = batch::runJob(manifest, options->results, options->id);
            std::cout << options->id << ": " << batch::jobStateName(r.state) << ", avg error "
                      << r.average << ", held-out " << r.heldOutAverage << ", " << r.bytesPerTexel
                      << " bytes per texel, " << r.wallSeconds << " s\n";
        } else if (status->parsed()) {
            const batch::Manifest manifest = batch::readManifest(options->results);
            const std::map<std::string, std::string> queued = batch::slurmStates(options->results);
            const std::map<std::string, std::string> tasks = batch::slurmTasks(options->results);
            std::map<std::string, std::size_t> counts;
            for (const batch::BatchJob& j : manifest.jobs) {
                const batch::JobResult r = batch::readJobResult(options->results, j.id);
                std::string state = batch::jobStateName(r.state);
                const auto q = queued.find(j.id);
                if (r.state != batch::JobState::Done && r.state != batch::JobState::Running &&
                    q != queued.end())
                    state = "slurm " + q->second;
                ++counts[state.substr(0, state.find(' '))];
                std::cout << std::left << std::setw(40) << j.id << " " << state;
                if (r.state == batch::JobState::Failed) std::cout << ": " << r.failure;
                const auto task = tasks.find(j.id);
                if (r.state == batch::JobState::Pending && q == queued.end() && task != tasks.end())
                    std::cout << " (Slurm task " << task->second
                              << " ended without a result: cancelled, out of time or its node "
                                 "failed; see "
                              << options->results << "/slurm/" << task->second << ".out)";
                std::cout << "\n";
            }
            std::cout << manifest.jobs.size() << " jobs:";
            for (const auto& [state, count] : counts) std::cout << " " << count << " " << state;
            std::cout << "\n";
        } else if (report->parsed()) {
            const batch::Manifest manifest = batch::readManifest(options->results);
            batch::writeReport(manifest, options->results);
            std::cout << "wrote " << options->results << "/report.md, results.csv, results.json, "
                      << "index.html\n";
        }
    };
}

}  // namespace osgBTF::tool
