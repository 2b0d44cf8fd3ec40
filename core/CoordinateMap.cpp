#include "core/CoordinateMap.h"

#include <cmath>
#include <exception>

#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfOutputFile.h>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/MeasuredBtf.h"
#include "core/SizeGuard.h"

namespace osgBTF {

namespace {

const char* const kMapVersionAttribute = "osgBTF.coordinateMap";
const char* const kSampleWidthAttribute = "osgBTF.sampleWidth";
const char* const kSampleHeightAttribute = "osgBTF.sampleHeight";

int intAttribute(const Imf::Header& header, const char* name, const std::string& path) {
    const auto* value = header.findTypedAttribute<Imf::IntAttribute>(name);
    if (!value) fail(path, std::string("coordinate map without an int attribute ") + name);
    return value->value();
}

}  // namespace

CoordinateMap::CoordinateMap(int width_, int height_, int sampleWidth_, int sampleHeight_)
    : width(width_), height(height_), sampleWidth(sampleWidth_), sampleHeight(sampleHeight_) {
    if (width <= 0 || height <= 0)
        throw Error("coordinate map: invalid size " + std::to_string(width) + "x" +
                    std::to_string(height));
    const std::uint64_t entries = std::uint64_t(width) * std::uint64_t(height) * 2;
    checkMemory(entries * sizeof(std::int32_t),
                "coordinate map " + std::to_string(width) + "x" + std::to_string(height));
    coordinates.assign(entries, 0);
}

void validateCoordinateMap(const CoordinateMap& map, const std::string& what) {
    if (map.width <= 0 || map.height <= 0)
        fail(what,
             "invalid map size " + std::to_string(map.width) + "x" + std::to_string(map.height));
    if (map.sampleWidth <= 0 || map.sampleHeight <= 0)
        fail(what, "invalid sample size " + std::to_string(map.sampleWidth) + "x" +
                       std::to_string(map.sampleHeight));
    if (map.coordinates.size() != std::size_t(map.width) * std::size_t(map.height) * 2)
        fail(what, "holds " + std::to_string(map.coordinates.size()) + " coordinates, not 2 x " +
                       std::to_string(map.width) + " x " + std::to_string(map.height));
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x) {
            const int sx = map.sampleX(x, y), sy = map.sampleY(x, y);
            if (sx < 0 || sy < 0 || sx >= map.sampleWidth || sy >= map.sampleHeight)
                fail(what, "entry (" + std::to_string(x) + ", " + std::to_string(y) +
                               ") points to (" + std::to_string(sx) + ", " + std::to_string(sy) +
                               "), outside the " + std::to_string(map.sampleWidth) + "x" +
                               std::to_string(map.sampleHeight) + " sample");
        }
}

void writeCoordinateMap(const CoordinateMap& map, const std::string& path) {
    validateCoordinateMap(map, path);
    // File rows are top-down; the map's are bottom-up.
    std::vector<float> red(std::size_t(map.width) * map.height), green(red.size());
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x) {
            const std::size_t i = std::size_t(map.height - 1 - y) * map.width + x;
            red[i] = float(map.sampleX(x, y));
            green[i] = float(map.sampleY(x, y));
        }
    writeFileAtomically(path, [&](const std::string& temporary) {
        try {
            Imf::Header header(map.width, map.height);
            header.compression() = Imf::ZIP_COMPRESSION;
            header.channels().insert("R", Imf::Channel(Imf::FLOAT));
            header.channels().insert("G", Imf::Channel(Imf::FLOAT));
            header.insert(kMapVersionAttribute, Imf::IntAttribute(kCoordinateMapVersion));
            header.insert(kSampleWidthAttribute, Imf::IntAttribute(map.sampleWidth));
            header.insert(kSampleHeightAttribute, Imf::IntAttribute(map.sampleHeight));
            Imf::OutputFile file(temporary.c_str(), header);
            Imf::FrameBuffer frame;
            const std::size_t row = sizeof(float) * std::size_t(map.width);
            frame.insert("R", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(red.data()),
                                         sizeof(float), row));
            frame.insert("G", Imf::Slice(Imf::FLOAT, reinterpret_cast<char*>(green.data()),
                                         sizeof(float), row));
            file.setFrameBuffer(frame);
            file.writePixels(map.height);
        } catch (const Error&) {
            throw;
        } catch (const std::exception& e) {
            fail(path, std::string("OpenEXR: ") + e.what());
        }
    });
}

