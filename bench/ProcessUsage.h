// What a benchmark reports about its own process (getrusage): CPU time and peak resident memory.
#pragma once

#include <sys/resource.h>
#include <unistd.h>

#include <cstdio>

namespace osgBTF::bench {

/** User + system CPU seconds of this process so far. */
inline double cpuSeconds() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_utime.tv_sec + usage.ru_stime.tv_sec) +
           1e-6 * double(usage.ru_utime.tv_usec + usage.ru_stime.tv_usec);
}

/** Peak resident memory of this process so far, in GiB. */
inline double peakResidentGiB() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return double(usage.ru_maxrss) / (1024.0 * 1024.0);  // ru_maxrss is in KiB on Linux
}

/** Peak resident memory of this process so far, in MiB. */
inline double peakResidentMiB() {
    return peakResidentGiB() * 1024.0;
}

/** Starts the peak of resident memory again from the present (Linux: "5" to
 *  /proc/self/clear_refs); peakResidentSinceResetMiB() reads it. False where unsupported. */
inline bool resetPeakResident() {
    std::FILE* f = std::fopen("/proc/self/clear_refs", "w");
    if (!f) return false;
    const bool written = std::fputs("5", f) >= 0;
    return std::fclose(f) == 0 && written;
}

/** Peak resident memory since the last resetPeakResident() (or the start), in MiB (VmHWM of
 *  /proc/self/status; 0 where unreadable). */
inline double peakResidentSinceResetMiB() {
    double kib = 0;
    if (std::FILE* f = std::fopen("/proc/self/status", "r")) {
        char line[256];
        while (std::fgets(line, sizeof line, f))
            if (std::sscanf(line, "VmHWM: %lf kB", &kib) == 1) break;
        std::fclose(f);
    }
    return kib / 1024.0;
}

/** Resident memory of this process now, in MiB (/proc/self/statm; 0 where unreadable). */
inline double residentMiB() {
    long pages = 0, resident = 0;
    if (std::FILE* f = std::fopen("/proc/self/statm", "r")) {
        if (std::fscanf(f, "%ld %ld", &pages, &resident) != 2) resident = 0;
        std::fclose(f);
    }
    return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

}  // namespace osgBTF::bench
