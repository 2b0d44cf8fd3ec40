// btf compare INPUT --out DIR: fit every method, tabulate error / memory / pass cost, draw the
// pictures and recommend a method (the library side is harness/Compare.h).
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>
#include <sstream>

#include "core/Error.h"
#include "harness/Compare.h"
#include "materials/MethodRegistry.h"
#include "scene/EnvironmentLight.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

namespace {

/** "640x480" or "512" (square). */
void parseResolution(const std::string& text, PassSettings& pass) {
    const auto x = text.find('x');
    try {
        std::size_t used = 0;
        if (x == std::string::npos) {
            pass.width = pass.height = std::stoi(text, &used);
            if (used == text.size() && pass.width > 0) return;
        } else {
            pass.width = std::stoi(text.substr(0, x), &used);
            if (used == x) {
                const std::string h = text.substr(x + 1);
                pass.height = std::stoi(h, &used);
                if (used == h.size() && pass.width > 0 && pass.height > 0) return;
            }
        }
    } catch (const std::exception&) {
    }
    throw Error("--resolution: '" + text + "' is not N or WxH (positive integers)");
}

}  // namespace

std::vector<std::string> splitList(const std::string& text) {
    std::vector<std::string> items;
    std::string item;
    std::istringstream in(text);
    while (std::getline(in, item, ','))
        if (!item.empty()) items.push_back(item);
    return items;
}

void addMethodSettings(const std::vector<std::string>& settings,
                       std::map<std::string, std::map<std::string, std::string>>& into) {
    for (const std::string& setting : settings) {
        const auto colon = setting.find(':');
        const auto eq = setting.find('=');
        if (colon == std::string::npos || colon == 0 || eq == std::string::npos || eq < colon + 2)
            throw Error("--set: '" + setting + "' is not METHOD:KEY=VALUE");
        into[setting.substr(0, colon)][setting.substr(colon + 1, eq - colon - 1)] =
            setting.substr(eq + 1);
    }
}

