// Benchmark: a UBO2014 file opened as stored (scene/OpenMaterial.h: readUbo2014, then
// the fmf material of its factors; nothing decoded) and its first rendered frame, headless.
// Goal at full size (bench_make_ubo2014: 400x400, 151x151, DFMF K = 100): open + first frame
// <= 5 s, peak resident memory <= 1.5 GB.
// Usage: bench_open_ubo2014 FILE [--frames N] [--storage half|float] [--save MATERIAL]
//   Prints the time to read the file, to build the material, to render the first frame (one
//   pixel per texel through the GPU path: texture upload, shader compile, one pass) and the median
//   of N more frames, and the process's peak resident memory. bench/open_ubo2014.sh adds the
//   same for `btfviewer FILE --frames 1` under Xvfb. --save writes the opened material as a
//   fitted-material file instead (for bench_load_material: loading it at full size).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "bench/ProcessUsage.h"
#include "core/Directions.h"
#include "core/Error.h"
#include "harness/MaterialImage.h"
#include "harness/headless/HeadlessRenderer.h"
#include "loaders/Ubo2014.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/fmf/Fmf.h"
#include "scene/OpenMaterial.h"

using osgBTF::bench::peakResidentMiB;
using osgBTF::bench::residentMiB;

int main(int argc, char** argv) {
    std::string file, storage = "half", save;
    int frames = 5;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--frames" && i + 1 < argc)
            frames = std::atoi(argv[++i]);
        else if (arg == "--storage" && i + 1 < argc)
            storage = argv[++i];
        else if (arg == "--save" && i + 1 < argc)
            save = argv[++i];
        else if (file.empty() && arg[0] != '-')
            file = arg;
        else
            file.clear(), i = argc;
    }
    if (file.empty() || frames < 1 || (storage != "half" && storage != "float")) {
        std::fprintf(stderr,
                     "usage: %s FILE [--frames N>=1] [--storage half|float] [--save MATERIAL]\n",
                     argv[0]);
        return 2;
    }
    try {
        using clock = std::chrono::steady_clock;
        auto seconds = [](clock::time_point a, clock::time_point b) {
            return std::chrono::duration<double>(b - a).count();
        };
        const double startResident = residentMiB();
        const auto start = clock::now();
        osg::ref_ptr<osgBTF::Material> material =
            osgBTF::openUbo2014Material(file, storage == "float" ? osgBTF::MaterialTexture::Float
                                                                 : osgBTF::MaterialTexture::Half);
        const auto opened = clock::now();
        if (!save.empty()) {
            osgBTF::saveMaterial(*material, save);
            std::printf("%s: saved\n", save.c_str());
            return 0;
        }
        const double openedResident = residentMiB(), openedPeak = peakResidentMiB();
        const auto* fmf = dynamic_cast<const osgBTF::FmfMaterial*>(material.get());
        osgBTF::HeadlessRenderer renderer;
        const auto context = clock::now();
        const double contextResident = residentMiB();
        const glm::vec3 view = osgBTF::Direction{30, 45}.toVector();
        const glm::vec3 light = osgBTF::Direction{50, 200}.toVector();
        osgBTF::renderMaterialImage(renderer, *material, view, light);
        const auto first = clock::now();
        const double firstResident = residentMiB(), firstPeak = peakResidentMiB();
        std::vector<double> times;
        for (int i = 0; i < frames; ++i) {
            const auto a = clock::now();
            osgBTF::renderMaterialImage(renderer, *material, view, light);
            times.push_back(seconds(a, clock::now()));
        }
        std::sort(times.begin(), times.end());
        const osgBTF::MemoryFootprint memory = material->memory();
        std::printf(
            "%s: %s material, %dx%d texels, %zu x %zu directions, ranks %d/%d/%d, %s textures "
            "(%.1f MB)\n"
            "open (read + material): %.2f s; context: %.2f s; first frame (%dx%d, upload + "
            "compile + pass): %.2f s; open + first frame: %.2f s (context excluded), %.2f s in "
            "all\n"
            "later frames (re-rendered through renderMaterialImage, median of %d): %.3f s\n"
            "renderer: %s\n"
            "resident memory: %.0f MiB at the start, %.0f MiB after open (peak %.0f), %.0f MiB "
            "with the context, %.0f MiB "
            "after the first frame (peak %.0f)\npeak resident memory: %.0f MiB\n",
            file.c_str(), material->methodName().c_str(), material->width(), material->height(),
            material->views().size(), material->lights().size(),
            fmf ? fmf->factors().components(0) : 0, fmf ? fmf->factors().components(1) : 0,
            fmf ? fmf->factors().components(2) : 0, storage.c_str(),
            double(memory.totalBytes) / 1e6, seconds(start, opened), seconds(opened, context),
            material->width(), material->height(), seconds(context, first),
            seconds(start, opened) + seconds(context, first), seconds(start, first), frames,
            times[times.size() / 2], renderer.glRenderer().c_str(), startResident, openedResident,
            openedPeak, contextResident, firstResident, firstPeak, peakResidentMiB());
    } catch (const osgBTF::Error& e) {
        std::fprintf(stderr, "bench_open_ubo2014: %s\n", e.what());
        return 1;
    }
    return 0;
}
