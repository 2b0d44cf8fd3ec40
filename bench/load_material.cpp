// Peak host memory of loading fitted materials, against their size: for each FILE, a child
// process (so that each peak is its own) reads the file with loadMaterial and reports its
// resident memory before (libraries loaded, allocator trimmed), its peak while loading, the
// material's texture bytes at their stored precision (Material::memory), and the ratio of the
// growth to those bytes. Issue goal: at most 1.1 (no copy of the textures held twice).
// Usage: bench_load_material FILE...   (e.g. the fits of bench/load_materials.sh)
#include <malloc.h>
#include <sys/resource.h>
#include <sys/wait.h>
#include <unistd.h>

#include <cstdio>
#include <string>

#include "bench/ProcessUsage.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"

namespace {

int measure(const std::string& file) {
    malloc_trim(0);
    const double before = osgBTF::bench::residentMiB();
    osg::ref_ptr<osgBTF::Material> material = osgBTF::loadMaterial(file);
    const double peak = osgBTF::bench::peakResidentMiB();
    const double held = osgBTF::bench::residentMiB();
    const double bytes = double(material->memory().totalBytes) / (1024.0 * 1024.0);
    std::printf("%-10s %10.1f %10.1f %10.1f %10.1f %8.2f %8.2f  %s\n",
                material->methodName().c_str(), bytes, before, peak, held,
                (peak - before) / bytes, (held - before) / bytes, file.c_str());
    std::fflush(stdout);  // the child ends with _Exit, which flushes nothing
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 2) {
        std::fprintf(stderr, "usage: bench_load_material FILE...\n");
        return 2;
    }
    std::printf("%-10s %10s %10s %10s %10s %8s %8s  %s\n", "method", "size MiB", "before",
                "peak", "after", "peak/sz", "held/sz", "file");
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
