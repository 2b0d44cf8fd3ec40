// btf info FILE: what a measured BTF holds, and whether its values are sane. A UBO2014 file is
// described from its header and factors, never decoded (a full-size one is 22 GB decoded);
// --stats streams its values through the factor products in blocks of images.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <limits>
#include <memory>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <nlohmann/json.hpp>

#include "core/MeasuredBtf.h"
#include "core/Progress.h"
#include "loaders/LoadBtf.h"
#include "loaders/OutOfCoreImageSet.h"
#include "loaders/Rti.h"
#include "loaders/Ubo2014.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

namespace {

struct ValueStats {
    double minimum[3], maximum[3], sum[3];
    std::size_t perChannel = 0, nan = 0, inf = 0;

    ValueStats() {
        for (int c = 0; c < 3; ++c) {
            minimum[c] = std::numeric_limits<double>::infinity();
            maximum[c] = -minimum[c];
            sum[c] = 0;
        }
    }
    /** RGB triples, interleaved. */
    void add(const float* values, std::size_t count) {
        for (std::size_t i = 0; i < count; ++i) {
            const float x = values[i];
            const int c = int(i % 3);
            if (std::isnan(x)) {
                ++nan;
            } else if (std::isinf(x)) {
                ++inf;
            } else {
                minimum[c] = std::min(minimum[c], double(x));
                maximum[c] = std::max(maximum[c], double(x));
                sum[c] += x;
            }
        }
    }
    void merge(const ValueStats& o) {
        for (int c = 0; c < 3; ++c) {
            minimum[c] = std::min(minimum[c], o.minimum[c]);
            maximum[c] = std::max(maximum[c], o.maximum[c]);
            sum[c] += o.sum[c];
        }
        nan += o.nan;
        inf += o.inf;
    }
    /** range.R/G/B {min, max, mean}, nan_count, inf_count. */
    void toJson(nlohmann::json& out) const {
        out["nan_count"] = nan;
        out["inf_count"] = inf;
        for (int c = 0; c < 3; ++c) {
            const char* name = c == 0 ? "R" : c == 1 ? "G" : "B";
            out["range"][name] = {{"min", minimum[c]},
                                  {"max", maximum[c]},
                                  {"mean", perChannel ? sum[c] / double(perChannel) : 0.0}};
        }
    }
};

ValueStats scan(const MeasuredBtf& btf) {
    ValueStats s;
    for (std::size_t v = 0; v < btf.viewCount(); ++v)
        for (std::size_t l = 0; l < btf.lightCount(); ++l) {
            const std::vector<float> image = btf.image(v, l);
            s.add(image.data(), image.size());
        }
    s.perChannel = btf.texelCount() * btf.viewCount() * btf.lightCount();
    return s;
}

/** Every value of a factored BTF, decoded block by block of images (FactoredBtf::decodeImages)
 *  and never all at once: per TBB worker one block of at most ~32 MB of decoded values. */
ValueStats scan(const FactoredBtf& f, const std::string& label) {
    const std::size_t texels = f.texelCount(), images = f.imageCount();
    const std::size_t block =
        std::clamp<std::size_t>((std::size_t(32) << 20) / (texels * 3 * sizeof(float)), 1, 256);
    tbb::enumerable_thread_specific<std::vector<float>> buffers;
    tbb::enumerable_thread_specific<ValueStats> partial;
    Progress progress(label, images);
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, images, block),
        [&](const tbb::blocked_range<std::size_t>& range) {
            std::vector<float>& decoded = buffers.local();
            decoded.resize(range.size() * texels * 3);
            f.decodeImages(range.begin(), range.size(), decoded.data());
            partial.local().add(decoded.data(), decoded.size());
            progress.advance(range.size());
        },
        // Only the simple partitioner keeps every range within `block`; the default
        // one hands out ranges many blocks long.
        tbb::simple_partitioner());
    progress.finish();
    ValueStats s;
    for (const ValueStats& p : partial) s.merge(p);
    s.perChannel = texels * images;
    return s;
}

/** Every value of a source read texel block by texel block (an out-of-core capture). */
ValueStats scan(const BtfSource& source, const std::string& label) {
    const std::size_t texels = source.texelCount(), perTexel = source.imageCount() * 3;
    const std::size_t block = std::max<std::size_t>(1, source.abrdfBlockTexels());
    tbb::enumerable_thread_specific<ValueStats> partial;
    Progress progress(label, texels);
    tbb::parallel_for(std::size_t(0), (texels + block - 1) / block, [&](std::size_t b) {
        const std::size_t first = b * block, count = std::min(block, texels - first);
        std::vector<float> values(count * perTexel);
        source.readAbrdfRange(first, count, values.data());
        partial.local().add(values.data(), values.size());
        progress.advance(count);
    });
    progress.finish();
    ValueStats s;
    for (const ValueStats& p : partial) s.merge(p);
    s.perChannel = texels * source.imageCount();
    return s;
}

