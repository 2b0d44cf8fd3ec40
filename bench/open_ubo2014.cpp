// Benchmark: a UBO2014 file opened as stored (scene/OpenMaterial.h: readUbo2014, then
// the fmf material of its factors; nothing decoded) and its first rendered frame, headless.
// Goal at full size (bench_make_ubo2014: 400x400, 151x151, DFMF K = 100): open + first frame
// <= 5 s, peak resident memory <= 1.5 GB.
// Usage: bench_open_ubo2014 FILE [--frames N] [--storage half|float] [--save MATERIAL]
//   [--sequential]
//   Prints the time to read the file and build the material, to create the GL context (the two
//   side by side, on two threads, unless --sequential), and the first frame split by stage (one
//   pixel per texel through the GPU path): the textures' upload, the program's compile and link,
//   the pass itself; then the median of N more frames (each through renderMaterialImage, which
//   uploads again), and resident memory after each stage. bench/open_ubo2014.sh adds the same for
//   `btfviewer FILE --frames 1` under Xvfb. --save writes the opened material as a
//   fitted-material file instead (for bench_load_material: loading it at full size).
#include <algorithm>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <future>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <osg/GL>
#include <osg/Geode>
#include <osg/GraphicsContext>
#include <osg/Program>
#include <osg/Texture>
#include <osgViewer/Viewer>

#include "bench/ProcessUsage.h"
#include "core/Directions.h"
#include "core/Error.h"
#include "harness/MaterialImage.h"
#include "harness/headless/HeadlessRenderer.h"
#include "loaders/Ubo2014.h"
#include "materials/MaterialFiles.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"
#include "materials/fmf/Fmf.h"
#include "scene/OpenMaterial.h"

using osgBTF::bench::cpuSeconds;
using osgBTF::bench::peakResidentMiB;
using osgBTF::bench::residentMiB;

