// btf tiles INPUT -o DIR: the BSVTF tile set of an fmf material (Schwartz et al. 2013 sections
// 5-7), for streaming from a folder or a static HTTP server (streaming/TileSet.h describes the
// files).
#include <cctype>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include "core/Error.h"
#include "materials/fmf/Fmf.h"
#include "scene/OpenMaterial.h"
#include "streaming/TileBuilder.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

Runner addTilesCommand(CLI::App& app, CommonOptions&) {
    auto* command = app.add_subcommand(
        "tiles",
        "Write the BSVTF tile set of an fmf material: every group of 4 Eigen-Textures as a "
        "pyramid of 64x64 tiles (+4 texels of padding) coded against the decoded parent (8x8 "
        "DCT, JPEG-like quantisation, deflate), the tiles' priority weights, U in packets of 4 "
        "components and an index (Schwartz et al. 2013)");
    struct Options {
        std::string input, output, codec = "dct";
        TileBuildOptions build;
    };
    auto options = std::make_shared<Options>();
    command
        ->add_option("INPUT", options->input,
                     "An fmf material: a fitted-material file from `btf fit -m fmf --no-mipmap`, "
                     "or a UBO2014 "
                     "FMF .btf (its stored factors; DFMF files: fit fmf first)")
        ->required();
    command
        ->add_option("-o,--output", options->output,
                     "Output folder (created; an existing one is replaced as a whole)")
        ->required();
    command
        ->add_option("--codec", options->build.codec,
                     "dct (coded residuals, Schwartz et al. 2013) or raw (41,472-byte half tiles)")
        ->check(CLI::IsMember({"dct", "raw"}))
        ->capture_default_str();
    command->add_option("--quality", options->build.quality, "JPEG-like quality of dct, 1..100")
        ->check(CLI::Range(1, 100))
        ->capture_default_str();
    command->add_option("--tile-size", options->build.tileSize, "T, a multiple of 8")
        ->capture_default_str();
    command
        ->add_option("--padding", options->build.padding,
                     "Texels of padding per side (T + 2 P a multiple of 8)")
        ->capture_default_str();
    return [options] {
        std::string extension = std::filesystem::path(options->input).extension().string();
        for (char& c : extension) c = char(std::tolower(static_cast<unsigned char>(c)));
        if (extension == ".zip" || std::filesystem::is_directory(options->input))
            fail(options->input, "is a measured BTF; tile an fmf fit of it (`btf fit " +
                                     options->input +
                                     " -m fmf -o M.btfmat`, then `btf tiles M.btfmat`)");
        const osg::ref_ptr<Material> material = openMaterial(options->input);
        const auto* fmf = dynamic_cast<const FmfMaterial*>(material.get());
        if (!fmf)
            fail(options->input, "is a '" + material->methodName() +
                                     "' material; BSVTF tiles an fmf material (`btf fit IN -m "
                                     "fmf -o M.btfmat`, or a UBO2014 FMF .btf)");
        const TileBuildReport r = buildTileSet(*fmf, options->output, options->build);
        const double mib = 1024.0 * 1024.0;
        std::cout << std::fixed << std::setprecision(2) << options->output << ": " << r.groups
                  << " groups x " << r.levels << " levels, " << r.tiles << " tiles, "
                  << r.storedTileBytes / mib << " MiB of tiles (" << r.rawTileBytes / mib
                  << " MiB raw, " << std::setprecision(1)
                  << double(r.rawTileBytes) / double(std::max<std::uint64_t>(1, r.storedTileBytes))
                  << ":1), U " << std::setprecision(2) << r.uBytes / mib << " MiB in " << r.groups
                  << " packets, index " << r.indexBytes / 1024.0 << " KiB; largest tile error "
                  << std::setprecision(6) << r.largestTileError << "; " << std::setprecision(2)
                  << r.seconds << " s\n";
    };
}

}  // namespace osgBTF::tool
