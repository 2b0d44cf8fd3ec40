// Benchmark: LPCA fit time and peak memory on a Bonn-81 BTF (Meseth et al. 2003: 1-2 hours for
// 32x8). Usage: bench_fit_lpca [--size N] [--options "clusters=32 components=8"] [--float]
// [--error]
//   Generates the built-in sample at N x N texels (default 256, half storage unless --float),
//   fits "lpca" with the options, prints fit time, iterations, peak resident memory, memory per
//   texel and, with --error, the per-texel error of Meseth et al. 2003 section 4.1.
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <string>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "core/Progress.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/lpca/Lpca.h"

namespace {
double peakMiB() {
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    return usage.ru_maxrss / 1024.0;  // Linux: KiB
}
}  // namespace

int main(int argc, char** argv) {
    int size = 256;
    std::string options = "clusters=32 components=8";
    bool useFloat = false, error = false;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--size" && i + 1 < argc)
            size = std::stoi(argv[++i]);
        else if (arg == "--options" && i + 1 < argc)
            options = argv[++i];
        else if (arg == "--float")
            useFloat = true;
        else if (arg == "--error")
            error = true;
        else {
            std::fprintf(stderr, "usage: %s [--size N] [--options TEXT] [--float] [--error]\n",
                         argv[0]);
            return 2;
        }
    }
    try {
        osgBTF::Progress::setEnabled(true);
        auto start = std::chrono::steady_clock::now();
        osgBTF::SampleOptions sample;
        sample.width = sample.height = size;
        sample.storage = useFloat ? osgBTF::Storage::Float : osgBTF::Storage::Half;
        const osgBTF::MeasuredBtf btf = osgBTF::makeSampleBtf(sample);
        const double generate =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const double afterData = peakMiB();
        start = std::chrono::steady_clock::now();
        osg::ref_ptr<osgBTF::LpcaMaterial> m =
            osgBTF::LpcaMaterial::fit(btf, osgBTF::FitOptions::parse(options));
        const double fit =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        const osgBTF::MemoryFootprint memory = m->memory();
        std::printf("data: %dx%d Bonn 81x81 (%s, %s), generated in %.1f s, peak RSS %.0f MiB\n",
                    size, size, useFloat ? "float" : "half",
                    osgBTF::formatBytes(btf.memoryBytes()).c_str(), generate, afterData);
        std::printf(
            "lpca %s: fit %.1f s (%s iterations on %s training texels), peak RSS %.0f MiB "
            "(fit overhead %.0f MiB)\n",
            options.c_str(), fit, m->fitInfo["iterations"].c_str(),
            m->fitInfo["training_texels"].c_str(), peakMiB(), peakMiB() - afterData);
        std::printf("memory: %.2f values, %.2f bytes per texel\n", memory.valuesPerTexel,
                    memory.bytesPerTexel);
        if (error) {
            const osgBTF::ErrorSummary e = osgBTF::computeError(
                btf, [&](std::size_t t, float* out) { m->evaluateMeasured(t, out); });
            std::printf("error: avg %.4f min %.4f max %.4f, RMSE %.4f, PSNR %.1f dB\n", e.average,
                        e.minimum, e.maximum, e.rmse, e.psnr);
        }
    } catch (const osgBTF::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
