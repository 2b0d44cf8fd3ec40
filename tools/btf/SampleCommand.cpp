// btf sample -o FILE: writes the built-in synthetic sample BTF in a Bonn format.
#include <filesystem>
#include <iostream>
#include <memory>

#include "core/Error.h"
#include "core/Progress.h"
#include "harness/sample/SampleBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

Runner addSampleCommand(CLI::App& app, CommonOptions&) {
    auto* command = app.add_subcommand(
        "sample",
        "Write the built-in sample BTF (a woven cloth-like height field with self-shadowing and a "
        "glossy lobe, 81x81 Bonn directions) as a UBO2003-format zip");
    struct Options {
        std::string output;
        int size = 64;
        std::string format = "jpg";
        int quality = 95;
        float variation = 0.0f;
        int weaveRepeats = 2;
    };
    auto options = std::make_shared<Options>();
    command->add_option("-o,--output", options->output, "Output zip file")->required();
    command->add_option("--size", options->size, "Texels per side")
        ->check(CLI::Range(4, 4096))
        ->capture_default_str();
    command
        ->add_option("--format", options->format,
                     "Image format of the members: jpg (UBO2003), png (lossless 8-bit), hdr "
                     "(ATRIUM-HDR style Radiance RGBE) or exr (float)")
        ->check(CLI::IsMember({"jpg", "png", "hdr", "exr"}))
        ->capture_default_str();
    command->add_option("--quality", options->quality, "JPEG quality")
        ->check(CLI::Range(1, 100))
        ->capture_default_str();
    command
        ->add_option("--variation", options->variation,
                     "0: every weave cell alike; up to 1: each cell its own tint (+-35 %) and "
                     "thread height (+-30 %), so tiling the sample shows its period (a test input "
                     "for btf synthesize)")
        ->check(CLI::Range(0.0f, 1.0f))
        ->capture_default_str();
    command
        ->add_option("--weave-repeats", options->weaveRepeats,
                     "How often the weave pattern repeats across the sample")
        ->check(CLI::Range(1, 64))
        ->capture_default_str();
    return [options] {
        const auto start = std::chrono::steady_clock::now();
        SampleOptions sample;
        sample.width = sample.height = options->size;
        sample.variation = options->variation;
        sample.threadsPerTile = options->weaveRepeats;
        const MeasuredBtf btf = makeSampleBtf(sample);
        const Ubo2003ImageFormat format = options->format == "png"   ? Ubo2003ImageFormat::Png
                                          : options->format == "hdr" ? Ubo2003ImageFormat::Hdr
                                          : options->format == "exr" ? Ubo2003ImageFormat::Exr
                                                                     : Ubo2003ImageFormat::Jpeg;
        writeUbo2003Zip(btf, options->output, format, options->quality);
        const double seconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
        std::cout << "wrote " << options->output << ": " << btf.width() << "x" << btf.height()
                  << " texels, " << btf.viewCount() << " views x " << btf.lightCount()
                  << " lights, " << options->format << " members, "
                  << formatBytes(std::filesystem::file_size(options->output)) << " in " << seconds
                  << " s\n";
    };
}

}  // namespace osgBTF::tool
