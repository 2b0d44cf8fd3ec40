// btf eval FITTED --view T,P --light T,P -o img: one (view, light) image through the GPU path.
// With --env FILE the patch is lit by an HDR environment instead (harness/MaterialImage.h).
// FITTED may be a UBO2014 .btf: its stored factors render as an fmf material (nothing decoded).
#include <iostream>
#include <memory>
#include <optional>
#include <sstream>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "harness/MaterialImage.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"
#include "scene/EnvironmentLight.h"
#include "scene/OpenMaterial.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

namespace {
Direction parseDirection(const std::string& text, const std::string& option) {
    Direction d;
    char comma = 0;
    std::istringstream in(text);
    std::string rest;
    if (!(in >> d.theta >> comma >> d.phi) || comma != ',' || (in >> rest))
        throw Error(option + ": '" + text + "' is not THETA,PHI in degrees");
    if (d.theta < 0 || d.theta >= 90)
        throw Error(option + ": theta " + std::to_string(d.theta) + " is not in [0, 90)");
    return d;
}
}  // namespace

Runner addEvalCommand(CLI::App& app, CommonOptions&) {
    auto* command = app.add_subcommand(
        "eval",
        "Render one (view, light) image of a fitted material through the GPU path (headless "
        "OpenGL: EGL, or OSMesa with OSGBTF_HEADLESS=osmesa where linked), one pixel per texel, "
        "oriented like the input images; also evaluates it on the CPU and reports the largest "
        "GPU-CPU difference");
    struct Options {
        std::string input, output, view = "0,0", light = "0,0", storage = "half", env;
        float exposure = 1.0f, rotation = 0.0f;
        bool cpu = false;
    };
    auto options = std::make_shared<Options>();
    command
        ->add_option("FITTED", options->input,
                     "Fitted material file from btf fit, an RTI file (.ptm, .rti, relight's "
                     "DIR/info.json), or a UBO2014 "
                     ".btf (its stored factors, "
                     "rendered as an fmf material without decoding)")
        ->required();
    command->add_option("-o,--output", options->output, "Output image (.exr, .png, .hdr, ...)")
        ->required();
    command->add_option("--view", options->view, "View direction THETA,PHI (degrees)")
        ->capture_default_str();
    auto* lightOption =
        command->add_option("--light", options->light, "Light direction THETA,PHI (degrees)")
            ->capture_default_str();
    command
        ->add_option("--env", options->env,
                     "Light the patch (normal +Z, unoccluded) by this HDR lat-long environment "
                     "(.hdr, .exr; +Z up, top row the zenith) instead of --light: the map "
                     "projected onto the measured light directions (scene/README.md)")
        ->excludes(lightOption);
    command->add_option("--exposure", options->exposure, "--env: factor on the result")
        ->capture_default_str();
    command
        ->add_option("--rotation", options->rotation,
                     "--env: turns the environment about +Z (degrees, counter-clockwise from "
                     "above)")
        ->capture_default_str();
    command->add_flag("--cpu", options->cpu,
                      "Evaluate on the CPU only and write that image: no OpenGL context, no GPU "
                      "render, no GPU-CPU comparison");
    command
        ->add_option("--storage", options->storage,
                     "UBO2014 input: texture storage of its factors, half or float (float only "
                     "for files that store float scalars)")
        ->check(CLI::IsMember({"half", "float"}))
        ->capture_default_str();
    return [options] {
        const glm::vec3 view = parseDirection(options->view, "--view").toVector();
        const glm::vec3 light = parseDirection(options->light, "--light").toVector();
        osg::ref_ptr<EnvironmentLight> environment;
        if (!options->env.empty()) {
            environment = new EnvironmentLight;
            environment->setFile(options->env);
            if (!environment->hasMap()) throw Error("--env: " + environment->getError());
            environment->setRotation(options->rotation);
        }
        FloatImage cpu, gpu;
        std::string method, levels, glRenderer;
        {
            // Scoped: the material and the GL context are released before the image is written,
            // so that the image codecs (loaded for PNG and the like) do not add to their peak.
            osg::ref_ptr<Material> material =
                openMaterial(options->input, options->storage == "float" ? MaterialTexture::Float
                                                                         : MaterialTexture::Half);
            // --cpu: no context at all, so that the CPU path costs what a CPU decoder costs
            // (docs/viewing.md, "The CPU path").
            std::optional<HeadlessRenderer> renderer;
            if (!options->cpu) renderer.emplace();
            if (environment) {
                const std::vector<glm::vec3> g =
                    projectPatchEnvironment(*material, environment->projectionMap());
                cpu = evaluateEnvironmentImage(*material, g, view, options->exposure);
                if (renderer)
                    gpu = renderEnvironmentImage(*renderer, *material, g, view, options->exposure);
            } else {
                cpu = evaluateMaterialImage(*material, view, light);
                if (renderer) gpu = renderMaterialImage(*renderer, *material, view, light);
            }
            method = material->methodName();
            if (material->mipLayout().mipMapped())
                levels = " base of " + std::to_string(material->mipLayout().levelCount()) +
                         " mip levels";
            if (renderer) glRenderer = renderer->glRenderer();
        }
        writeFloatImage(options->cpu ? cpu : gpu, options->output);
        std::cout << "wrote " << options->output << " (" << method << ", " << cpu.width << "x"
                  << cpu.height << levels << ", "
                  << (environment ? "environment " + options->env + ", " : "");
        if (options->cpu)
            std::cout << "CPU)\n";
        else
            std::cout << "GPU: " << glRenderer << "); largest GPU-CPU difference "
                      << maxAbsDifference(gpu, cpu) << "\n";
    };
}

}  // namespace osgBTF::tool
