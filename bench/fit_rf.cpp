// Benchmark: RF fit time and error on the built-in sample.
// Usage: bench_fit_rf [--size N] [--lobes K] [--options "key=value ..."] [--out FILE]
//                     [--pass-time VIEWPORT]
//   Generates makeSampleBtf at N x N (default 64; half storage from 128 up, to halve the memory),
//   fits "rf" and prints fit time, error avg/min/max, RMSE/PSNR and memory per texel. With
//   --pass-time, also the time of one VIEWPORT x VIEWPORT pass of the fitted material through
//   the headless renderer (OSGBTF_HEADLESS picks EGL or OSMesa), one directional light.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include <osg/Uniform>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "core/Progress.h"
#include "harness/headless/HeadlessRenderer.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodOptions.h"
#include "materials/rf/Rf.h"

int main(int argc, char** argv) {
    using namespace osgBTF;
    int size = 64, viewport = 0;
    std::string optionText, out;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--size" && i + 1 < argc) {
            size = std::atoi(argv[++i]);
        } else if (arg == "--lobes" && i + 1 < argc) {
            optionText += std::string(" lobes=") + argv[++i];
        } else if (arg == "--options" && i + 1 < argc) {
            optionText += std::string(" ") + argv[++i];
        } else if (arg == "--pass-time" && i + 1 < argc) {
            viewport = std::atoi(argv[++i]);
        } else if (arg == "--out" && i + 1 < argc) {
            out = argv[++i];
        } else {
            std::fprintf(stderr,
                         "usage: bench_fit_rf [--size N] [--lobes K] [--options TEXT] [--out FILE] "
                         "[--pass-time VIEWPORT]\n");
            return 2;
        }
    }
    try {
        Progress::setEnabled(true);
        SampleOptions sampleOptions;
        sampleOptions.width = sampleOptions.height = size;
        sampleOptions.storage = size >= 128 ? Storage::Half : Storage::Float;
        auto start = std::chrono::steady_clock::now();
        const MeasuredBtf btf = makeSampleBtf(sampleOptions);
        const double sampleSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

        start = std::chrono::steady_clock::now();
        osg::ref_ptr<RfMaterial> m = RfMaterial::fit(btf, FitOptions::parse(optionText));
        const double fitSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();

        const ErrorSummary e =
            computeError(btf, [&](std::size_t t, float* o) { m->evaluateMeasured(t, o); });
        const MemoryFootprint f = m->memory();
        std::printf("rf fit of the %dx%d built-in sample (%zu views x %zu lights, %d lobes)\n",
                    size, size, btf.viewCount(), btf.lightCount(), m->lobeCount());
        std::printf("  sample generation  %.1f s\n", sampleSeconds);
        std::printf(
            "  fit                %.1f s (%.1f us per texel and view; %s LM iterations "
            "per view, %s fallbacks)\n",
            fitSeconds, 1e6 * fitSeconds / double(btf.texelCount() * btf.viewCount()),
            m->fitInfo["iterations"].c_str(), m->fitInfo["fallbacks"].c_str());
        std::printf("  extrapolated to 256x256: %.0f s\n",
                    fitSeconds * 65536.0 / double(btf.texelCount()));
        std::printf(
            "  error avg %.4f  min %.4f  max %.4f  RMSE %.4f  PSNR %.2f dB  non-finite %zu\n",
            e.average, e.minimum, e.maximum, e.rmse, e.psnr, e.nonFiniteValues);
        std::printf("  memory %.0f values, %.0f bytes per texel, %.1f MiB in all\n",
                    f.valuesPerTexel, f.bytesPerTexel, double(f.totalBytes) / 1048576.0);
        if (!out.empty()) saveMaterial(*m, out);
        if (viewport > 0) {
            HeadlessRenderer renderer;
            renderer.setCamera(orthoUnitSquare(viewport, viewport));
            osg::ref_ptr<osg::StateSet> stateSet = m->createStateSet();
            osg::ref_ptr<osg::Geode> geode = createFullScreenQuad(stateSet.get());
            osg::Geometry* quad = geode->getDrawable(0)->asGeometry();
            osg::ref_ptr<osg::Vec4Array> tangents =
                new osg::Vec4Array(quad->getVertexArray()->getNumElements());
            for (auto& t : *tangents) t.set(1, 0, 0, 1);
            quad->setVertexAttribArray(6, tangents.get(), osg::Array::BIND_PER_VERTEX);
            stateSet->addUniform(new osg::Uniform("osgBTF_lightCount", 1));
            osg::ref_ptr<osg::Uniform> position =
                new osg::Uniform(osg::Uniform::FLOAT_VEC4, "osgBTF_lightPosition", 8);
            position->setElement(0, osg::Vec4(0.4f, 0.3f, 0.866f, 0.0f));
            stateSet->addUniform(position.get());
            osg::ref_ptr<osg::Uniform> colour =
                new osg::Uniform(osg::Uniform::FLOAT_VEC3, "osgBTF_lightColor", 8);
            colour->setElement(0, osg::Vec3(1, 1, 1));
            stateSet->addUniform(colour.get());
            renderer.setScene(geode.get());
            const PassTiming timing = renderer.timePasses(10);
            std::printf("  pass %dx%d on %s: wall %.2f ms, CPU %.2f ms, GPU %.3f ms (medians)\n",
                        viewport, viewport, renderer.glRenderer().c_str(), timing.wallMs,
                        timing.cpuMs, timing.gpuMs);
        }
    } catch (const Error& e) {
        std::fprintf(stderr, "bench_fit_rf: %s\n", e.what());
        return 1;
    }
    return 0;
}
