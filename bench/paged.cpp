// Paged soak: a headless viewer flies over a grid of osg::PagedLOD tiles (harness/PagedScene.h),
// each a .osgt file holding a MaterialNode, loaded by the DatabasePager with its compile ahead
// and removed once out of range, for ten minutes by default; it samples the RSS, the GL objects
// alive in the context, the tiles loaded and the frame times. Exits 1 when memory or GL objects
// grew after the warm-up (one pass over the grid) beyond their tolerance, 2 on bad usage.
// Usage: bench_paged [--seconds S] [--columns C] [--rows R] [--speed TILES_PER_S] [--size PX]
//                    [--texels N] [--keep TILES]
//   Defaults: 600 s over 40 x 25 = 1,000 tiles at 4 tiles/s, a 256 x 256 view; the tiles'
//   materials (lambert, pca, laf, in turn) are fitted to the built-in sample of N x N texels
//   (default 32); --keep: tiles the pager keeps loaded out of range (default 16).
//   OSGBTF_HEADLESS picks the back end.
#include <unistd.h>

#include <cstdlib>
#include <filesystem>
#include <iostream>
#include <string>

#include "bench/ProcessUsage.h"
#include "bench/SampleMaterials.h"
#include "harness/PagedScene.h"
#include "harness/headless/HeadlessRenderer.h"

namespace fs = std::filesystem;

int main(int argc, char** argv) {
    osgBTF::PagedSoakOptions options;
    int texels = 32;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        const bool hasValue = i + 1 < argc;
        if (arg == "--seconds" && hasValue)
            options.seconds = std::atof(argv[++i]);
        else if (arg == "--columns" && hasValue)
            options.grid.columns = std::atoi(argv[++i]);
        else if (arg == "--rows" && hasValue)
            options.grid.rows = std::atoi(argv[++i]);
        else if (arg == "--speed" && hasValue)
            options.tilesPerSecond = std::atof(argv[++i]);
        else if (arg == "--size" && hasValue)
            options.size = std::atoi(argv[++i]);
        else if (arg == "--texels" && hasValue)
            texels = std::atoi(argv[++i]);
        else if (arg == "--keep" && hasValue)
            options.keepTiles = unsigned(std::atoi(argv[++i]));
        else {
            std::cerr << "usage: bench_paged [--seconds S] [--columns C] [--rows R] [--speed "
                         "TILES_PER_S] [--size PX] [--texels N] [--keep TILES]\n";
            return 2;
        }
    }
    options.sampleSeconds = std::max(1.0, options.seconds / 60.0);
    const fs::path folder =
        fs::temp_directory_path() / ("osgbtf-paged-" + std::to_string(getpid()));
    try {
        osgBTF::bench::useBuildPlugins();
        const std::vector<std::string> files = osgBTF::bench::writeSampleMaterials(folder, texels);
        const std::string tiles = (folder / "tiles").string();
        osgBTF::writePagedTiles(tiles, files, options.grid);
        osgBTF::HeadlessRenderer renderer;
        std::cout << "GL_RENDERER: " << renderer.glRenderer() << "\n"
                  << options.grid.columns * options.grid.rows << " tiles, "
                  << options.tilesPerSecond << " tiles/s, " << options.seconds << " s\n";
        const double cpu0 = osgBTF::bench::cpuSeconds();
        const osgBTF::PagedSoakResult result = osgBTF::runPagedSoak(renderer, tiles, options);
        std::cout << osgBTF::formatPagedSoak(result) << "CPU " << osgBTF::bench::cpuSeconds() - cpu0
                  << " s, peak RSS " << osgBTF::bench::peakResidentMiB() << " MiB\n";
        fs::remove_all(folder);
        return result.growth.empty() ? 0 : 1;
    } catch (const std::exception& e) {
        std::error_code ignored;
        fs::remove_all(folder, ignored);
        std::cerr << "bench_paged: " << e.what() << "\n";
        return 2;
    }
}