const char* colorModelName(int model) {
    switch (model) {
        case 0:
            return "RGB";
        case 1:
            return "YUV";
        case 3:
            return "PCA";
        case 4:
            return "YCoCg";
        case 11:
            return "exp-YUV (log Y, chroma / Y)";
        default:
            return "unknown";
    }
}

const char* scalarName(int size) {
    return size == 2 ? "half" : size == 4 ? "float" : "double";
}

nlohmann::json directionJson(const DirectionSet& set) {
    float lo = 90, hi = 0;
    for (const Direction& d : set.directions()) {
        lo = std::min(lo, d.theta);
        hi = std::max(hi, d.theta);
    }
    return {{"name", set.name()}, {"count", set.size()}, {"theta_min", lo}, {"theta_max", hi}};
}

/** The views: and lights: lines of `out`'s direction sets. */
void printDirections(const nlohmann::json& out) {
    for (const char* key : {"views", "lights"}) {
        const auto& d = out[key];
        std::cout << (std::string(key) + ":").append(10 - std::string(key).size() - 1, ' ')
                  << d["count"] << " (" << d["name"].get<std::string>() << ", theta "
                  << d["theta_min"].get<float>() << " to " << d["theta_max"].get<float>()
                  << " deg)\n";
    }
}

void printStats(const nlohmann::json& out) {
    for (const char* name : {"R", "G", "B"}) {
        const auto& r = out["range"][name];
        std::cout << "range " << name << ":  min " << r["min"].get<double>() << "  max "
                  << r["max"].get<double>() << "  mean " << r["mean"].get<double>() << "\n";
    }
    std::cout << "non-finite: " << out["nan_count"].get<std::size_t>() << " NaN, "
              << out["inf_count"].get<std::size_t>() << " Inf\n";
}

/** btf info on a UBO2014 file: the header and the factors as read, nothing decoded unless
 *  `stats`. */