Runner addCompareCommand(CLI::App& app, CommonOptions& common) {
    auto* command = app.add_subcommand(
        "compare",
        "Compare compression methods on one measured BTF: fits each method in a `btf fit` child "
        "process (reusing DIR/fits/<method>.exr when it is newer than INPUT and made with the "
        "same options), then writes DIR/report.md, results.csv, results.json and pictures/: "
        "error (CPU evaluator, GPU spot check), memory, pass cost (static ALU/TEX count, time "
        "per pass in RGBA8 and RGBA16F targets, minus the empty pass of the same run, against a "
        "fetch calibration pass), fit time and peak memory, and a "
        "recommendation. Definitions: harness/README.md");
    struct Options {
        std::string input, output, methods = "all", resolution = "256", targets = "rgba8,rgba16f";
        std::vector<std::string> settings;
        int lobes = 0, components = 0, clusters = 0;
        CompareOptions compare;
        bool noReuse = false, noGpu = false;
    };
    auto options = std::make_shared<Options>();
    CompareOptions& c = options->compare;
    command->add_option("INPUT", options->input, "Measured BTF (zip, folder or .btf)")->required();
    command
        ->add_option("-o,--out", options->output,
                     "Output folder; written as DIR.tmp<pid> and renamed when complete "
                     "(an existing DIR is replaced)")
        ->required();
    std::string methodList;
    for (const std::string& m : allCompareMethods())
        methodList += (methodList.empty() ? "" : ",") + m;
    command
        ->add_option("--methods", options->methods,
                     "Comma-separated methods, or 'all' (" + methodList + "); the baseline '" +
                         baselineMethod().name + "' is always added")
        ->capture_default_str();
    command->add_option(
        "--lobes", options->lobes,
        "lobes=N for every compared method that has it (" + methodListWithOption("lobes") + ")");
    command->add_option("--components", options->components,
                        "components=C for every compared method that has it (" +
                            methodListWithOption("components") + ")");
    command->add_option("--clusters", options->clusters,
                        "clusters=K for every compared method that has it (" +
                            methodListWithOption("clusters") + ")");
    command->add_option("--set", options->settings,
                        "METHOD:KEY=VALUE, one method's option (repeatable; `btf fit --help` "
                        "lists them), e.g. --set pca:components=8. Invalid values make that "
                        "method fail, reported in the tables, while the others complete.\n" +
                            methodsHelp());
    command
        ->add_option("--resolution", options->resolution,
                     "Viewport of the timed passes: N (square) or WxH")
        ->capture_default_str();
    command->add_option("--lights", c.pass.lights, "Directional lights in the timed passes (1-8)")
        ->check(CLI::Range(1, 8))
        ->capture_default_str();
    command->add_option("--frames", c.pass.frames, "Timed frames per pass (the median is used)")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    command
        ->add_option("--warmup-frames", c.pass.warmupFrames,
                     "Untimed frames before the timed ones of every pass")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    command
        ->add_option("--targets", options->targets,
                     "Comma-separated colour targets of the timed passes, each timed on its own "
                     "(rgba8, rgba16f, rgba32f); the first is the one --max-ms-per-pass reads")
        ->capture_default_str();
    command
        ->add_option("--calibration-fetches", c.pass.calibrationFetches,
                     "RGBA32F texelFetch reads per pixel in the calibration pass")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    command
        ->add_option("--texture-scale", c.pass.textureScale,
                     "Times the material repeats across the timed viewport")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    command->add_option("--sphere-size", c.sphereSize, "Pixels per sphere render")
        ->check(CLI::Range(16, 4096))
        ->capture_default_str();
    command
        ->add_option("--max-bytes-per-texel", c.maxBytesPerTexel,
                     "Memory budget of the recommendation (0: none)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    command
        ->add_option("--max-ms-per-pass", c.maxMsPerPass,
                     "Time budget of the recommendation, ms per pass at --resolution and "
                     "--lights (0: none)")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    command
        ->add_option("--error-texels", c.errorTexels,
                     "Compute the error tables on this many random texels (every view and light "
                     "pair of each, the same texels for every method); 0 = all. Default: all for "
                     "data in memory, 4096 for a UBO2014 file (decoded block by block)")
        ->check(CLI::NonNegativeNumber);
    command
        ->add_option("--holdout-fraction", c.holdoutFraction,
                     "Fit each method a second time without this fraction of the (view, light) "
                     "pairs (whole directions) and report its error, PSNR and SSIM on them "
                     "(0: no held-out fits, half the fitting time)")
        ->check(CLI::Range(0.0, 0.5))
        ->capture_default_str();
    command->add_option(
        "--material", options->compare.materialFiles,
        "An already fitted file as one more row, beside the fitted methods (repeatable): an "
        "osgBTF fitted material (.btfmat, .exr), a .ptm (PTM_FORMAT_RGB, _LRGB, _JPEG_RGB, "
        "_JPEG_LRGB), an .rti (hemispherical harmonics) or relight's DIR/info.json. Evaluated at "
        "INPUT's measured directions (an RTI capture's: its lights) and labelled file:NAME in the "
        "tables, CSV, JSON and pictures; it must have INPUT's size in texels. Not fitted, not "
        "held out, never the recommendation");
    command->add_flag("--refit", options->noReuse, "Fit every method again, even when DIR has it");
    command->add_flag("--no-gpu", options->noGpu,
                      "Skip the OpenGL part (GPU spot check, pass times, sphere renders)");
    command->add_option("--env", options->compare.envFile,
                        "Also draw pictures/environment.png: the sample patch lit by this HDR "
                        "lat-long environment (.hdr, .exr) with every method (GPU)");
    command->add_option("--exposure", options->compare.envExposure, "--env: factor on the result")
        ->capture_default_str();
    command
        ->add_option("--rotation", options->compare.envRotation,
                     "--env: turns the environment about +Z (degrees)")
        ->capture_default_str();
    addLoadOptions(*command, common);
    return [&common, options] {
        if (!options->compare.envFile.empty()) {
            // Before the fits: a missing map must not cost their time.
            osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
            light->setFile(options->compare.envFile);
            if (!light->hasMap()) throw Error("--env: " + light->getError());
        }
        CompareOptions compare = options->compare;
        compare.input = options->input;
        compare.outputDir = options->output;
        compare.reuseFits = !options->noReuse;
        compare.gpu = !options->noGpu;
        parseResolution(options->resolution, compare.pass);
        compare.pass.targets.clear();
        for (const std::string& t : splitList(options->targets)) {
            try {
                compare.pass.targets.push_back(passTarget(t));
            } catch (const Error& e) {
                throw Error(std::string("--targets: ") + e.what());
            }
        }
        if (compare.pass.targets.empty()) throw Error("--targets: no target named");
        compare.methods =
            options->methods == "all" ? allCompareMethods() : splitList(options->methods);
        if (compare.methods.empty()) throw Error("--methods: no method named");
        std::vector<std::string> all = compare.methods;
        all.insert(all.begin(), baselineMethod().name);
        for (const std::string& m : all) {
            findMethod(m);
            const std::pair<const char*, int> shortcuts[] = {{"lobes", options->lobes},
                                                             {"components", options->components},
                                                             {"clusters", options->clusters}};
            for (const auto& [key, value] : shortcuts)
                if (value && findOption(findMethod(m), key))
                    compare.methodOptions[m][key] = std::to_string(value);
        }
        addMethodSettings(options->settings, compare.methodOptions);
        compare.load = common.loadOptions();
        compare.fitExtraArguments = {"--storage", common.storage, "--decode", common.decode};
        if (!common.memoryLimit.empty())
            compare.fitGlobalArguments = {"--memory-limit", common.memoryLimit};

        for (const std::string& file : compare.materialFiles)
            if (!std::filesystem::exists(file)) fail(file, "no such file (--material)");
        const CompareResult result = runCompare(compare);

        std::cout << "compared " << result.methods.size() << " methods on " << result.input << " ("
                  << result.width << "x" << result.height << " texels, " << result.views << "x"
                  << result.lights << " directions); " << result.gpuNote << "\n";
        // One line per method: error, memory, then per target the pass time, the time minus the
        // empty pass (the shading), and that over the fetch-bound floor.
        std::cout << std::left << std::setw(14) << "method" << std::right << std::setw(10)
                  << "avg error" << std::setw(12) << "bytes/tex";
        for (const PassTarget& t : result.pass.targets)
            std::cout << std::setw(13) << t.name + " ms" << std::setw(10) << "- empty"
                      << std::setw(9) << "x floor";
        std::cout << "\n";
        if (result.calibrations.size() == result.pass.targets.size()) {
            std::cout << std::left << std::setw(14) << "(empty pass)" << std::right << std::setw(22)
                      << "";
            for (const Calibration& cal : result.calibrations)
                std::cout << std::fixed << std::setprecision(3) << std::setw(13) << cal.empty.ms
                          << std::setw(10) << 0.0 << std::setw(9) << "" << std::defaultfloat;
            std::cout << "\n";
        }
        for (const MethodResult& m : result.methods) {
            std::cout << std::left << std::setw(14) << m.label() << std::right;
            if (m.failed) {
                std::cout << "  " << m.failure << "\n";
                continue;
            }
            std::cout << std::fixed << std::setprecision(5) << std::setw(10) << m.error.average
                      << std::setprecision(1) << std::setw(12) << m.memory.bytesPerTexel;
            for (std::size_t i = 0; i < result.pass.targets.size(); ++i) {
                if (i >= m.passes.size() || !m.passes[i].measured()) {
                    std::cout << std::setw(13) << "n/a" << std::setw(10) << "n/a" << std::setw(9)
                              << "n/a";
                    continue;
                }
                const MethodPass& p = m.passes[i];
                std::cout << std::setprecision(3) << std::setw(13) << p.pass.ms << std::setw(10)
                          << p.shadingMs << std::setprecision(2) << std::setw(9);
                if (p.floorMs > 0)
                    std::cout << p.floorRatio;
                else
                    std::cout << "n/a";
            }
            std::cout << std::defaultfloat << "\n";
        }
        std::cout << result.recommendation << "\n"
                  << "wrote " << options->output << "/report.md\n";
    };
}

}  // namespace osgBTF::tool
