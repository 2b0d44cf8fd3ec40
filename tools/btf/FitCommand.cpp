// btf fit INPUT --method NAME -o OUT: compress a measured BTF with one method, report the error.
#include <cctype>
#include <chrono>
#include <filesystem>
#include <functional>
#include <iomanip>
#include <iostream>
#include <memory>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "core/FloatImage.h"
#include "core/Progress.h"
#include "fit/MipMapping.h"
#include "harness/FitScore.h"
#include "harness/HeldOut.h"
#include "loaders/LoadBtf.h"
#include "loaders/Ubo2014.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

std::string methodListWithOption(const std::string& key) {
    std::string list;
    for (const std::string& name : methodsWithOption(key))
        list += (list.empty() ? "" : ", ") + name;
    return list;
}

void printErrorSummary(const ErrorSummary& e) {
    std::cout << std::setprecision(5) << "per-texel error (Meseth et al. 2003, sec. 4.1): avg "
              << e.average << "  min " << e.minimum << "  max " << e.maximum << "\n"
              << "RMSE " << e.rmse << "  PSNR " << std::setprecision(4) << e.psnr << " dB";
    if (e.nonFiniteValues) std::cout << "  (" << e.nonFiniteValues << " NaN/Inf values!)";
    std::cout << "\n";
}

