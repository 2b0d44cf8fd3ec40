// Benchmark: Schneider 2004 Table 1 in our own run: time per pass of the original LPCA rendering
// (3x3 manual direction interpolation) and the revised one (3D texture, 2 fetches + 1 lerp per
// component) for c = 2, 4, 8 at 1024x1024, the same fitted data in the same run.
// Usage: bench_lpca_pass_time [--size N] [--frames F] [--viewport P] [--resolution R] [--unorm8 1]
//   Renders a full-viewport patch through the headless renderer (OSGBTF_HEADLESS picks EGL or
//   OSMesa); prints the GL renderer, wall / CPU / GPU-timer ms per pass (medians), the speed-up,
//   and the extra per-texel error of the resampled model. --unorm8 1 times the revised method's
//   8-bit storage (Schneider 2004's RGBA8 3D textures) instead of half floats.
#include <cstdio>
#include <string>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/PassCost.h"
#include "harness/headless/HeadlessRenderer.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/lpca-revised/LpcaRevised.h"
#include "materials/lpca/Lpca.h"

namespace {

osg::ref_ptr<osg::Geode> patch(osg::StateSet* stateSet) {
    osgBTF::setDirectionalLights(*stateSet, {osg::Vec3(0.4f, 0.3f, 0.866f)});
    return osgBTF::createTangentPatch(stateSet);
}

double errorAverage(const osgBTF::MeasuredBtf& btf, const osgBTF::Material& m) {
    return osgBTF::computeError(btf, [&](std::size_t t, float* out) { m.evaluateMeasured(t, out); })
        .average;
}

}  // namespace

int main(int argc, char** argv) {
    int size = 64, frames = 5, viewport = 1024, resolution = 16, unorm8 = 0;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string arg = argv[i];
        const int value = std::stoi(argv[i + 1]);
        if (arg == "--size")
            size = value;
        else if (arg == "--frames")
            frames = value;
        else if (arg == "--viewport")
            viewport = value;
        else if (arg == "--resolution")
            resolution = value;
        else if (arg == "--unorm8")
            unorm8 = value;
    }
    try {
        osgBTF::SampleOptions sample;
        sample.width = sample.height = size;
        const osgBTF::MeasuredBtf btf = osgBTF::makeSampleBtf(sample);
        osgBTF::HeadlessRenderer renderer;
        renderer.setCamera(osgBTF::orthoUnitSquare(viewport, viewport));
        std::printf(
            "renderer: %s (%s), software: %s; %dx%d pass, data %dx%d, 32 clusters, grid "
            "%d^4, revised storage %s\n",
            renderer.glRenderer().c_str(), renderer.glVersion().c_str(),
            renderer.isSoftwareRenderer() ? "yes" : "no", viewport, viewport, size, size,
            resolution, unorm8 ? "unorm8" : "half");
        std::printf(
            "| c | LPCA wall ms | LPCA CPU ms | LPCA GPU ms | revised wall ms | revised CPU "
            "ms | revised GPU ms | speed-up (wall) | error LPCA | error revised |\n");
        std::printf("|---|---|---|---|---|---|---|---|---|---|\n");
        for (int c : {2, 4, 8}) {
            osg::ref_ptr<osgBTF::LpcaMaterial> lpca = osgBTF::LpcaMaterial::fit(
                btf, osgBTF::FitOptions::parse("clusters=32 components=" + std::to_string(c)));
            osg::ref_ptr<osgBTF::LpcaRevisedMaterial> revised =
                osgBTF::LpcaRevisedMaterial::fromLpca(*lpca, resolution, unorm8 != 0);
            osgBTF::PassTiming timing[2];
            const osgBTF::Material* materials[2] = {lpca.get(), revised.get()};
            for (int m = 0; m < 2; ++m) {
                osg::ref_ptr<osg::StateSet> stateSet = materials[m]->createStateSet();
                renderer.setScene(patch(stateSet.get()).get());
                timing[m] = renderer.timePasses(frames);
            }
            std::printf("| %d | %.1f | %.1f | %.2f | %.1f | %.1f | %.2f | %.2fx | %.4f | %.4f |\n",
                        c, timing[0].wallMs, timing[0].cpuMs, timing[0].gpuMs, timing[1].wallMs,
                        timing[1].cpuMs, timing[1].gpuMs, timing[0].wallMs / timing[1].wallMs,
                        errorAverage(btf, *lpca), errorAverage(btf, *revised));
            std::fflush(stdout);
        }
    } catch (const osgBTF::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
