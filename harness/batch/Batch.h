// osgBTF batch: every method fitted and scored on every measured BTF of a folder (`btf batch`),
// on this machine or as a Slurm job array, resumable, then a leaderboard.
//
// A results folder holds manifest.json (the plan: materials and jobs) and one folder per job,
// jobs/<id>/, where the job writes result.json atomically when it ends (done or failed), its log
// and its fitted material. A job is one material x one method x one set of options; everything it
// measures happens in one `btf batch job` process, started by the local pool (runLocal) or by a
// Slurm array task (submitSlurm), so both ways give the same files. Layout and formulas:
// harness/batch/README.md.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace osgBTF::batch {

struct BatchMaterial {
    std::string name;           ///< unique in the manifest; the stem of the file or folder
    std::string materialClass;  ///< the parent folder below the planned folder, else the name
                                ///< without trailing digits ("carpet01" -> "carpet")
    std::string input;          ///< absolute path
    int width = 0, height = 0;
    std::size_t views = 0, lights = 0;
    bool factored = false;         ///< a UBO2014 file, decoded block by block
    std::uint64_t inputBytes = 0;  ///< what opening it holds in memory
};

struct BatchJob {
    std::string id;  ///< "<material>--<method>[--key=value...]", stable for the same plan
    std::string material, method;
    std::map<std::string, std::string> options;
    std::uint64_t estimatedPeakBytes = 0;  ///< estimatePeakBytes(); the pools' and --mem's unit
};

struct Manifest {
    int version = 1;
    std::string created;  ///< UTC, ISO 8601
    /** Fraction of the measured (view, light) pairs each job also leaves out of a second fit
     *  and scores (holdoutSplit); 0: no held-out scores. */
    double holdoutFraction = 0.1;
    /** Texels the error is computed on (randomTexels, the same for every method of a material);
     *  the default -1: all for data in memory, 4096 for a UBO2014 file (errorTexelCount). */
    long long errorTexels = -1;
    std::string storage = "float", decode = "auto";  ///< `btf fit`'s load options
    std::vector<BatchMaterial> materials;
    std::vector<BatchJob> jobs;

    const BatchMaterial& material(const std::string& name) const;
    /** Throws Error "RESULTS: no job 'ID' in the manifest". */
    const BatchJob& job(const std::string& id) const;
};

struct PlanOptions {
    /** Folders (searched recursively), list files (one path per line, '#' comments) or BTFs. */
    std::vector<std::string> inputs;
    std::vector<std::string> methods;  ///< registry names
    /** METHOD -> KEY -> VALUE, validated against each method's options. */
    std::map<std::string, std::map<std::string, std::string>> methodOptions;
    double holdoutFraction = 0.1;
    long long errorTexels = -1;
    std::string storage = "float", decode = "auto";
};

/** Every measured BTF below `folder`: UBO2014 .btf files, UBO2003/ATRIUM zips, RTI zips (images
 *  and their .lp file), and folders that hold UBO2003-named images or an .lp file (a folder is
 *  one BTF, not searched further). Sorted by path. */
std::vector<std::string> findMeasuredBtfs(const std::string& folder);

/** Opens every material (a UBO2014 file's header and factors; a UBO2003 zip or folder is read
 *  whole to know its size) and lists one job per material and method. Throws Error for an input
 *  that is missing or not a measured BTF, an unknown method or an invalid option, and when no
 *  material is found. */
Manifest planBatch(const PlanOptions& options);

/** Peak resident memory of a job, for the pool and Slurm's --mem: the input as opened, the
 *  fit's working copy of it for the methods that gather all values (twice for the held-out fit)
 *  and a fixed part for the program itself. A coarse upper estimate; the results record the
 *  measured peak beside it (report.md). */
std::uint64_t estimatePeakBytes(const BatchMaterial& material, const std::string& method);

/** Creates RESULTS (and RESULTS/jobs) if needed and writes RESULTS/manifest.json atomically. A
 *  manifest already there is replaced: jobs of the same id keep their results. */
void writeManifest(const Manifest& manifest, const std::string& resultsDir);
/** Throws Error "RESULTS: no manifest.json (run `btf batch plan` first)" or naming a bad file. */
Manifest readManifest(const std::string& resultsDir);

