#include "streaming/TileBuilder.h"

#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>

#include <tbb/parallel_for.h>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/Progress.h"
#include "core/PublishFolder.h"
#include "materials/fmf/Fmf.h"
#include "streaming/TileSet.h"

namespace osgBTF {

namespace fs = std::filesystem;

namespace {

/** One level of one group: RGBA floats, rows from the bottom. */
struct LevelImage {
    int width = 0, height = 0;
    std::vector<float> rgba;
    const float* at(int x, int y) const {
        // Wrap-around: the material repeats on a surface, so the padding does too.
        x = ((x % width) + width) % width;
        y = ((y % height) + height) % height;
        return rgba.data() + (std::size_t(y) * std::size_t(width) + std::size_t(x)) * 4;
    }
};

/** Box mean of the (up to 4) texels of `finer` under each texel of the ceil-halved level. */
LevelImage downsample(const LevelImage& finer, int width, int height) {
    LevelImage out{width, height, std::vector<float>(std::size_t(width) * height * 4, 0.0f)};
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x) {
            float sum[4] = {0, 0, 0, 0};
            int n = 0;
            for (int dy = 0; dy < 2; ++dy)
                for (int dx = 0; dx < 2; ++dx) {
                    const int fx = 2 * x + dx, fy = 2 * y + dy;
                    if (fx >= finer.width || fy >= finer.height) continue;
                    const float* v = finer.at(fx, fy);
                    for (int c = 0; c < 4; ++c) sum[c] += v[c];
                    ++n;
                }
            for (int c = 0; c < 4; ++c)
                out.rgba[(std::size_t(y) * width + x) * 4 + std::size_t(c)] = sum[c] / float(n);
        }
    return out;
}

void writeBytes(const fs::path& path, const std::vector<std::uint8_t>& data) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(data.data()), std::streamsize(data.size()));
    out.close();
    if (!out) fail(path.string(), "cannot write");
}

}  // namespace

TileBuildReport buildTileSet(const Material& material, const std::string& folder,
                             const TileBuildOptions& options) {
    const auto* fmf = dynamic_cast<const FmfMaterial*>(&material);
    if (!fmf)
        fail(
            material.sourceFile.empty() ? material.methodName() + " material" : material.sourceFile,
            "is a '" + material.methodName() + "' material; BSVTF tiles an " +
                std::string(FmfMaterial::kMethod) + " material");
    return buildTileSet(*fmf, folder, options);
}

