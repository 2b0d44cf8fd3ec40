// Benchmark: fit time, error and memory of a method on the built-in sample, and optionally the
// time of one rendering pass at 1024 x 1024 (headless).
// Usage: bench_fit_analytic [--method laf] [--size 64] [--options "lobes=2"] [--gpu]
//                           [--frames 20] [--lights 1] [--save FILE]
//   Works for any registered method (laf, slaf, rf, ...). Prints one Markdown-ready line per
//   figure.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "core/Progress.h"
#include "harness/PassCost.h"
#include "harness/headless/HeadlessRenderer.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"

namespace {

void timeGpuPass(const osgBTF::Material& material, int frames, int lights) {
    osgBTF::HeadlessRenderer renderer;
    osgBTF::PassSettings settings;
    settings.width = settings.height = 1024;
    settings.frames = frames;
    settings.lights = lights;
    settings.textureScale = 16;  // every pixel fetches different texels, as on a real model
    const osgBTF::PassTarget target = osgBTF::passTarget("rgba16f");
    const osgBTF::Calibration calibration = osgBTF::runCalibration(renderer, settings, target);
    const osgBTF::MethodPass t =
        osgBTF::timeMethodPass(renderer, material, settings, calibration, -1);
    std::printf(
        "| gpu pass 1024x1024 %s (%s, %d light%s) | %.2f ms, empty pass %.2f ms, difference %.2f "
        "ms (%s, median of %d frames) |\n",
        target.name.c_str(), renderer.glRenderer().c_str(), lights, lights == 1 ? "" : "s",
        t.pass.ms, t.emptyMs, t.shadingMs, t.pass.clock.c_str(), frames);
}

}  // namespace

int main(int argc, char** argv) {
    std::string method = "laf", options, save;
    int size = 64, frames = 20, lights = 1;
    bool gpu = false;
    for (int i = 1; i < argc; ++i) {
        const std::string a = argv[i];
        auto next = [&]() -> std::string {
            if (i + 1 >= argc) {
                std::cerr << a << " needs a value\n";
                std::exit(2);
            }
            return argv[++i];
        };
        if (a == "--method")
            method = next();
        else if (a == "--size")
            size = std::atoi(next().c_str());
        else if (a == "--options")
            options = next();
        else if (a == "--save")
            save = next();
        else if (a == "--frames")
            frames = std::atoi(next().c_str());
        else if (a == "--lights")
            lights = std::atoi(next().c_str());
        else if (a == "--gpu")
            gpu = true;
        else {
            std::cerr << "usage: bench_fit_analytic [--method NAME] [--size N] [--options \"k=v\"] "
                         "[--gpu] [--frames N] [--lights N] [--save FILE]\n";
            return 2;
        }
    }
    try {
        osgBTF::Progress::setEnabled(true);
        osgBTF::SampleOptions sample;
        sample.width = sample.height = size;
        auto t0 = std::chrono::steady_clock::now();
        const osgBTF::MeasuredBtf btf = osgBTF::makeSampleBtf(sample);
        const double sampleSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const osgBTF::MethodInfo& info = osgBTF::findMethod(method);
        t0 = std::chrono::steady_clock::now();
        osg::ref_ptr<osgBTF::Material> m = info.fit(btf, osgBTF::FitOptions::parse(options));
        const double fitSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
        const osgBTF::ErrorSummary e = osgBTF::computeError(
            btf, [&](std::size_t t, float* out) { m->evaluateMeasured(t, out); });
        const osgBTF::MemoryFootprint mem = m->memory();
        std::printf("| method | %s (%s) |\n| sample | %dx%d, Bonn 81x81 (made in %.1f s) |\n",
                    method.c_str(), options.empty() ? "defaults" : options.c_str(), size, size,
                    sampleSeconds);
        std::printf("| fit time | %.1f s (%.2f ms per texel, wall) |\n", fitSeconds,
                    1000.0 * fitSeconds / double(btf.texelCount()));
        std::printf("| error avg / min / max | %.4f / %.4f / %.4f |\n", e.average, e.minimum,
                    e.maximum);
        std::printf("| rmse / psnr | %.4f / %.2f dB |\n", e.rmse, e.psnr);
        std::printf("| non-finite values | %zu |\n", e.nonFiniteValues);
        std::printf("| memory | %.1f values, %.1f bytes per texel |\n", mem.valuesPerTexel,
                    mem.bytesPerTexel);
        for (const auto& [key, value] : m->fitInfo)
            std::printf("| fit.%s | %s |\n", key.c_str(), value.c_str());
        if (!save.empty()) osgBTF::saveMaterial(*m, save);
        if (gpu) timeGpuPass(*m, frames, lights);
    } catch (const osgBTF::Error& e) {
        std::cerr << "bench_fit_analytic: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
