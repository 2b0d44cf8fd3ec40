// btf tiles INPUT -o DIR: the BSVTF tile set of an fmf material (Schwartz et al. 2013 sections
// 5-7), for streaming from a folder or a static HTTP server (streaming/TileSet.h describes the
// files).
//
// BSVTF streams FMF: one factorisation with the colour in U's rows. The UBO2014 database is
// distributed as DFMF (one factorisation per channel of a decorrelating colour model, usually
// the non-linear exp-YUV), which no linear recombination turns into FMF; such an input is
// converted by fitting fmf to its decoded values, streamed from the factors block by block
// (FactoredBtfSource: the decoded whole never exists), and the conversion's error against the
// DFMF values is measured and printed before the tiles are written.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <memory>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "core/FactoredBtf.h"
#include "loaders/LoadBtf.h"
#include "materials/MethodOptions.h"
#include "materials/MethodRegistry.h"
#include "scene/OpenMaterial.h"
#include "streaming/TileBuilder.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

namespace {

/** The fit of `method` (factorMethod(): fmf) to a DFMF material's decoded values with
 *  `components` (0: its largest rank), and its error against those values over `errorTexels`
 *  texels at every (view, light) pair. */
osg::ref_ptr<Material> convertDfmf(const MethodInfo& method, const Material& dfmf, int components,
                                   long long errorTexels) {
    const FactoredBtf factors = method.factors->complete(dfmf);
    const int ranks[3] = {factors.components(0), factors.components(1), factors.components(2)};
    if (components == 0) components = std::max({ranks[0], ranks[1], ranks[2]});
    const FactoredBtfSource source(factors);
    FitOptions fit;
    fit.set("components", std::to_string(components));
    fit.set("storage", method.factors->scalarBytes(dfmf) == 4 ? "float" : "half");
    osg::ref_ptr<Material> fmf = method.fit(source, fit);
    fmf->sourceFile = dfmf.sourceFile;
    const std::vector<std::size_t> texels =
        randomTexels(source, errorTexelCount(source, errorTexels));
    const ErrorSummary error = computeError(
        source, [&](std::size_t t, float* abrdf) { fmf->evaluateMeasured(t, abrdf); }, &texels);
    std::cout << std::setprecision(6) << dfmf.sourceFile << ": DFMF (ranks " << ranks[0] << ", "
              << ranks[1] << ", " << ranks[2] << ", colour model " << factors.colorModel
              << ") converted to FMF with " << components << " components in "
              << std::setprecision(3) << std::stod(fmf->fitInfo["seconds"]) << " s; against the "
              << "DFMF values (" << texels.size() << " of " << source.texelCount()
              << " texels, every (view, light) pair): RMSE " << std::setprecision(6) << error.rmse
              << ", average error " << error.average << ", PSNR " << std::setprecision(2)
              << std::fixed << error.psnr << " dB\n"
              << std::defaultfloat;
    return fmf;
}

}  // namespace

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
        int components = 0;
        long long errorTexels = -1;
    };
    auto options = std::make_shared<Options>();
    command
        ->add_option("INPUT", options->input,
                     "An fmf material: a fitted-material file from `btf fit -m fmf --no-mipmap`, "
                     "or a UBO2014 .btf (FMF: its stored factors; DFMF: converted to FMF first, "
                     "see --components)")
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
    command
        ->add_option("--components", options->components,
                     "DFMF input: components of the FMF it is converted to (an fmf fit of its "
                     "decoded values, streamed from its factors; the conversion's error is "
                     "printed); default: its largest rank")
        ->check(CLI::PositiveNumber);
    command
        ->add_option("--error-texels", options->errorTexels,
                     "DFMF input: texels the conversion's error covers (every (view, light) pair "
                     "each; 0 = all; default 4096)")
        ->check(CLI::NonNegativeNumber);
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
        const MethodInfo& tiled = factorMethod();  // BSVTF streams its Eigen-Textures
        if (extension == ".zip" || std::filesystem::is_directory(options->input))
            fail(options->input, "is a measured BTF; tile an " + tiled.name +
                                     " fit of it (`btf fit " + options->input + " -m " +
                                     tiled.name + " -o M.btfmat`, then `btf tiles M.btfmat`)");
        osg::ref_ptr<Material> material = openMaterial(options->input);
        const bool factored = material->methodName() == tiled.name;
        if (factored && tiled.factors->description(*material).model == FactorModel::Dfmf) {
            // Converted from the factors as stored: a file of float scalars opened again as
            // floats (the default rounds them to half, as the GPU would get them).
            osg::ref_ptr<Material> exact = material;
            if (isUbo2014File(options->input)) {
                material = nullptr;
                exact = openMaterial(options->input, MaterialTexture::Float);
            }
            material = convertDfmf(tiled, *exact, options->components, options->errorTexels);
        } else if (options->components != 0) {
            fail(options->input, "--components converts DFMF input; this material is " +
                                     (factored ? std::string("FMF already") : "not " + tiled.name));
        }
        if (material->methodName() != tiled.name)
            fail(options->input, "is a '" + material->methodName() + "' material; BSVTF tiles an " +
                                     tiled.name + " material (`btf fit IN -m " + tiled.name +
                                     " -o M.btfmat`, or a UBO2014 FMF .btf)");
        const TileBuildReport r = buildTileSet(*material, options->output, options->build);
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