Runner addFitCommand(CLI::App& app, CommonOptions& common) {
    auto* command = app.add_subcommand("fit",
                                       "Fit a compression method to a measured BTF and "
                                       "save the fitted material (multi-part OpenEXR)");
    struct Options {
        std::string input, output, method;
        std::vector<std::string> settings;
        int lobes = 0, components = 0, clusters = 0;
        long long errorTexels = -1;
        bool mipmap = false, noMipmap = false;
        double holdout = 0;
    };
    auto options = std::make_shared<Options>();
    command->add_option("INPUT", options->input, "Measured BTF (zip, folder or .btf)")->required();
    command
        ->add_option("-o,--output", options->output,
                     "Fitted material file (.btfmat or .exr); with -m " + factorMethod().name +
                         " also a UBO2014 file (.btf) that other readers of the format read")
        ->required();
    command->add_option("-m,--method", options->method, methodsHelp())->required();
    command->add_option("--lobes", options->lobes,
                        "Shortcut for --set lobes=N (" + methodListWithOption("lobes") + ")");
    command->add_option(
        "--components", options->components,
        "Shortcut for --set components=C (" + methodListWithOption("components") + ")");
    command->add_option("--clusters", options->clusters,
                        "Shortcut for --set clusters=K (" + methodListWithOption("clusters") + ")");
    command->add_option("--set", options->settings,
                        "Method option KEY=VALUE (repeatable; see --method above)");
    command
        ->add_option("--error-texels", options->errorTexels,
                     "Compute the reported error on this many random texels (all view and light "
                     "pairs each); 0 = all. Default: all for data in memory, 4096 for a UBO2014 "
                     "file, which is decoded block by block and never whole")
        ->check(CLI::NonNegativeNumber);
    auto* mipmapFlag = command->add_flag(
        "--mipmap", options->mipmap,
        "Fit a mip-mapped material (the default, except for a .btf output): every level of "
        "box-filtered data (down to 1x1) fitted with the method, so minified surfaces render "
        "the average of what a pixel covers instead of aliasing (1.5x the texels, at most 1.41x "
        "the file; the error covers every level)");
    command
        ->add_flag("--no-mipmap", options->noMipmap,
                   "Fit the base level alone (a plain material: smaller, aliases when minified)")
        ->excludes(mipmapFlag);
    command
        ->add_option("--holdout-fraction", options->holdout,
                     "Leave this fraction of the (view, light) pairs out of the fit (whole "
                     "directions, the split of `btf batch`) and report the error, PSNR and SSIM "
                     "on them too: how the method predicts what it was not fitted on. The "
                     "material written is the one fitted without them (its base level: no "
                     "mip-maps)")
        ->check(CLI::Range(0.0, 0.5))
        ->excludes(mipmapFlag);
    addLoadOptions(*command, common);
    return [&common, options] {
        const MethodInfo& method = findMethod(options->method);
        FitOptions fit;
        for (const std::string& setting : options->settings) {
            const FitOptions parsed = FitOptions::parse(setting);
            for (const auto& [key, value] : parsed.values()) fit.set(key, value);
        }
        if (options->lobes) fit.set("lobes", std::to_string(options->lobes));
        if (options->components) fit.set("components", std::to_string(options->components));
        if (options->clusters) fit.set("clusters", std::to_string(options->clusters));
        validateOptions(method, fit);  // before the (long) load; the fit validates them again
        // What an earlier run killed while writing the same output left (OUTPUT.tmp<pid>).
        const std::filesystem::path outputPath(options->output);
        removeStaleTemporaries(outputPath.parent_path().string(), [&](const std::string& stem) {
            return stem == outputPath.filename().string();
        });
        std::string extension = std::filesystem::path(options->output).extension().string();
        for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
        const bool btfOutput = extension == ".btf";
        // Another tool's file (.ptm for ptm, .rti for hsh): the material is written as that.
        std::string foreignOwner;
        const ForeignFileFormat* foreign = findForeignFile(options->output, &foreignOwner);
        if (foreign && !foreign->write)
            fail(options->output, "osgBTF reads " + foreign->description +
                                      " but does not write it; save as .btfmat or another "
                                      "tool's file");
        if (foreign && !foreign->writes(foreignOwner, method.name))
            fail(options->output,
                 "a " + foreign->extension + " file holds " +
                     writtenMethodsText(*foreign, foreignOwner) + " material; fit it with " +
                     (foreign->methods ? "one of those methods" : "-m " + foreignOwner));
        if (foreign && options->mipmap)
            fail(options->output, "a " + foreign->extension + " file has no mip levels");
        // Mip-mapped unless asked otherwise (every method's file grows by at most
        // 1.41x on the built-in sample, tools/README.md), or the format cannot hold the levels.
        const bool holdout = options->holdout > 0;
        const bool mipmap =
            options->mipmap || (!options->noMipmap && !btfOutput && !holdout && !foreign);
        if (btfOutput && options->mipmap)
            fail(options->output,
                 "a UBO2014 .btf file has no mip levels; save a --mipmap fit as .btfmat or .exr");
        if ((btfOutput || foreign) && holdout)
            fail(options->output, "a --holdout-fraction fit is saved as .btfmat or .exr");
        if (btfOutput && !method.factors)
            fail(options->output, "only method " + factorMethod().name +
                                      " writes a UBO2014 .btf file (its factors are the "
                                      "format's); save " +
                                      method.name + " as .btfmat or .exr");
        // The input's measurement meta data go into a .btf output where the input has them.
        std::unique_ptr<Ubo2014Factors> meta;
        if (btfOutput && isUbo2014File(options->input)) {
            meta = std::make_unique<Ubo2014Factors>(readUbo2014(options->input));
            meta->factors.clear();
        }

        const auto start = std::chrono::steady_clock::now();
        // A UBO2014 file stays factored: each method reads decoded blocks (BtfSource).
        const std::unique_ptr<BtfSource> input =
            openBtfSource(options->input, common.loadOptions());
        const std::unique_ptr<BtfSource> atlas =
            mipmap ? std::make_unique<MipAtlasSource>(*input) : nullptr;
        const batch::HoldoutSplit split =
            holdout ? batch::holdoutSplit(input->viewCount(), input->lightCount(), options->holdout)
                    : batch::HoldoutSplit();
        const std::unique_ptr<BtfSource> kept =
            holdout ? std::make_unique<batch::DirectionSubsetSource>(*input, split) : nullptr;
        // A mip-mapped fit's error is measured against every level's data, a held-out fit's
        // against the directions it kept.
        const BtfSource& btf = atlas ? *atlas : kept ? *kept : *input;
        const auto loaded = std::chrono::steady_clock::now();
        osg::ref_ptr<Material> material =
            mipmap ? fitMipMapped(method, *input, fit) : method.fit(btf, fit);
        const double fitSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - loaded).count();
        material->fitInfo["seconds"] = std::to_string(fitSeconds);
        material->fitInfo["source"] = options->input;
        const std::vector<std::size_t> subsample = errorSubsample(btf, options->errorTexels);
        const ErrorSummary error = fitError(btf, *material, subsample);
        const MemoryFootprint memory = material->memory();
        std::function<void()> foreignReport;
        // Saved last, releasing the material's arrays into the file's (no second copy of a PCA
        // of gigabytes).
        if (btfOutput) {
            writeFactorsAsUbo2014(method.factors->complete(*material), options->output,
                                  method.factors->scalarBytes(*material), meta.get());
        } else if (foreign) {
            const std::string lost = saveMaterial(*material, options->output);
            // The file as written, read back and evaluated at the data's own directions (a
            // foreign file records none).
            const osg::ref_ptr<Material> written = loadMaterial(options->output);
            const std::size_t lights = btf.lightCount();
            const ErrorSummary writtenError = computeError(
                btf,
                [&](std::size_t t, float* out) {
                    const int x = int(t % std::size_t(btf.width()));
                    const int y = int(t / std::size_t(btf.width()));
                    for (std::size_t p = 0; p < btf.imageCount(); ++p) {
                        const glm::vec3 v = written->evaluate(x, y, btf.views().vector(p / lights),
                                                              btf.lights().vector(p % lights));
                        out[p * 3] = v.r;
                        out[p * 3 + 1] = v.g;
                        out[p * 3 + 2] = v.b;
                    }
                },
                subsample.empty() ? nullptr : &subsample);
            foreignReport = [=] {
                std::cout << foreign->extension << " file: " << lost << "; its error as written:\n";
                printErrorSummary(writtenError);
            };
        } else {
            saveFittedMaterial(material->releaseFittedMaterial(), options->output);
        }
        const double loadSeconds = std::chrono::duration<double>(loaded - start).count();
        std::cout << std::fixed << std::setprecision(2) << "fitted " << method.name << " to "
                  << options->input << " (" << input->width() << "x" << input->height()
                  << " texels, "
                  << (atlas ? std::to_string(material->mipLayout().levelCount()) +
                                  " mip levels in " + std::to_string(btf.width()) + "x" +
                                  std::to_string(btf.height()) + ", "
                            : std::string())
                  << btf.viewCount() << "x" << btf.lightCount() << " directions)\n"
                  << "time: load " << loadSeconds << " s, fit " << fitSeconds << " s\n"
                  << "memory: " << memory.valuesPerTexel << " values, " << memory.bytesPerTexel
                  << " bytes per texel, " << formatBytes(memory.totalBytes) << " in all\n";
        if (!subsample.empty())
            std::cout << "error over a random subsample of " << subsample.size() << " of "
                      << btf.texelCount() << " texels (all pairs; --error-texels 0 for all):\n";
        printErrorSummary(error);
        if (foreignReport) foreignReport();
        if (holdout) {
            // The saved file holds the arrays now: the held-out scores use it, loaded back.
            const osg::ref_ptr<Material> saved = loadMaterial(options->output);
            const HeldOutScores h =
                scoreHeldOut(*input, *saved, split, subsample.empty() ? nullptr : &subsample);
            std::cout << "held out of the fit: " << h.pairs << " of " << input->imageCount()
                      << " (view, light) pairs (" << split.keptViews.size() << " of "
                      << input->viewCount() << " views, " << split.keptLights.size() << " of "
                      << input->lightCount() << " lights kept); on them:\n";
            printErrorSummary(h.error);
            std::cout << std::setprecision(4) << "SSIM " << h.ssim << " (mean of " << h.imagesScored
                      << " whole images)\n";
        }
        std::cout << "wrote " << options->output << "\n";
    };
}

}  // namespace osgBTF::tool
