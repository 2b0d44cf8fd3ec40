// Peak host memory of loading fitted materials, against their size: for each FILE, a child
// process (so that each peak is its own) reads the file with loadMaterial twice and reports, for
// each load, its resident memory before (libraries loaded, allocator trimmed), its peak while
// loading, the material's texture bytes at their stored precision (Material::memory), and the
// ratio of the growth to those bytes. The first load also pays what a process sets up once
// (OpenEXR's and TBB's thread pools, code paged in: a few MiB to tens); the second, after the
// first material is released, is the cost of one more material. Issue goal: at most 1.1 (no copy
// of the textures held twice).
// Usage: bench_load_material FILE...   (e.g. the fits of bench/load_materials.sh)
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <algorithm>
#include <cstdio>
#include <string>

#include "bench/ProcessUsage.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"

namespace {

/** One load of `file`: a row of the table. */
void measureLoad(const std::string& file, const char* which) {
    {
        // Nothing of an earlier load stays in the allocator's free lists.
        malloc_trim(0);
    }
    osgBTF::bench::resetPeakResident();
    const double before = osgBTF::bench::residentMiB();
    osg::ref_ptr<osgBTF::Material> material = osgBTF::loadMaterial(file);
    const double peak = osgBTF::bench::peakResidentSinceResetMiB();
    malloc_trim(0);  // what the material holds, not what the allocator kept of the loading
    const double held = osgBTF::bench::residentMiB();
    const double bytes = double(material->memory().totalBytes) / (1024.0 * 1024.0);
    std::printf("%-10s %-6s %10.1f %10.1f %10.1f %10.1f %8.2f %8.2f %9.2f  %s\n",
                material->methodName().c_str(), which, bytes, before, peak, held,
                (peak - before) / bytes, (held - before) / bytes,
                (peak - before) / std::max(held - before, 1e-3), file.c_str());
    std::fflush(stdout);  // the child ends with _Exit, which flushes nothing
}

int measure(const std::string& file) {
    measureLoad(file, "first");
    measureLoad(file, "again");
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: bench_load_material FILE...\n");
        return 2;
    }
    std::printf("%-10s %-6s %10s %10s %10s %10s %8s %8s %9s  %s\n", "method", "load", "size MiB",
                "before", "peak", "after", "peak/sz", "held/sz", "peak/held", "file");
    std::fflush(stdout);
    int failures = 0;
    for (int i = 1; i < argc; ++i) {
        const pid_t child = fork();
        if (child == 0) {
            try {
                std::_Exit(measure(argv[i]));
            } catch (const std::exception& e) {
                std::fprintf(stderr, "bench_load_material: %s\n", e.what());
                std::_Exit(1);
            }
        }
        int status = 0;
        waitpid(child, &status, 0);
        failures += !(WIFEXITED(status) && WEXITSTATUS(status) == 0);
    }
    return failures == 0 ? 0 : 1;
}