CoordinateMap readCoordinateMap(const std::string& path) {
    // Pixels first: readFloatImage reports missing, truncated and corrupt files and checks the
    // memory limit before it allocates.
    const FloatImage image = readFloatImage(path);
    int version = 0, sampleWidth = 0, sampleHeight = 0;
    try {
        Imf::InputFile file(path.c_str());
        const Imf::Header& header = file.header();
        if (!header.findTypedAttribute<Imf::IntAttribute>(kMapVersionAttribute))
            fail(path, "not an osgBTF coordinate map (no osgBTF.coordinateMap attribute)");
        version = intAttribute(header, kMapVersionAttribute, path);
        sampleWidth = intAttribute(header, kSampleWidthAttribute, path);
        sampleHeight = intAttribute(header, kSampleHeightAttribute, path);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        fail(path, std::string("OpenEXR: ") + e.what());
    }
    if (version != kCoordinateMapVersion)
        fail(path, "coordinate map version " + std::to_string(version) +
                       " is not supported (this build reads version " +
                       std::to_string(kCoordinateMapVersion) + ")");
    const int r = image.channelIndex("R"), g = image.channelIndex("G");
    if (r < 0 || g < 0) fail(path, "coordinate map without R and G channels");

    CoordinateMap map;
    map.width = image.width;
    map.height = image.height;
    map.sampleWidth = sampleWidth;
    map.sampleHeight = sampleHeight;
    // The image is still held while the entries are filled: both must fit.
    checkMemory(saturatedProduct({std::uint64_t(image.width), std::uint64_t(image.height),
                                  std::uint64_t(image.channels) * 4 + 2 * sizeof(std::int32_t)}),
                path + ": coordinate map of " + std::to_string(image.width) + "x" +
                    std::to_string(image.height) + " entries");
    map.coordinates.resize(std::size_t(image.width) * image.height * 2);
    for (int y = 0; y < map.height; ++y)
        for (int x = 0; x < map.width; ++x) {
            const int fileRow = map.height - 1 - y;
            const float sx = image.at(x, fileRow, r), sy = image.at(x, fileRow, g);
            // Exact integers only: a fractional entry would render differently on the GPU
            // (nearest fetch) and the CPU (truncation).
            if (!std::isfinite(sx) || !std::isfinite(sy) || sx != std::floor(sx) ||
                sy != std::floor(sy) || std::fabs(sx) > 1e8f || std::fabs(sy) > 1e8f)
                fail(path, "entry (" + std::to_string(x) + ", " + std::to_string(y) +
                               ") is not a pair of integers");
            map.sampleX(x, y) = std::int32_t(sx);
            map.sampleY(x, y) = std::int32_t(sy);
        }
    validateCoordinateMap(map, path);
    return map;
}

MeasuredBtf materialiseCoordinateMap(const MeasuredBtf& sample, const CoordinateMap& map) {
    validateCoordinateMap(map, "coordinate map");
    if (map.sampleWidth != sample.width() || map.sampleHeight != sample.height())
        throw Error("coordinate map: made for a " + std::to_string(map.sampleWidth) + "x" +
                    std::to_string(map.sampleHeight) + " sample, not " +
                    std::to_string(sample.width()) + "x" + std::to_string(sample.height()));
    MeasuredBtf result(map.width, map.height, sample.views(), sample.lights(), sample.storage());
    const std::size_t texels = result.texelCount();
    std::vector<float> in, out(texels * 3);
    for (std::size_t v = 0; v < sample.views().size(); ++v)
        for (std::size_t l = 0; l < sample.lights().size(); ++l) {
            in = sample.image(v, l);
            for (int y = 0; y < map.height; ++y)
                for (int x = 0; x < map.width; ++x) {
                    const std::size_t from = map.sampleTexel(x, y) * 3;
                    const std::size_t to = (std::size_t(y) * map.width + x) * 3;
                    for (int c = 0; c < 3; ++c) out[to + c] = in[from + c];
                }
            result.setImage(v, l, out.data());
        }
    result.source = sample.source;
    return result;
}

}  // namespace osgBTF
