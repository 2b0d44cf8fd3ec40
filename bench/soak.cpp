// Soak: a headless viewer renders fitted materials for 10,000 frames,
// switching every node's material every 10 frames and reloading the scene from its files (through
// osgDB) every 500, and samples the RSS and the GL objects alive in the context. Exits 1 when
// anything grew after the warm-up beyond its tolerance (README "Reliability"), 2 on bad usage.
// Usage: bench_soak [--frames N] [--size TEXELS] [--warmup FRAMES] [--rss-tolerance MIB]
//   The materials (lambert, pca, laf) are fitted to the built-in sample of TEXELS x TEXELS texels
//   (default 32) and saved into a temporary folder first. OSGBTF_HEADLESS picks the back end.
#include <unistd.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

#include "bench/ProcessUsage.h"
#include "bench/SampleMaterials.h"
#include "core/Error.h"
#include "harness/Soak.h"
#include "harness/headless/HeadlessRenderer.h"

namespace fs = std::filesystem;

using osgBTF::bench::cpuSeconds;

int main(int argc, char** argv) {
    osgBTF::SoakOptions options;
    int texels = 32;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const bool hasValue = i + 1 < argc;
        if (arg == "--frames" && hasValue)
            options.frames = std::atoi(argv[++i]);
        else if (arg == "--size" && hasValue)
            texels = std::atoi(argv[++i]);
        else if (arg == "--warmup" && hasValue)
            options.warmupFrames = std::atoi(argv[++i]);
        else if (arg == "--rss-tolerance" && hasValue)
            options.rssToleranceMiB = std::atof(argv[++i]);
        else {
            std::cerr << "usage: bench_soak [--frames N] [--size TEXELS] [--warmup FRAMES] "
                         "[--rss-tolerance MIB]\n";
            return 2;
        }
    }
    const fs::path folder = fs::temp_directory_path() / ("osgbtf-soak-" + std::to_string(getpid()));
    try {
        osgBTF::bench::useBuildPlugins();
        const std::vector<std::string> files = osgBTF::bench::writeSampleMaterials(folder, texels);
        osgBTF::HeadlessRenderer renderer;
        std::cout << "GL_RENDERER: " << renderer.glRenderer() << "\n";
        const double cpu0 = cpuSeconds();
        const osgBTF::SoakResult result = osgBTF::runSoak(renderer, files, options);
        std::cout << osgBTF::formatSoak(result) << "CPU " << cpuSeconds() - cpu0 << " s\n";
        fs::remove_all(folder);
        return result.growth.empty() ? 0 : 1;
    } catch (const std::exception& e) {
        std::error_code ignored;
        fs::remove_all(folder, ignored);
        std::cerr << "bench_soak: " << e.what() << "\n";
        return 2;
    }
}
