// btf synthesize IN -o map.exr: k-coherence synthesis of a large surface from a measured sample
// (Boßerhoff and Nicoll 2003 sections 4-5) into a coordinate map; btf make-tileable IN -o OUT.zip:
// Sattler et al. 2003's linear edge blending so a sample tiles without a seam.
#include <chrono>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include "core/CoordinateMap.h"
#include "core/Error.h"
#include "harness/sample/Ubo2003Writer.h"
#include "loaders/LoadBtf.h"
#include "synthesis/KCoherence.h"
#include "synthesis/Tileable.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

namespace {

double secondsSince(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

/** Before any long work: the same message writeFileAtomically gives at the end. */
void requireOutputFolder(const std::string& output) {
    const std::filesystem::path folder = std::filesystem::path(output).parent_path();
    if (!folder.empty() && !std::filesystem::is_directory(folder))
        fail(output, "folder '" + folder.string() + "' does not exist");
}

}  // namespace

Runner addSynthesizeCommand(CLI::App& app, CommonOptions& common) {
    auto* command = app.add_subcommand(
        "synthesize",
        "Synthesise a large surface from a measured sample by k-coherence synthesis (Boßerhoff and "
        "Nicoll 2003, "
        "sec. 4) and write it as a coordinate map (OpenEXR, R = sample x, G = sample y per "
        "output texel); prints the analysis and synthesis times, the coherence rate and the "
        "seam ratio");
    struct Options {
        std::string input, output;
        SynthesisOptions synthesis;
        int size = 512;
    };
    auto options = std::make_shared<Options>();
    SynthesisOptions& s = options->synthesis;
    command->add_option("INPUT", options->input, "Measured BTF (zip, folder or .btf)")->required();
    command->add_option("-o,--output", options->output, "Coordinate map (.exr)")->required();
    command->add_option("--size", options->size, "Output texels per side")
        ->check(CLI::Range(1, 16384))
        ->capture_default_str();
    command
        ->add_option("--k", s.k,
                     "Candidates per neighbour: its shifted source and its k-1 most similar "
                     "texels (k = 1: Ashikhmin's coherent candidates only)")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    command
        ->add_option("--neighbourhood", s.neighbourhood,
                     "Neighbourhood radius r: a (2r+1)x(2r+1) square of texels")
        ->check(CLI::Range(1, 8))
        ->capture_default_str();
    command
        ->add_option("--levels", s.levels,
                     "Pyramid levels (the sample's sides must be multiples of 2^(levels-1))")
        ->check(CLI::Range(1, 8))
        ->capture_default_str();
    command->add_option("--seed", s.seed, "Random seed: the same seed gives the same map")
        ->capture_default_str();
    command
        ->add_option("--images", s.images,
                     "Use this many images, spread evenly over the (view, light) pairs, for the "
                     "texel vectors (0 = all)")
        ->capture_default_str();
    command->add_option("--textons", s.textons, "k-means clusters (textons) per level")
        ->check(CLI::Range(1, 65536))
        ->capture_default_str();
    command
        ->add_option("--dimensions", s.dimensions,
                     "Random-projection dimension of the texel vectors (distances are kept in "
                     "expectation)")
        ->check(CLI::Range(1, 4096))
        ->capture_default_str();
    command
        ->add_option("--patch", s.patch,
                     "Spacing of the jumps (output texels): one per cell of this side, to a texel "
                     "whose neighbourhood matches but lies elsewhere in the sample; 0: none (the "
                     "output then repeats the sample); default: half the sample's smaller side")
        ->check(CLI::Range(0, 1 << 20));
    addLoadOptions(*command, common);
    return [&common, options] {
        SynthesisOptions synthesis = options->synthesis;
        synthesis.width = synthesis.height = options->size;
        requireOutputFolder(options->output);
        const auto start = std::chrono::steady_clock::now();
        const std::unique_ptr<BtfSource> input =
            openBtfSource(options->input, common.loadOptions());
        const double loadSeconds = secondsSince(start);
        try {
            validateSynthesisOptions(synthesis, input->width(), input->height(),
                                     input->imageCount());
        } catch (const Error& e) {
            fail(options->input, e.what());
        }
        const auto analysed = std::chrono::steady_clock::now();
        const SampleAnalysis analysis = analyseSample(*input, synthesis);
        const double analysisSeconds = secondsSince(analysed);
        const auto synthesised = std::chrono::steady_clock::now();
        const CoordinateMap map = synthesizeMap(analysis, synthesis);
        const double synthesisSeconds = secondsSince(synthesised);
        const SynthesisQuality quality = measureSynthesis(analysis, map);
        writeCoordinateMap(map, options->output);
        const SynthesisLevel& finest = analysis.levels.back();
        std::cout << std::fixed << std::setprecision(2) << "synthesised " << map.width << "x"
                  << map.height << " texels from " << options->input << " (" << analysis.width
                  << "x" << analysis.height << " texels, " << analysis.images.size()
                  << " images: " << analysis.valuesPerTexel << " values per texel, projected to "
                  << finest.dimensions << ")\n"
                  << "settings: k " << synthesis.k << ", neighbourhood " << synthesis.neighbourhood
                  << ", levels " << synthesis.levels << ", seed " << synthesis.seed << ", "
                  << finest.textonCount << " textons at full resolution\n"
                  << "time: load " << loadSeconds << " s, analysis " << analysisSeconds
                  << " s, synthesis " << synthesisSeconds << " s\n"
                  << std::setprecision(4) << "coherence rate " << quality.coherenceRate
                  << " (share of adjacent output texels whose sources are adjacent in the "
                     "sample)\n"
                  << "seam ratio " << quality.seamRatio
                  << " (mean distance of adjacent output texels / of adjacent sample texels)\n"
                  << "wrote " << options->output << "\n";
    };
}

Runner addMakeTileableCommand(CLI::App& app, CommonOptions& common) {
    auto* command =
        app.add_subcommand("make-tileable",
                           "Blend a sample's opposite edges linearly (Sattler et al. 2003, sec. "
                           "3.2) so that it tiles without "
                           "a seam; writes a UBO2003-format zip of the same size and directions");
    struct Options {
        std::string input, output, format = "exr";
        int border = 0;
        int quality = 95;
    };
    auto options = std::make_shared<Options>();
    command->add_option("INPUT", options->input, "Measured BTF (zip, folder or .btf)")->required();
    command->add_option("-o,--output", options->output, "Output zip file")->required();
    command->add_option("--border", options->border,
                        "Texels per side over which the edge mismatch is spread (default: an "
                        "eighth of the smaller side)");
    command
        ->add_option("--format", options->format,
                     "Image format of the members: exr (float, lossless), png, jpg or hdr")
        ->check(CLI::IsMember({"jpg", "png", "hdr", "exr"}))
        ->capture_default_str();
    command->add_option("--quality", options->quality, "JPEG quality")
        ->check(CLI::Range(1, 100))
        ->capture_default_str();
    addLoadOptions(*command, common);
    return [&common, options] {
        requireOutputFolder(options->output);
        const auto start = std::chrono::steady_clock::now();
        const MeasuredBtf sample = loadMeasuredBtf(options->input, common.loadOptions());
        const int border =
            options->border ? options->border : defaultTileBorder(sample.width(), sample.height());
        try {
            validateTileBorder(border, sample.width(), sample.height());
        } catch (const Error& e) {
            fail(options->input, e.what());
        }
        const MeasuredBtf tileable = makeTileable(sample, border);
        const Ubo2003ImageFormat format = options->format == "png"   ? Ubo2003ImageFormat::Png
                                          : options->format == "hdr" ? Ubo2003ImageFormat::Hdr
                                          : options->format == "jpg" ? Ubo2003ImageFormat::Jpeg
                                                                     : Ubo2003ImageFormat::Exr;
        writeUbo2003Zip(tileable, options->output, format, options->quality);
        std::cout << std::fixed << std::setprecision(2) << "blended the edges of " << options->input
                  << " (" << sample.width() << "x" << sample.height() << " texels, "
                  << sample.imageCount() << " images) over " << border << " texels per side in "
                  << secondsSince(start) << " s\nwrote " << options->output << "\n";
    };
}

}  // namespace osgBTF::tool
