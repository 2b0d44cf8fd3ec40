// osgBTF batch, internal: the per-job lock and result file that every step shares.
#pragma once

#include <string>

#include <nlohmann/json.hpp>

#include "harness/batch/Batch.h"
#include "loaders/LoadOptions.h"

namespace osgBTF::batch {

/** An exclusive flock on jobs/<id>/lock for as long as it lives. The kernel drops it when the
 *  process dies (even by SIGKILL, or with its Slurm task), so a killed job is never "running". */
class JobLock {
public:
    /** Throws Error "<id>: is running in another process (LOCK is held)" when held. */
    JobLock(const std::string& lockPath, const std::string& id);
    ~JobLock();
    JobLock(const JobLock&) = delete;
    JobLock& operator=(const JobLock&) = delete;

private:
    int _fd = -1;
};

/** Whether some process holds the lock file's flock (false when it does not exist). */
bool jobLockHeld(const std::string& lockPath);

nlohmann::json jobResultToJson(const JobResult& result);
/** JSON has no NaN or infinity: null stands for "not measured" (and an exact fit's PSNR). */
nlohmann::json finiteOrNull(double value);
/** Now, UTC, ISO 8601. */
std::string utcNow();
/** The load options a manifest names (`btf fit`'s --storage and --decode values). */
LoadOptions manifestLoadOptions(const std::string& storage, const std::string& decode);
JobResult jobResultFromJson(const nlohmann::json& json);

}  // namespace osgBTF::batch
