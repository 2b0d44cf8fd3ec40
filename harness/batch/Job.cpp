// `btf batch job RESULTS ID`: one material x one method, fitted and scored in this process, the
// result written as jobs/<id>/result.json. The local pool and Slurm array tasks both run this.
#include <fcntl.h>
#include <sys/file.h>
#include <sys/resource.h>
#include <unistd.h>

#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>

#include "core/Error.h"
#include "core/FittedMaterialFile.h"
#include "core/FloatImage.h"
#include "harness/FitScore.h"
#include "harness/batch/BatchFiles.h"
#include "loaders/LoadBtf.h"
#include "materials/MethodRegistry.h"

namespace osgBTF::batch {

namespace fs = std::filesystem;

JobLock::JobLock(const std::string& lockPath, const std::string& id) {
    _fd = open(lockPath.c_str(), O_RDWR | O_CREAT | O_CLOEXEC, 0644);
    if (_fd < 0) fail(lockPath, std::string("cannot open the job's lock: ") + std::strerror(errno));
    if (flock(_fd, LOCK_EX | LOCK_NB) != 0) {
        close(_fd);
        throw Error(id + ": is running in another process (" + lockPath + " is held)");
    }
}

JobLock::~JobLock() {
    if (_fd >= 0) close(_fd);  // closing releases the flock
}

bool jobLockHeld(const std::string& lockPath) {
    const int fd = open(lockPath.c_str(), O_RDONLY | O_CLOEXEC);
    if (fd < 0) return false;
    const bool held = flock(fd, LOCK_SH | LOCK_NB) != 0 && errno == EWOULDBLOCK;
    close(fd);
    return held;
}

namespace {

double numberFrom(const nlohmann::json& json, const char* key) {
    const auto it = json.find(key);
    return it == json.end() || it->is_null() ? std::numeric_limits<double>::quiet_NaN()
                                             : it->get<double>();
}

std::string hostName() {
    char name[256] = {};
    return gethostname(name, sizeof name - 1) == 0 ? name : "";
}

}  // namespace

nlohmann::json finiteOrNull(double value) {
    return std::isfinite(value) ? nlohmann::json(value) : nlohmann::json(nullptr);
}

nlohmann::json jobResultToJson(const JobResult& r) {
    return {{"id", r.id},
            {"state", jobStateName(r.state)},
            {"failure", r.failure},
            {"avg", finiteOrNull(r.average)},
            {"rmse", finiteOrNull(r.rmse)},
            {"psnr", finiteOrNull(r.psnr)},
            {"heldout_avg", finiteOrNull(r.heldOutAverage)},
            {"heldout_rmse", finiteOrNull(r.heldOutRmse)},
            {"heldout_psnr", finiteOrNull(r.heldOutPsnr)},
            {"heldout_ssim", finiteOrNull(r.heldOutSsim)},
            {"heldout_pairs", r.heldOutPairs},
            {"error_texels", r.errorTexels},
            {"bytes_per_texel", finiteOrNull(r.bytesPerTexel)},
            {"compression_ratio", finiteOrNull(r.compressionRatio)},
            {"fit_seconds", finiteOrNull(r.fitSeconds)},
            {"heldout_fit_seconds", finiteOrNull(r.heldOutFitSeconds)},
            {"wall_seconds", finiteOrNull(r.wallSeconds)},
            {"peak_rss_bytes", r.peakRssBytes},
            {"host", r.host}};
}

JobResult jobResultFromJson(const nlohmann::json& json) {
    JobResult r;
    r.id = json.at("id").get<std::string>();
    const std::string state = json.at("state").get<std::string>();
    r.state = state == "done"     ? JobState::Done
              : state == "failed" ? JobState::Failed
                                  : JobState::Pending;
    r.failure = json.value("failure", "");
    r.average = numberFrom(json, "avg");
    r.rmse = numberFrom(json, "rmse");
    r.psnr = numberFrom(json, "psnr");
    r.heldOutAverage = numberFrom(json, "heldout_avg");
    r.heldOutRmse = numberFrom(json, "heldout_rmse");
    r.heldOutPsnr = numberFrom(json, "heldout_psnr");
    r.heldOutSsim = numberFrom(json, "heldout_ssim");
    r.heldOutPairs = json.value("heldout_pairs", std::size_t(0));
    r.errorTexels = json.value("error_texels", std::size_t(0));
    r.bytesPerTexel = numberFrom(json, "bytes_per_texel");
    r.compressionRatio = numberFrom(json, "compression_ratio");
    r.fitSeconds = numberFrom(json, "fit_seconds");
    r.heldOutFitSeconds = numberFrom(json, "heldout_fit_seconds");
    r.wallSeconds = numberFrom(json, "wall_seconds");
    r.peakRssBytes = json.value("peak_rss_bytes", std::uint64_t(0));
    r.host = json.value("host", "");
    return r;
}

JobResult runJob(const Manifest& manifest, const std::string& resultsDir, const std::string& id) {
    const BatchJob& job = manifest.job(id);
    const BatchMaterial& material = manifest.material(job.material);
    const fs::path folder = jobFolder(resultsDir, id);
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) fail(folder.string(), "cannot create: " + ec.message());
    const JobLock lock((folder / "lock").string(), id);
    // What a killed run of this job left (result.json.tmp<pid>, fit.btfmat.tmp<pid>).
    removeStaleTemporaries(folder.string(), [](const std::string&) { return true; });
    {
        // Finished meanwhile (by another run on the folder, or a task submitted twice).
        std::ifstream previous(folder / "result.json");
        if (previous) {
            try {
                const JobResult done = jobResultFromJson(nlohmann::json::parse(previous));
                if (done.state == JobState::Done) return done;
            } catch (const std::exception&) {
            }
        }
    }