void infoFactored(const std::string& input, bool json, bool stats, LoadOptions load) {
    const auto start = std::chrono::steady_clock::now();
    // Without --stats the matrices are skipped, not read: a full-size file answers at once.
    load.headerOnly = !stats;
    const Ubo2014Factors f = readUbo2014(input, load);
    const double readSeconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    const bool fmf = f.model == FactorModel::Fmf;
    std::error_code ec;
    const std::uint64_t fileBytes = std::filesystem::file_size(input, ec);
    // FactoredBtf::factorBytes() as it would be after a full read (U rows x K, texels x K, S).
    std::uint64_t factorValues = 0;
    for (const BtfFactor& factor : f.factors)
        factorValues +=
            (f.imageCount() * (fmf ? 3 : 1) + f.texelCount()) * std::uint64_t(factor.U.cols()) +
            std::uint64_t(factor.S.size());
    const std::uint64_t factorBytes = factorValues * sizeof(float);
    nlohmann::json out = {
        {"file", input},
        {"format", fmf ? "UBO2014 FMF" : "UBO2014 DFMF"},
        {"signature", f.signature},
        {"width", f.width},
        {"height", f.height},
        {"views", directionJson(f.views)},
        {"lights", directionJson(f.lights)},
        {"images", f.imageCount()},
        {"ranks", {f.components(0), f.components(1), f.components(2)}},
        {"scalar", scalarName(f.scalarSize)},
        {"cosine", f.cosine},
        {"file_bytes", fileBytes},
        {"factor_bytes", factorBytes},
        {"decoded_float_bytes", f.decodedBytes()},
        {"decoded_half_bytes", f.decodedBytes() / 2},
        {"meta",
         {{"version", f.metaVersion},
          {"measurement_setup", f.measurementSetup},
          {"image_sensor", f.imageSensor},
          {"light_source", f.lightSource},
          {"ppmm", f.ppmm}}},
        {"read_seconds", readSeconds},
    };
    if (fmf) {
        out["dynamic_range_reduction"] = f.drr();
        out["header_version"] = f.headerVersion;
        out["height_map"] = {f.heightMapWidth, f.heightMapHeight};
    } else {
        out["color_model"] = {{"id", f.colorModel}, {"name", colorModelName(f.colorModel)}};
    }
    double statsSeconds = 0;
    if (stats) {
        const auto begin = std::chrono::steady_clock::now();
        const ValueStats s =
            scan(f, "statistics of " + std::filesystem::path(input).filename().string());
        statsSeconds =
            std::chrono::duration<double>(std::chrono::steady_clock::now() - begin).count();
        s.toJson(out);
        out["stats_seconds"] = statsSeconds;
    }
    if (json) {
        std::cout << out.dump(2) << "\n";
        return;
    }
    std::cout << std::fixed << std::setprecision(4);
    std::cout << "file:     " << input << "\n"
              << "format:   " << out["format"].get<std::string>() << " (signature " << f.signature
              << ", " << scalarName(f.scalarSize) << " scalars)\n"
              << "texels:   " << f.width << " x " << f.height << "\n";
    printDirections(out);
    std::cout << "images:   " << f.imageCount() << " (view, light) pairs\n";
    if (fmf)
        std::cout << "factors:  FMF, rank " << f.components(0)
                  << " (one factorisation, colour in the rows of U), dynamic-range reduction "
                  << (f.drr() ? "on" : "off") << ", header version " << f.headerVersion
                  << (f.heightMapWidth ? ", height map " + std::to_string(f.heightMapWidth) + "x" +
                                             std::to_string(f.heightMapHeight)
                                       : std::string())
                  << "\n";
    else
        std::cout << "factors:  DFMF, ranks " << f.components(0) << ", " << f.components(1) << ", "
                  << f.components(2) << " (channels of colour model " << f.colorModel << ", "
                  << colorModelName(f.colorModel) << ")\n";
    std::cout << "cosine:   " << (f.cosine ? "in the data (divided out when decoding)" : "no")
              << "\n"
              << "bytes:    " << formatBytes(fileBytes) << " file, " << formatBytes(factorBytes)
              << " factors as float; decoded " << formatBytes(f.decodedBytes()) << " as float, "
              << formatBytes(f.decodedBytes() / 2) << " as half\n"
              << std::setprecision(2) << "read:     " << readSeconds
              << (stats ? " s (factors, nothing decoded)\n" : " s (header, factors skipped)\n")
              << std::setprecision(4);
    if (stats) {
        printStats(out);
        std::cout << std::setprecision(2) << "stats:    " << statsSeconds
                  << " s (all values, decoded in blocks)\n";
    }
}

/** btf info on an RTI capture kept out of core: the light file and the first photo's header,
 *  nothing decoded unless `stats` (then every photo, through the out-of-core source). */
void infoLargeCapture(const std::string& input, const RtiCaptureHeader& h, bool json, bool stats,
                      const LoadOptions& load) {
    const std::size_t lights = h.lights.size();
    const std::uint64_t floats =
        MeasuredBtf::bytesNeeded(h.width, h.height, 1, lights, Storage::Float);
    const std::uint64_t disk =
        OutOfCoreImageSet::diskBytesNeeded(h.width, h.height, lights, h.rawBytes);
    const DirectionSet view("rti-view", {{0, 0}});
    nlohmann::json out = {
        {"file", input},
        {"width", h.width},
        {"height", h.height},
        {"views", directionJson(view)},
        {"lights", directionJson(h.lights)},
        {"storage", "disk"},
        {"float_bytes", floats},
        {"disk_bytes", disk},
        {"raw_8bit_bytes", std::uint64_t(h.width) * h.height * lights * 3},
        {"decoded", h.decoding},
    };
    if (stats) {
        LoadOptions onDisk = load;
        onDisk.placement = LoadOptions::Placement::Disk;
        const std::unique_ptr<BtfSource> source = openRtiCapture(input, onDisk);
        scan(*source, "statistics of " + std::filesystem::path(input).filename().string())
            .toJson(out);
    }
    if (json) {
        std::cout << out.dump(2) << "\n";
        return;
    }
    std::cout << std::fixed << std::setprecision(4);
    std::cout << "file:     " << input << "\n"
              << "texels:   " << h.width << " x " << h.height << " (" << std::setprecision(1)
              << double(h.width) * h.height / 1e6 << " megapixels)\n"
              << std::setprecision(4);
    printDirections(out);
    std::cout << "images:   " << lights << " photos (from the light file; the first one's header "
              << "read, no pixel decoded)\n"
              << "storage:  disk: " << formatBytes(disk) << " decoded into " << outOfCoreFolder()
              << " when fitted (" << formatBytes(floats)
              << " as floats, more than a quarter of the memory limit of "
              << formatBytes(memoryLimit()) << ")\n"
              << "decoded:  " << h.decoding
              << " (8/16-bit image values to radiance; --decode to choose)\n";
    if (stats)
        printStats(out);
    else
        std::cout << "stats:    not computed (--stats decodes every photo)\n";
}

}  // namespace

