// Benchmark: PCA fit time (issue 4 goal: 16 components on a 256x256x81x81 BTF in <= 20 s) and
// peak memory.
// Usage: bench_fit_pca [--size N] [--components C] [--storage unorm8|half|float] [--error]
//   Generates the built-in sample (makeSampleBtf) of NxN texels in half storage (2.6 GB at 256),
//   fits PCA, prints the fit time, the memory footprint and the process's peak resident memory;
//   --error also computes the per-texel error over all 81 x 81 measured pairs.

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>

#include "bench/ProcessUsage.h"
#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/pca/Pca.h"

using osgBTF::bench::cpuSeconds;
using osgBTF::bench::peakResidentGiB;

int main(int argc, char** argv) {
    int size = 256, components = 16;
    std::string storage = "unorm8";
    bool error = false;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--size" && i + 1 < argc)
            size = std::atoi(argv[++i]);
        else if (arg == "--components" && i + 1 < argc)
            components = std::atoi(argv[++i]);
        else if (arg == "--storage" && i + 1 < argc)
            storage = argv[++i];
        else if (arg == "--error")
            error = true;
        else {
            std::fprintf(stderr,
                         "usage: %s [--size N] [--components C] [--storage unorm8|half|float] "
                         "[--error]\n",
                         argv[0]);
            return 2;
        }
    }
    try {
        using clock = std::chrono::steady_clock;
        osgBTF::SampleOptions sample;
        sample.width = sample.height = size;
        sample.storage = osgBTF::Storage::Half;
        auto t0 = clock::now();
        const osgBTF::MeasuredBtf btf = osgBTF::makeSampleBtf(sample);
        const double generate = std::chrono::duration<double>(clock::now() - t0).count();
        std::printf("sample %dx%d x 81 x 81 (half, %s) generated in %.1f s, peak RSS %.2f GiB\n",
                    size, size, osgBTF::formatBytes(btf.memoryBytes()).c_str(), generate,
                    peakResidentGiB());

        osgBTF::FitOptions options;
        options.set("components", std::to_string(components));
        options.set("storage", storage);
        t0 = clock::now();
        const double cpu0 = cpuSeconds();
        osg::ref_ptr<osgBTF::PcaMaterial> m = osgBTF::PcaMaterial::fit(btf, options);
        const double fit = std::chrono::duration<double>(clock::now() - t0).count();
        const double fitCpu = cpuSeconds() - cpu0;
        const osgBTF::MemoryFootprint memory = m->memory();
        const osgBTF::PcaMaterial::MemoryBreakdown b = m->memoryBreakdown();
        std::printf(
            "pca fit: %d components, %s storage: %.2f s wall, %.2f s CPU (goal <= 20 s), energy "
            "kept "
            "%s, peak RSS "
            "%.2f GiB\n"
            "memory: per texel %.1f values / %.1f bytes (Eigen-Textures), shared weights %.2f "
            "values / %.2f bytes per texel; total %.1f values / %.1f bytes per texel, %s\n",
            components, storage.c_str(), fit, fitCpu, m->fitInfo.at("energy").c_str(),
            peakResidentGiB(), b.perTexelValues, b.perTexelBytes, b.sharedValues, b.sharedBytes,
            memory.valuesPerTexel, memory.bytesPerTexel,
            osgBTF::formatBytes(memory.totalBytes).c_str());
        if (error) {
            t0 = clock::now();
            const osgBTF::ErrorSummary e = osgBTF::computeError(
                btf, [&](std::size_t t, float* out) { m->evaluateMeasured(t, out); });
            std::printf("error: avg %.5f min %.5f max %.5f rmse %.5f psnr %.2f dB (%.1f s)\n",
                        e.average, e.minimum, e.maximum, e.rmse, e.psnr,
                        std::chrono::duration<double>(clock::now() - t0).count());
        }
    } catch (const osgBTF::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