    const auto start = std::chrono::steady_clock::now();
    const auto secondsSince = [](std::chrono::steady_clock::time_point from) {
        return std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
    };
    JobResult result;
    result.id = id;
    result.host = hostName();
    const double nan = std::numeric_limits<double>::quiet_NaN();
    result.heldOutAverage = result.heldOutRmse = result.heldOutPsnr = result.heldOutSsim = nan;
    result.heldOutFitSeconds = nan;
    try {
        const LoadOptions load = manifestLoadOptions(manifest.storage, manifest.decode);
        const std::unique_ptr<BtfSource> source = openBtfSource(material.input, load);
        if (source->width() != material.width || source->height() != material.height ||
            source->viewCount() != material.views || source->lightCount() != material.lights)
            fail(material.input, "is not the size the plan recorded (plan the batch again)");
        const MethodInfo& method = findMethod(job.method);
        const MethodScore score =
            fitAndScore(*source, method, FitOptions(job.options), manifest.errorTexels,
                        manifest.holdoutFraction, [&](Material& fitted) {
                            // Released into the file's arrays (no second copy), before the held-out
                            // fit.
                            saveFittedMaterial(fitted.releaseFittedMaterial(),
                                               (folder / "fit.btfmat").string());
                        });
        result.fitSeconds = score.fitSeconds;
        result.average = score.fit.error.average;
        result.rmse = score.fit.error.rmse;
        result.psnr = score.fit.error.psnr;
        result.errorTexels = score.fit.error.texelsCompared;
        result.bytesPerTexel = score.fit.memory.bytesPerTexel;
        result.compressionRatio = score.fit.compressionRatio;
        if (score.heldOut) {
            result.heldOutFitSeconds = score.heldOutFitSeconds;
            result.heldOutAverage = score.heldOut->error.average;
            result.heldOutRmse = score.heldOut->error.rmse;
            result.heldOutPsnr = score.heldOut->error.psnr;
            result.heldOutSsim = score.heldOut->ssim;
            result.heldOutPairs = score.heldOut->pairs;
        }
        result.state = JobState::Done;
    } catch (const std::exception& e) {
        result.state = JobState::Failed;
        result.failure = e.what();
    }
    result.wallSeconds = secondsSince(start);
    struct rusage usage {};
    getrusage(RUSAGE_SELF, &usage);
    result.peakRssBytes = std::uint64_t(usage.ru_maxrss) * 1024u;  // Linux: kilobytes
    writeTextAtomically((folder / "result.json").string(), jobResultToJson(result).dump(2) + "\n");
    if (result.state == JobState::Failed) throw Error(id + ": " + result.failure);
    return result;
}

}  // namespace osgBTF::batch
