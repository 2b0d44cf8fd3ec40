// Benchmark: a BTF ground against a plain textured one under each osgShadow technique (issue 47:
// ViewDependentShadowMap made a BTF scene crawl, because the material's program ran in the shadow
// maps' depth passes). The scene of harness/ShadowScene.h, each technique with OSG's defaults,
// the camera computing near and far from bounding volumes as a stock osgViewer does.
// Usage: bench_shadow_techniques [--frames F] [--width W] [--height H] [--texels N]
//                                [--method M]
//   Prints the GL renderer and, per technique, wall ms per frame (median) of the plain and the
//   BTF ground and their ratio.
#include <cstdio>
#include <string>

#include <osg/Camera>

#include "core/Error.h"
#include "harness/ShadowScene.h"
#include "harness/headless/HeadlessRenderer.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MethodRegistry.h"

int main(int argc, char** argv) {
    int frames = 10, width = 640, height = 480, texels = 16;
    std::string method = "pca";
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string arg = argv[i], value = argv[i + 1];
        if (arg == "--frames")
            frames = std::stoi(value);
        else if (arg == "--width")
            width = std::stoi(value);
        else if (arg == "--height")
            height = std::stoi(value);
        else if (arg == "--texels")
            texels = std::stoi(value);
        else if (arg == "--method")
            method = value;
        else {
            std::fprintf(stderr, "bench_shadow_techniques: unknown argument '%s'\n", arg.c_str());
            return 2;
        }
    }
    try {
        osgBTF::SampleOptions sample;
        sample.width = sample.height = texels;
        const osgBTF::MethodInfo& info = osgBTF::findMethod(method);
        osg::ref_ptr<osgBTF::Material> material = info.fit(
            osgBTF::makeSampleBtf(sample), osgBTF::FitOptions::parse(info.quickFitOptions));
        osgBTF::HeadlessRenderer renderer;
        renderer.setCamera(osgBTF::shadowSceneCamera(width, height));
        renderer.camera().setComputeNearFarMode(
            osg::CullSettings::COMPUTE_NEAR_FAR_USING_BOUNDING_VOLUMES);
        std::printf("renderer: %s (%s); %d x %d, %d frames, %s ground of %d x %d texels\n",
                    renderer.glRenderer().c_str(), renderer.glVersion().c_str(), width, height,
                    frames, method.c_str(), texels, texels);
        std::printf("| technique | plain ground ms/frame | %s ground ms/frame | ratio |\n",
                    method.c_str());
        std::printf("|---|---|---|---|\n");
        for (const std::string& technique : osgBTF::shadowTechniqueNames()) {
            double ms[2];
            for (int btf = 0; btf < 2; ++btf) {
                const osgBTF::ShadowScene scene =
                    osgBTF::makeShadowScene(btf ? material.get() : nullptr, technique);
                renderer.setScene(scene.root.get());
                ms[btf] = renderer.timePasses(frames).wallMs;
            }
            std::printf("| %s | %.1f | %.1f | %.2f |\n", technique.c_str(), ms[0], ms[1],
                        ms[1] / ms[0]);
            std::fflush(stdout);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_shadow_techniques: %s\n", e.what());
        return 1;
    }
    return 0;
}