Runner addInfoCommand(CLI::App& app, CommonOptions& common) {
    auto* command = app.add_subcommand("info",
                                       "Print sizes, direction sets, value range, memory "
                                       "and NaN/Inf count of a measured BTF (a UBO2014 file: "
                                       "its header and factors, value ranges with --stats)");
    struct Options {
        std::string input;
        bool json = false, stats = false;
    };
    auto options = std::make_shared<Options>();
    std::string& input = options->input;
    command
        ->add_option(
            "FILE", input,
            "UBO2003/ATRIUM zip or folder, UBO2014 .btf, an RTI set (.lp file, or a "
            "folder or zip with one), or an RTI fitted file (.ptm, .rti, relight's DIR/info.json)")
        ->required();
    command->add_flag("--json", options->json, "Print JSON instead of text");
    command->add_flag("--stats", options->stats,
                      "UBO2014 files: also the value range and NaN/Inf count of every decoded "
                      "value, streamed through the factors in blocks (minutes at full size); "
                      "other inputs always have them");
    addLoadOptions(*command, common);
    return [&common, options] {
        const std::string& input = options->input;
        // Another tool's fitted file (.ptm, .rti): its header and what it reads as.
        if (const ForeignFileFormat* format = findForeignFile(input)) {
            const std::string header = format->info(input);
            const osg::ref_ptr<Material> material = loadMaterial(input);
            const MemoryFootprint memory = material->memory();
            if (options->json) {
                std::cout << nlohmann::json{{"file", input},
                                            {"format", format->description},
                                            {"header", header},
                                            {"method", material->methodName()},
                                            {"width", material->width()},
                                            {"height", material->height()},
                                            {"values_per_texel", memory.valuesPerTexel}}
                                 .dump(2)
                          << "\n";
                return;
            }
            std::cout << "file:     " << input << "\n"
                      << "format:   " << format->description << "\n"
                      << header << "\n"
                      << "reads as: a " << material->methodName() << " material, "
                      << material->width() << " x " << material->height() << " texels, "
                      << memory.valuesPerTexel << " values per texel\n";
            return;
        }
        if (isUbo2014File(input)) {
            infoFactored(input, options->json, options->stats, common.loadOptions());
            return;
        }
        const LoadOptions load = common.loadOptions();
        if (load.placement != LoadOptions::Placement::Memory && isRtiCapture(input)) {
            // A capture that a fit would keep out of core is described from its headers.
            const RtiCaptureHeader h = readRtiCaptureHeader(input, load);
            if (rtiCaptureOnDisk(h.width, h.height, h.lights.size(), load)) {
                infoLargeCapture(input, h, options->json, options->stats, load);
                return;
            }
        }
        const MeasuredBtf btf = loadMeasuredBtf(input, load);
        const ValueStats s = scan(btf);
        const std::uint64_t raw8bit =
            std::uint64_t(btf.texelCount()) * btf.viewCount() * btf.lightCount() * 3;
        nlohmann::json out = {
            {"file", input},
            {"width", btf.width()},
            {"height", btf.height()},
            {"views", directionJson(btf.views())},
            {"lights", directionJson(btf.lights())},
            {"storage", btf.storage() == Storage::Float ? "float" : "half"},
            {"memory_bytes", btf.memoryBytes()},
            {"raw_8bit_bytes", raw8bit},
            {"decoded", btf.decoding},
        };
        s.toJson(out);
        if (options->json) {
            std::cout << out.dump(2) << "\n";
            return;
        }
        std::cout << std::fixed << std::setprecision(4);
        std::cout << "file:     " << input << "\n"
                  << "texels:   " << btf.width() << " x " << btf.height() << "\n";
        printDirections(out);
        std::cout << "images:   " << btf.viewCount() * btf.lightCount() << " (view, light) pairs\n"
                  << "storage:  " << out["storage"].get<std::string>() << ", "
                  << formatBytes(btf.memoryBytes()) << " in memory (" << formatBytes(raw8bit)
                  << " as 8-bit RGB)\n";
        if (!btf.decoding.empty())
            std::cout << "decoded:  " << btf.decoding
                      << " (8/16-bit image values to radiance; --decode to choose)\n";
        printStats(out);
    };
}

}  // namespace osgBTF::tool
