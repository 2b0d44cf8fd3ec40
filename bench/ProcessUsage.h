// What a benchmark reports about its own process (getrusage): CPU time and peak resident memory.
#pragma once

#include <sys/resource.h>

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

}  // namespace osgBTF::bench