int main(int argc, char** argv) {
    std::string file, storage = "half", save;
    int frames = 5;
    bool sequential = false;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--sequential")
            sequential = true;
        else if (arg == "--frames" && i + 1 < argc)
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
                     "usage: %s FILE [--frames N>=1] [--storage half|float] [--save MATERIAL] "
                     "[--sequential]\n",
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
        const auto kind =
            storage == "float" ? osgBTF::MaterialTexture::Float : osgBTF::MaterialTexture::Half;
        // The file is read on one thread while the context is made on this one (issue 47: the
        // context's cost hides behind the read); --sequential does one after the other.
        double contextSeconds = 0, openSeconds = 0;
        auto opening = std::async(sequential ? std::launch::deferred : std::launch::async, [&] {
            const auto a = clock::now();
            osg::ref_ptr<osgBTF::Material> opened = osgBTF::openUbo2014Material(file, kind);
            openSeconds = seconds(a, clock::now());  // read after get(): the future orders it
            return opened;
        });
        if (!save.empty()) {
            osgBTF::saveMaterial(*opening.get(), save);
            std::printf("%s: saved\n", save.c_str());
            return 0;
        }
        auto makeContext = [&] {
            const auto a = clock::now();
            auto made = std::make_unique<osgBTF::HeadlessRenderer>();
            contextSeconds = seconds(a, clock::now());
            return made;
        };
        std::unique_ptr<osgBTF::HeadlessRenderer> renderer;
        osg::ref_ptr<osgBTF::Material> material;
        if (sequential) {
            material = opening.get();
            renderer = makeContext();
        } else {
            renderer = makeContext();
            material = opening.get();  // waits for the reading thread
        }
        const auto ready = clock::now();
        const double readyCpu = cpuSeconds();
        const double readyResident = residentMiB(), readyPeak = peakResidentMiB();
        const auto* fmf = dynamic_cast<const osgBTF::FmfMaterial*>(material.get());
        const glm::vec3 view = osgBTF::Direction{30, 45}.toVector();
        const glm::vec3 light = osgBTF::Direction{50, 200}.toVector();

        // The first frame by stage, on one StateSet: the textures' compileGLObjects (the upload:
        // fmf generates its layers into the driver), the program's (compile and link), then
        // the pass, drawn as renderMaterialImage draws it. glFinish closes each stage.
        osg::ref_ptr<osg::StateSet> stateSet = material->createStateSet();
        osg::GraphicsContext* gc = renderer->viewer().getCamera()->getGraphicsContext();
        gc->makeCurrent();
        osg::State& state = *gc->getState();
        const auto uploadStart = clock::now();
        const double uploadStartCpu = cpuSeconds();
        for (const auto& unit : stateSet->getTextureAttributeList())
            for (const auto& entry : unit)
                if (auto* texture = dynamic_cast<osg::Texture*>(entry.second.first.get()))
                    texture->compileGLObjects(state);
        glFinish();
        const auto uploaded = clock::now();
        const double uploadedCpu = cpuSeconds();
        const double uploadedResident = residentMiB();
        if (auto* program =
                dynamic_cast<osg::Program*>(stateSet->getAttribute(osg::StateAttribute::PROGRAM)))
            program->compileGLObjects(state);
        glFinish();
        const auto compiled = clock::now();
        const double compiledCpu = cpuSeconds();
        gc->releaseContext();
        int w = material->width(), h = material->height();
        osg::ref_ptr<osg::StateSet> lighting = new osg::StateSet;
        osgBTF::addRectifiedLighting(*lighting, view, light);
        osg::ref_ptr<osg::Geode> patch = osgBTF::rectifiedPatch();
        patch->setStateSet(lighting.get());
        osg::ref_ptr<osg::Group> root = new osg::Group;
        root->setStateSet(stateSet.get());
        root->addChild(patch.get());
        renderer->render(root.get(), osgBTF::orthoUnitSquare(w, h));
        const auto first = clock::now();
        const double firstCpu = cpuSeconds();
        const double firstResident = residentMiB(), firstPeak = peakResidentMiB();
        std::vector<double> times;
        for (int i = 0; i < frames; ++i) {
            const auto a = clock::now();
            osgBTF::renderMaterialImage(*renderer, *material, view, light);
            times.push_back(seconds(a, clock::now()));
        }
        std::sort(times.begin(), times.end());
        const osgBTF::MemoryFootprint memory = material->memory();
        std::printf(
            "%s: %s material, %dx%d texels, %zu x %zu directions, ranks %d/%d/%d, %s textures "
            "(%.1f MB)\n"
            "open (read + material): %.2f s; context: %.2f s (%s); both ready after %.2f s\n"
            "first frame (%dx%d): upload %.2f s, program %.2f s, pass %.2f s\n"
            "first image after %.2f s in all (the process's start not included)\n"
            "CPU seconds of the process (all threads; what another load on the machine does not "
            "stretch): %.2f until both are ready, upload %.2f, program %.2f, pass %.2f\n"
            "later frames (re-uploaded and re-rendered through renderMaterialImage, median of "
            "%d): %.3f s\n"
            "renderer: %s\n"
            "resident memory: %.0f MiB at the start, %.0f MiB with the material and the context "
            "(peak %.0f), %.0f MiB after the upload, %.0f MiB after the first frame (peak %.0f)\n"
            "peak resident memory: %.0f MiB\n",
            file.c_str(), material->methodName().c_str(), material->width(), material->height(),
            material->views().size(), material->lights().size(),
            fmf ? fmf->factors().components(0) : 0, fmf ? fmf->factors().components(1) : 0,
            fmf ? fmf->factors().components(2) : 0, storage.c_str(),
            double(memory.totalBytes) / 1e6, openSeconds, contextSeconds,
            sequential ? "one after the other" : "the open on another thread meanwhile",
            seconds(start, ready), w, h, seconds(uploadStart, uploaded),
            seconds(uploaded, compiled), seconds(compiled, first), seconds(start, first), readyCpu,
            uploadedCpu - uploadStartCpu, compiledCpu - uploadedCpu, firstCpu - compiledCpu, frames,
            times[times.size() / 2], renderer->glRenderer().c_str(), startResident, readyResident,
            readyPeak, uploadedResident, firstResident, firstPeak, peakResidentMiB());
    } catch (const osgBTF::Error& e) {
        std::fprintf(stderr, "bench_open_ubo2014: %s\n", e.what());
        return 1;
    }
    return 0;
}
