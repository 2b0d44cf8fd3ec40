// osgBTF harness: fit one method in a child process (`btf fit`), so that a crash, an abort or an
// exhausted memory limit in one method's fit is contained, and its peak memory can be measured.
#pragma once

#include <sys/types.h>

#include <cstdint>
#include <map>
#include <string>
#include <vector>

namespace osgBTF {

/** One `btf fit` child process of the comparison: the base level of INPUT (`--no-mipmap`). */
struct FitJob {
    std::string tool;                            ///< the `btf` executable
    std::string input;                           ///< measured BTF
    std::string method;                          ///< registry name
    std::map<std::string, std::string> options;  ///< passed as --set KEY=VALUE
    /** Extra arguments after `fit` (load options such as --storage half). */
    std::vector<std::string> extraArguments;
    /** Global arguments before `fit` (e.g. --memory-limit 8G). */
    std::vector<std::string> globalArguments;
    std::string output;  ///< fitted material file to write (.exr)
    std::string log;     ///< the child's stdout and stderr go here
};

struct FitProcessResult {
    bool ok = false;
    std::string message;     ///< why it failed: the child's "btf: error: ..." text, or the signal
    double wallSeconds = 0;  ///< the whole child: start, load, fit, save, error summary
    std::uint64_t peakRssBytes = 0;  ///< wait4() rusage ru_maxrss of the child
    bool reused = false;             ///< taken from an earlier run instead (see reuseFit)
};

/** Runs `tool [global] --no-progress fit INPUT -m METHOD --set k=v ... [extra] -o OUTPUT`, waits
 *  for it with wait4() and reports its exit, wall time and peak resident memory. Never throws for
 *  a failing child; throws Error only if the child cannot be started (tool missing). */
FitProcessResult runFitProcess(const FitJob& job);

/** Starts args[0] with args, stdout and stderr into `log`, stdin from /dev/null and
 *  OSGBTF_PARENT_PID naming this process (the child dies with it). Throws Error when args[0] is
 *  not executable or cannot start. */
pid_t spawnChild(const std::vector<std::string>& args, const std::string& log);

/** Why a child that wait4() reported with `status` failed: its own "btf: error: ..." line in
 *  `logPath` (else its last line), after "crashed (signal N, Name)" for a signal. */
std::string childFailure(int status, const std::string& logPath);

/** The record kept beside a fitted file (<output>.json) so that a later run can reuse it. */
void writeFitRecord(const FitJob& job, const FitProcessResult& result, const std::string& path);

/** True when `previousOutput` and its record `previousOutput + ".json"` exist, the file is newer
 *  than the input, and the record names the same input, method, options and extra arguments.
 *  Then `result` receives the recorded time and memory with reused = true. */
bool canReuseFit(const FitJob& job, const std::string& previousOutput, FitProcessResult& result);

/** The `btf` executable next to the running one (/proc/self/exe's folder), or the running one if
 *  it is itself named btf. */
std::string defaultFitTool();

}  // namespace osgBTF