TileBuildReport buildTileSet(const FmfMaterial& material, const std::string& folder,
                             const TileBuildOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const FactoredBtf& factors = material.factors();
    const std::string source =
        material.sourceFile.empty() ? std::string("fmf material") : material.sourceFile;
    if (factors.model != FactorModel::Fmf)
        fail(source,
             "BSVTF streams FMF materials (one factorisation, the colour in U's rows); this is "
             "DFMF (one factorisation per colour channel): fit an fmf material first, e.g. "
             "`btf fit IN -m fmf --no-mipmap -o M.btfmat`");
    if (material.mipLayout().mipMapped())
        fail(source,
             "the material is mip-mapped; BSVTF builds its own levels: fit the base level "
             "alone (`btf fit IN -m fmf --no-mipmap -o M.btfmat`)");
    if (options.codec != "dct" && options.codec != "raw")
        throw Error("tiles: unknown codec '" + options.codec + "' (known: dct, raw)");
    if (options.quality < 1 || options.quality > 100)
        throw Error("tiles: quality must be in 1..100, got " + std::to_string(options.quality));

    // The textures as the GPU gets them (half storage: the rounded values).
    const FittedMaterial file = material.toFittedMaterial();
    const MaterialTexture& sxv = file.texture("sxv");
    const MaterialTexture& u = file.texture("u");
    const int groups = sxv.depth;
    TileLayout layout(sxv.width, sxv.height, groups, options.tileSize, options.padding);

    TileSetIndex index;
    index.layout = layout;
    index.components = factors.components(0);
    index.codec = options.codec;
    index.parameters = file.parameters;
    index.views = factors.views;
    index.lights = factors.lights;
    index.tiles.assign(layout.tileCount(), TileRecord{});
    index.uPackets.assign(std::size_t(groups), UPacketRecord{});
    // One quantisation step at step size 1 is 1/255 of the largest Eigen-Texture value: quality
    // then means on the first (largest) Eigen-Texture what it means for an 8-bit JPEG, and the
    // steps are absolute for every component, which is what eq. 7's error (the same for every
    // component, U being orthonormal) asks for.
    float peak = 0.0f;
    for (float v : sxv.data) peak = std::max(peak, std::fabs(v));
    index.codecSettings.quality = options.quality;
    index.codecSettings.unit = peak > 0.0f ? peak / 255.0f : 1.0f;

    const fs::path target(folder);
    const fs::path parent = target.has_parent_path() ? target.parent_path() : fs::path(".");
    if (!fs::is_directory(parent)) fail(folder, "folder '" + parent.string() + "' does not exist");
    removeStaleTemporaries(parent.string(), [&](const std::string& stem) {
        return stem == target.filename().string();
    });
    const fs::path work = parent / (target.filename().string() + ".tmp" + std::to_string(getpid()));
    std::error_code ec;
    fs::remove_all(work, ec);
    fs::create_directories(work / "u", ec);
    if (ec) fail(work.string(), "cannot create: " + ec.message());

    TileBuildReport report;
    report.groups = groups;
    report.levels = layout.levels();
    report.tiles = layout.tileCount();
    try {
        // U packets: components 4g..4g+3 of every row, in the u texture's (view, row) order.
        const std::size_t rows = std::size_t(u.height) * std::size_t(u.depth);
        for (int g = 0; g < groups; ++g) {
            std::vector<Imath::half> packet(rows * 4);
            for (std::size_t r = 0; r < rows; ++r)
                for (int j = 0; j < 4; ++j)
                    packet[r * 4 + std::size_t(j)] = Imath::half(
                        u.data[(r * std::size_t(u.width) + std::size_t(g)) * 4 + std::size_t(j)]);
            const std::vector<std::uint8_t> bytes = halfBytes(packet.data(), packet.size());
            index.uPackets[std::size_t(g)] = {std::uint32_t(bytes.size()), tileSetCrc(bytes)};
            writeBytes(work / TileSetIndex::uPacketPath(g), bytes);
            report.uBytes += bytes.size();
        }

        Progress progress("tiles", layout.tileCount());
        const int side = layout.paddedTileSize(), T = layout.tileSize(), P = layout.padding();
        const std::size_t tileValues = std::size_t(side) * std::size_t(side) * 4;
        std::vector<double> groupError(std::size_t(groups), 0.0);
        for (int g = 0; g < groups; ++g) {
            std::vector<LevelImage> levels(std::size_t(layout.levels()));
            LevelImage& finest = levels.back();
            finest.width = layout.width();
            finest.height = layout.height();
            const std::size_t texels = std::size_t(finest.width) * std::size_t(finest.height);
            finest.rgba.assign(sxv.data.begin() + std::ptrdiff_t(std::size_t(g) * texels * 4),
                               sxv.data.begin() + std::ptrdiff_t(std::size_t(g + 1) * texels * 4));
            for (int l = layout.finestLevel() - 1; l >= 0; --l)
                levels[std::size_t(l)] = downsample(levels[std::size_t(l) + 1],
                                                    layout.levelWidth(l), layout.levelHeight(l));

            std::map<std::pair<int, int>, std::vector<Imath::half>> previous;
            for (int l = 0; l <= layout.finestLevel(); ++l) {
                fs::create_directories(
                    work / ("tiles/" + std::to_string(g) + "/" + std::to_string(l)), ec);
                if (ec) fail(work.string(), "cannot create: " + ec.message());
                const int tx = layout.tilesX(l), count = tx * layout.tilesY(l);
                std::vector<std::vector<Imath::half>> decoded{std::size_t(count)};
                std::vector<double> errors(static_cast<std::size_t>(count), 0.0);
                const LevelImage& image = levels[std::size_t(l)];
                tbb::parallel_for(0, count, [&](int k) {
                    const TileId t{g, l, k % tx, k / tx};
                    std::vector<Imath::half> tile(tileValues);
                    double sumSquares = 0.0, sumDiff = 0.0;
                    int inside = 0;
                    for (int py = 0; py < side; ++py)
                        for (int px = 0; px < side; ++px) {
                            const int x = t.x * T - P + px, y = t.y * T - P + py;
                            const float* v = image.at(x, y);
                            for (int c = 0; c < 4; ++c)
                                tile[(std::size_t(py) * side + px) * 4 + std::size_t(c)] =
                                    Imath::half(v[c]);
                            // Weights and norms over the tile's own texels inside the level.
                            const bool own = px >= P && px < P + T && py >= P && py < P + T &&
                                             x < image.width && y < image.height;
                            if (!own) continue;
                            ++inside;
                            const float* up =
                                l > 0 ? levels[std::size_t(l) - 1].at(x >> 1, y >> 1) : nullptr;
                            for (int c = 0; c < 4; ++c) {
                                sumSquares += double(v[c]) * v[c];
                                const double d = v[c] - (up ? up[c] : 0.0f);
                                sumDiff += d * d;
                            }
                        }
                    TileRecord& record = index.tiles[layout.index(t)];
                    record.weight = float(sumDiff / inside);
                    record.norm = float(sumSquares / inside);

                    std::vector<std::uint8_t> bytes;
                    std::vector<Imath::half> out;
                    if (options.codec == "raw") {
                        bytes = halfBytes(tile.data(), tile.size());
                        out = tile;
                    } else {
                        std::vector<Imath::half> prediction;
                        if (l > 0) {
                            prediction.resize(tileValues);
                            predictFromParent(layout, t, previous.at({t.x / 2, t.y / 2}).data(),
                                              prediction.data());
                        }
                        bytes = encodeTile(tile.data(),
                                           prediction.empty() ? nullptr : prediction.data(), side,
                                           index.codecSettings, &out);
                    }
                    double largest = 0.0;
                    for (std::size_t i = 0; i < tileValues; ++i)
                        largest = std::max(largest, std::fabs(double(out[i]) - double(tile[i])));
                    errors[std::size_t(k)] = largest;
                    record.bytes = std::uint32_t(bytes.size());
                    record.crc = tileSetCrc(bytes);
                    writeBytes(work / TileSetIndex::tilePath(t), bytes);
                    decoded[std::size_t(k)] = std::move(out);
                    progress.advance();
                });
                previous.clear();
                for (int k = 0; k < count; ++k) {
                    previous[{k % tx, k / tx}] = std::move(decoded[std::size_t(k)]);
                    report.storedTileBytes +=
                        index.tiles[layout.index({g, l, k % tx, k / tx})].bytes;
                    groupError[std::size_t(g)] =
                        std::max(groupError[std::size_t(g)], errors[std::size_t(k)]);
                }
            }
        }
        progress.finish();
        report.largestTileError = *std::max_element(groupError.begin(), groupError.end());
        report.rawTileBytes = std::uint64_t(layout.tileCount()) * layout.tileBytes();

        const std::string text = index.serialize();
        report.indexBytes = text.size();
        writeBytes(work / TileSetIndex::kIndexName,
                   std::vector<std::uint8_t>(text.begin(), text.end()));
        publishFolder(work.string(), folder);
    } catch (...) {
        fs::remove_all(work, ec);
        throw;
    }
    report.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    return report;
}

}  // namespace osgBTF