std::string jobFolder(const std::string& resultsDir, const std::string& id);

enum class JobState { Pending, Running, Done, Failed };
const char* jobStateName(JobState state);

struct JobResult {
    std::string id;
    JobState state = JobState::Pending;
    std::string failure;  ///< why it failed (the job's error, the signal, Slurm's reason)
    double average = 0, rmse = 0, psnr = 0;  ///< on every measured pair of the error texels
    /** On the held-out pairs, by the fit without them; NaN: no held-out fit. */
    double heldOutAverage = 0, heldOutRmse = 0, heldOutPsnr = 0;
    double heldOutSsim = 0;  ///< mean SSIM of up to 8 whole held-out images (harness/HeldOut.h)
    std::size_t heldOutPairs = 0, errorTexels = 0;
    double bytesPerTexel = 0, compressionRatio = 0;
    double fitSeconds = 0, heldOutFitSeconds = 0, wallSeconds = 0;
    std::uint64_t peakRssBytes = 0;
    std::string host;
};

/** The state of a job from its folder: Done or Failed from result.json, Running while a process
 *  holds its lock (flock on jobs/<id>/lock), Pending otherwise (never run, or killed: a killed
 *  job leaves no result and no lock). */
JobResult readJobResult(const std::string& resultsDir, const std::string& id);

/** The job, in this process (`btf batch job`): takes its lock (throws Error "... is running in
 *  another process" when held), fits, scores, saves the fit and writes result.json atomically.
 *  A failure is written as a Failed result and rethrown. Returns the result. */
JobResult runJob(const Manifest& manifest, const std::string& resultsDir, const std::string& id);

struct LocalRunOptions {
    std::string tool;  ///< the btf executable (defaultFitTool() when empty)
    int jobs = 1;      ///< at most this many at once
    /** The sum of the running jobs' estimates stays below this (a job above it alone runs
     *  alone, with a warning). */
    std::uint64_t memoryBudget = 0;
    /** Passed before `batch job` (e.g. --memory-limit). */
    std::vector<std::string> globalArguments;
};

struct RunSummary {
    std::size_t alreadyDone = 0, ran = 0, done = 0, failed = 0, runningElsewhere = 0;
};

/** Runs every job that is not Done (Failed and killed ones again) as `btf batch job` child
 *  processes, with a progress bar over jobs. A job that fails or crashes is recorded (its
 *  result.json, or for a crash the signal) and the others go on. */
RunSummary runLocal(const Manifest& manifest, const std::string& resultsDir,
                    const LocalRunOptions& options);

struct SlurmOptions {
    std::string tool;  ///< the btf executable (defaultFitTool() when empty)
    std::string partition, time;
    std::vector<std::string> sbatchArguments;  ///< extra, e.g. --account=x
    std::vector<std::string> globalArguments;  ///< before `batch job`
    bool wait = false;                         ///< until every submitted task has left the queue
    double pollSeconds = 2;
};

/** Whether sbatch is on PATH. */
bool haveSlurm();

/** Submits every job that is not Done as Slurm array tasks: one `sbatch --array` per group of
 *  jobs with the same --mem (the estimate rounded up to a power of two MiB), each task one
 *  `btf batch job`. Records the submissions in RESULTS/slurm/submissions.json. Throws Error
 *  "--slurm: ..." without sbatch or when sbatch refuses. With wait, polls squeue until the tasks
 *  have left the queue. Returns how many tasks were submitted. */
std::size_t submitSlurm(const Manifest& manifest, const std::string& resultsDir,
                        const SlurmOptions& options, RunSummary* summary = nullptr);

/** Job id -> Slurm state ("PENDING", "RUNNING", ...) of this folder's submitted tasks still in
 *  squeue; empty without Slurm or submissions. */
std::map<std::string, std::string> slurmStates(const std::string& resultsDir);

/** Job id -> its last submitted Slurm array task ("123_4"; its log is RESULTS/slurm/123_4.out). */
std::map<std::string, std::string> slurmTasks(const std::string& resultsDir);

/** The leaderboard: RESULTS/report.md, results.csv, results.json and index.html (sortable
 *  tables and plots, no network needed), each written atomically. Returns the JSON text. */
std::string writeReport(const Manifest& manifest, const std::string& resultsDir);

}  // namespace osgBTF::batch
