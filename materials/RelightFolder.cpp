// Reads top to bottom: the JPEG helpers, info.json, the planes, the type registry. The layout:
// RelightFolder.h and docs/formats.md section 8.4.
//
// JPEG decoding goes through the project's image codecs (core/ImageCodecs.h: OpenImageIO, whose
// JPEG reader is libjpeg-turbo's) rather than a direct libjpeg-turbo dependency: the codecs are
// already what every photograph of a capture is decoded with, they read from memory (the legacy
// .ptm's JPEG streams), they report a JPEG's size before decoding it (the memory guard sees it
// first), and they stay in their own lazily loaded module, so the render library links no image
// library. They ask libjpeg for RGB output, which decodes relight's planes whether they were
// written as YCbCr (colorspace rgb) or as untransformed RGB (the others).
#include "materials/RelightFolder.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <sstream>

#include <glm/geometric.hpp>
#include <nlohmann/json.hpp>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/ImageCodecs.h"
#include "core/MeasuredBtf.h"
#include "core/SizeGuard.h"
#include "materials/ForeignFiles.h"
#include "materials/Material.h"
#include "materials/RelightLayoutWriter.h"

namespace osgBTF {

namespace fs = std::filesystem;

// ---- JPEG --------------------------------------------------------------------------------------

void checkJpegComplete(const std::string& name, const unsigned char* bytes, std::size_t size) {
    if (size < 4 || bytes[0] != 0xFF || bytes[1] != 0xD8)
        fail(name, "not a JPEG (no start-of-image marker)");
    if (bytes[size - 2] != 0xFF || bytes[size - 1] != 0xD9)
        fail(name, "truncated JPEG (no end-of-image marker)");
}

std::vector<unsigned char> decodeJpeg(const std::string& name, const unsigned char* bytes,
                                      std::size_t size, int width, int height, int channels,
                                      const std::string& expected) {
    checkJpegComplete(name, bytes, size);
    std::string error;
    const std::unique_ptr<ImageReader> reader =
        imageCodecs().openBytes(bytes, size, "jpg", name, error);
    if (!reader) fail(name, error.empty() ? "not a readable JPEG" : error);
    reader->singleThreaded();
    const ImageHeader& h = reader->header();
    if (h.width != width || h.height != height || h.channels != channels || !h.eightBit)
        fail(name, "the JPEG is " + std::to_string(h.width) + "x" + std::to_string(h.height) +
                       " with " + std::to_string(h.channels) + " channel" +
                       (h.channels == 1 ? "" : "s") + ", " + expected);
    std::vector<unsigned char> pixels(std::size_t(width) * std::size_t(height) *
                                      std::size_t(channels));
    if (!reader->readBytes(pixels.data())) {
        const std::string message = reader->error();
        fail(name, message.empty() ? "cannot decode the JPEG" : message);
    }
    return pixels;
}

namespace {

// ---- info.json ---------------------------------------------------------------------------------

/** info.json is a few kilobytes (lights and 3 numbers per plane); anything far larger is no
 *  relight file, and is refused before it is read. */
constexpr std::uintmax_t kLargestInfo = 16u << 20;

std::string folderOf(const std::string& infoPath) {
    const fs::path folder = fs::path(infoPath).parent_path();
    return folder.empty() ? std::string(".") : folder.string();
}

std::string planeName(const std::string& infoPath, int j) {
    return (fs::path(folderOf(infoPath)) / ("plane_" + std::to_string(j) + ".jpg")).string();
}

/** The tiled layout whose files lie next to info.json, named as relight and OpenLIME name them;
 *  empty when none. */
std::string tiledLayout(const std::string& folder) {
    std::error_code ec;
    const fs::path d(folder);
    if (fs::exists(d / "plane_0.dzi", ec)) return "deepzoom (plane_0.dzi)";
    if (fs::exists(d / "planes.tzi", ec)) return "itarzoom (planes.tzi)";
    if (fs::exists(d / "plane_0.tzi", ec)) return "tarzoom (plane_0.tzi)";
    if (fs::exists(d / "plane_0" / "ImageProperties.xml", ec))
        return "zoomify (plane_0/ImageProperties.xml)";
    if (fs::is_directory(d / "plane_0", ec)) return "google (plane_0/)";
    return {};
}

double finiteNumber(const std::string& path, const nlohmann::json& value, const std::string& what) {
    if (!value.is_number()) fail(path, what + " is not a number");
    const double v = value.get<double>();
    if (!std::isfinite(v)) fail(path, what + " is not a finite number");
    return v;
}

long long integer(const std::string& path, const nlohmann::json& info, const char* key) {
    const auto it = info.find(key);
    if (it == info.end()) fail(path, std::string("no \"") + key + "\"");
    if (!it->is_number_integer()) fail(path, std::string("\"") + key + "\" is not an integer");
    return it->get<long long>();
}

std::string text(const std::string& path, const nlohmann::json& info, const char* key) {
    const auto it = info.find(key);
    if (it == info.end()) fail(path, std::string("no \"") + key + "\"");
    if (!it->is_string()) fail(path, std::string("\"") + key + "\" is not a string");
    return it->get<std::string>().substr(0, 32);
}

struct RelightType {
    RelightBuilder builder;
    RelightBasis basis = RelightBasis::Fixed;
};
std::map<std::string, RelightType>& relightTypeTable();
std::mutex& registryMutex();

/** The registered basis of a type (Fixed for a type no method reads: refused later by name). */
RelightBasis basisOf(const std::string& type) {
    std::lock_guard<std::mutex> lock(registryMutex());
    const auto it = relightTypeTable().find(type);
    return it == relightTypeTable().end() ? RelightBasis::Fixed : it->second.basis;
}

/** The registered PCA types (colorspaces mrgb, mycc), for messages: "bilinear, rbf". */
std::string pcaTypes() {
    std::lock_guard<std::mutex> lock(registryMutex());
    std::string list;
    for (const auto& entry : relightTypeTable())
        if (entry.second.basis != RelightBasis::Fixed)
            list += (list.empty() ? "" : ", ") + entry.first;
    return list;
}

/** The basis of relight's PCA types (colorspaces mrgb, mycc): "range" per plane, "sigma" (rbf) or
 *  "resolution" (bilinear), and "basis", (nplanes + 1) x nodes x 3 numbers. */
void parsePcaBasis(const std::string& path, const nlohmann::json& info,
                   const nlohmann::json& material, RelightPlanes& p) {
    const std::size_t planes = std::size_t(p.planeCount);
    std::size_t nodes = 0;
    if (p.basisKind == RelightBasis::GaussianNodes) {
        const auto sigma = info.find("sigma");
        if (sigma == info.end()) fail(path, "no \"sigma\" (type " + p.type + ")");
        p.sigma = finiteNumber(path, *sigma, "\"sigma\"");
        if (!(p.sigma > 0)) fail(path, "\"sigma\" " + sigma->dump() + " is not positive");
        if (p.rawLights.empty())
            fail(path, "no \"lights\" (type " + p.type + " interpolates between them)");
        nodes = p.rawLights.size();
    } else {
        const long long resolution = integer(path, info, "resolution");
        if (resolution < 2 || resolution > 64)
            fail(path, "\"resolution\" " + std::to_string(resolution) + " is not 2..64");
        p.resolution = int(resolution);
        nodes = std::size_t(resolution * resolution);
    }
    const auto range = material.find("range");
    if (range == material.end())
        fail(path, "no materials[0].range (colorspace " + p.colorspace + ")");
    if (!range->is_array() || range->size() != planes)
        fail(path, "materials[0].range has " +
                       (range->is_array() ? std::to_string(range->size()) : std::string("no")) +
                       " values, \"nplanes\" is " + std::to_string(planes));
    for (std::size_t m = 0; m < planes; ++m) {
        const double r =
            finiteNumber(path, (*range)[m], "materials[0].range[" + std::to_string(m) + "]");
        if (r == 0) fail(path, "materials[0].range[" + std::to_string(m) + "] is 0");
        p.range.push_back(r);
    }
    const auto basis = info.find("basis");
    if (basis == info.end()) fail(path, "no \"basis\" (colorspace " + p.colorspace + ")");
    const std::size_t expected = (planes + 1) * nodes * 3;
    if (!basis->is_array() || basis->size() != expected)
        fail(path, "\"basis\" has " +
                       (basis->is_array() ? std::to_string(basis->size()) : std::string("no")) +
                       " values, (nplanes + 1) x " + std::to_string(nodes) +
                       (p.basisKind == RelightBasis::GaussianNodes ? " lights" : " grid nodes") +
                       " x 3 is " + std::to_string(expected));
    p.basis.reserve(expected);
    for (std::size_t i = 0; i < expected; ++i)
        p.basis.push_back(finiteNumber(path, (*basis)[i], "\"basis\"[" + std::to_string(i) + "]"));
}

struct Quantisation {
    std::vector<double> scale, bias;
};

RelightPlanes parseInfo(const std::string& path, Quantisation& quantisation) {
    std::error_code ec;
    if (fs::is_directory(path, ec)) fail(path, "is a folder; name its info.json");
    const std::uintmax_t size = fs::file_size(path, ec);
    if (ec) fail(path, "cannot be read: " + ec.message());
    if (size > kLargestInfo)
        fail(path, "is " + std::to_string(size) +
                       " bytes, too large for a relight info.json (at most 16 MiB)");
    nlohmann::json info;
    try {
        info = nlohmann::json::parse(readWholeFile(path));
    } catch (const nlohmann::json::exception& e) {
        fail(path, std::string("not JSON: ") + e.what());
    }
    if (!info.is_object()) fail(path, "not a relight info.json (not a JSON object)");
    RelightPlanes p;
    p.type = text(path, info, "type");
    p.colorspace = text(path, info, "colorspace");
    if (info.contains("format") && info["format"] != "jpg")
        fail(path, "\"format\" is " + info["format"].dump().substr(0, 32) +
                       " (planes in \"jpg\" are read)");
    const bool mixed = p.colorspace == "mrgb" || p.colorspace == "mycc";
    if (p.colorspace != "rgb" && p.colorspace != "lrgb" && !mixed)
        fail(path, "colorspace '" + p.colorspace + "' is not read (rgb, lrgb, mrgb and mycc are)");
    // relight writes its PCA types in mrgb or mycc only, the others never so.
    p.basisKind = basisOf(p.type);
    const bool pca = p.basisKind != RelightBasis::Fixed;
    if (pca && !mixed)
        fail(path, "type '" + p.type + "' with colorspace '" + p.colorspace +
                       "' (relight writes its PCA types in mrgb or mycc)");
    if (!pca && mixed)
        fail(path, "colorspace " + p.colorspace + " with type '" + p.type +
                       "' (relight writes mrgb and mycc for its PCA types: " + pcaTypes() + ")");
    long long planes = 0;
    if (p.colorspace == "mycc") {
        // mycc: "yccplanes" (luminance, then the two chroma counts) instead of "nplanes".
        const auto ycc = info.find("yccplanes");
        if (ycc == info.end()) fail(path, "no \"yccplanes\" (colorspace mycc)");
        if (!ycc->is_array() || ycc->size() != 3) fail(path, "\"yccplanes\" is not 3 integers");
        for (std::size_t k = 0; k < 3; ++k) {
            if (!(*ycc)[k].is_number_integer() || (*ycc)[k].get<long long>() < 0 ||
                (*ycc)[k].get<long long>() > 3 * 64)
                fail(path, "\"yccplanes\" is not 3 integers in 0..192");
            p.yccPlanes[k] = int((*ycc)[k].get<long long>());
        }
        if (p.yccPlanes[1] != p.yccPlanes[2] || p.yccPlanes[0] < p.yccPlanes[1])
            fail(path, "\"yccplanes\" " + ycc->dump() +
                           " (relight's renderer reads luminance planes >= chroma planes, the "
                           "two chroma counts equal)");
        planes = p.yccPlanes[0] + p.yccPlanes[1] + p.yccPlanes[2];
    } else {
        planes = integer(path, info, "nplanes");
    }
    if (planes < 1 || planes > 3 * 64)
        fail(path, "\"nplanes\" " + std::to_string(planes) + " is not 1..192");
    p.planeCount = int(planes);
    if (pca) {
        p.terms = int(planes);
    } else if (p.luminance()) {
        if (planes < 4)
            fail(path,
                 "colorspace lrgb needs 3 colour planes and at least one luminance plane, "
                 "\"nplanes\" is " +
                     std::to_string(planes));
        p.terms = int(planes) - 3;
    } else {
        if (planes % 3 != 0)
            fail(path, "colorspace rgb holds 3 planes per term, \"nplanes\" " +
                           std::to_string(planes) + " is not a multiple of 3");
        p.terms = int(planes) / 3;
    }
    for (const char* key : {"width", "height"})
        if (info.contains(key)) {
            const long long v = integer(path, info, key);
            if (v < 1 || v > (1 << 20))
                fail(path,
                     std::string("\"") + key + "\" " + std::to_string(v) + " is not 1..1048576");
            (key[0] == 'w' ? p.width : p.height) = int(v);
        }
    const auto materials = info.find("materials");
    if (materials == info.end()) fail(path, "no \"materials\"");
    if (!materials->is_array() || materials->size() != 1 || !(*materials)[0].is_object())
        fail(path, "\"materials\" is not an array of one object (one material is read)");
    const nlohmann::json& material = (*materials)[0];
    for (const char* key : {"scale", "bias"}) {
        const auto values = material.find(key);
        if (values == material.end()) fail(path, std::string("no materials[0].") + key);
        if (!values->is_array() || values->size() != std::size_t(planes))
            fail(path, std::string("materials[0].") + key + " has " +
                           (values->is_array() ? std::to_string(values->size()) : "no") +
                           " values, \"nplanes\" is " + std::to_string(planes));
        std::vector<double>& out = key[0] == 's' ? quantisation.scale : quantisation.bias;
        for (std::size_t m = 0; m < values->size(); ++m)
            out.push_back(
                finiteNumber(path, (*values)[m],
                             std::string("materials[0].") + key + "[" + std::to_string(m) + "]"));
    }
    if (const auto lights = info.find("lights"); lights != info.end()) {
        if (!lights->is_array() || lights->size() % 3 != 0 || lights->size() > 3 * 100000)
            fail(path, "\"lights\" is not a list of x, y, z triples");
        for (std::size_t i = 0; i < lights->size(); i += 3) {
            glm::vec3 l;
            for (int a = 0; a < 3; ++a)
                l[a] =
                    float(finiteNumber(path, (*lights)[i + std::size_t(a)],
                                       "\"lights\"[" + std::to_string(i + std::size_t(a)) + "]"));
            if (glm::length(l) <= 0) fail(path, "light " + std::to_string(i / 3) + " is zero");
            p.rawLights.push_back(l);
            p.lights.push_back(glm::normalize(l));
        }
    }
    if (pca) parsePcaBasis(path, info, material, p);
    const std::string folder = folderOf(path);
    if (!fs::exists(planeName(path, 0), ec)) {
        const std::string layout = tiledLayout(folder);
        if (layout.rfind("deepzoom", 0) == 0) {
            p.deepZoom = true;
            return p;
        }
        if (!layout.empty())
            fail(path, "relight's tiled layout " + layout +
                           " is not read; the single-image (plane_0.jpg ...) and deep-zoom "
                           "(plane_0.dzi ...) layouts are");
        fail(planeName(path, 0), "no such file (the first plane of " + path + ")");
    }
    return p;
}

// ---- the registry ------------------------------------------------------------------------------

std::map<std::string, RelightType>& relightTypeTable() {
    static std::map<std::string, RelightType> types;
    return types;
}

std::mutex& registryMutex() {
    static std::mutex m;
    return m;
}

}  // namespace

// ---- the deep-zoom layout ----------------------------------------------------------------------

namespace {

/** An attribute's integer value in a .dzi (Microsoft's Deep Zoom XML: one Image element with
 *  Format, Overlap and TileSize, one Size element with Width and Height); -1 when absent. */
long long dziAttribute(const std::string& xml, const std::string& name) {
    const std::string key = name + "=\"";
    const std::size_t at = xml.find(key);
    if (at == std::string::npos) return -1;
    std::size_t end = at + key.size();
    long long value = 0;
    for (; end < xml.size() && std::isdigit(static_cast<unsigned char>(xml[end])); ++end) {
        value = value * 10 + (xml[end] - '0');
        if (value > (1LL << 31)) return -1;
    }
    return end < xml.size() && xml[end] == '"' && end > at + key.size() ? value : -1;
}

struct DziHeader {
    std::string path;
    int tileSize = 0, overlap = 0, width = 0, height = 0;
};

DziHeader readDzi(const std::string& infoPath, int j) {
    DziHeader d;
    d.path = (fs::path(folderOf(infoPath)) / ("plane_" + std::to_string(j) + ".dzi")).string();
    std::error_code ec;
    if (!fs::is_regular_file(d.path, ec))
        fail(d.path, "no such file (the deep-zoom layout of " + infoPath + ")");
    if (fs::file_size(d.path, ec) > 65536) fail(d.path, "is too large for a .dzi (at most 64 KiB)");
    const std::string xml = readWholeFile(d.path);
    if (xml.find("<Image") == std::string::npos) fail(d.path, "not a Deep Zoom .dzi (no <Image>)");
    const long long tile = dziAttribute(xml, "TileSize"), overlap = dziAttribute(xml, "Overlap");
    const long long w = dziAttribute(xml, "Width"), h = dziAttribute(xml, "Height");
    if (tile < 1 || tile > 8192 || overlap < 0 || overlap >= tile)
        fail(d.path,
             "TileSize and Overlap are not integers with 1 <= TileSize <= 8192 and 0 <= "
             "Overlap < TileSize");
    if (xml.find("Format=\"jpg\"") == std::string::npos &&
        xml.find("Format=\"jpeg\"") == std::string::npos)
        fail(d.path, "Format is not \"jpg\" (tiles in JPEG are read)");
    if (w < 1 || h < 1 || w > (1 << 20) || h > (1 << 20))
        fail(d.path, "Size Width and Height are not 1..1048576");
    d.tileSize = int(tile);
    d.overlap = int(overlap);
    d.width = int(w);
    d.height = int(h);
    return d;
}

/** The full-size level of plane_j.dzi's pyramid (relight's deep-zoom numbering,
 *  RelightLayoutWriter.h deepZoomLevels), its tiles put together: width x height x 3 bytes,
 *  rows top down. */
std::vector<unsigned char> readDeepZoomPlane(const std::string& infoPath, int j, int width,
                                             int height) {
    const DziHeader d = readDzi(infoPath, j);
    if (d.width != width || d.height != height)
        fail(d.path, "Size is " + std::to_string(d.width) + "x" + std::to_string(d.height) +
                         ", info.json gives " + std::to_string(width) + "x" +
                         std::to_string(height));
    const int ts = d.tileSize, ov = d.overlap;
    const int level = int(deepZoomLevels(width, height, ts).size()) - 1;
    const fs::path levelFolder = fs::path(folderOf(infoPath)) /
                                 ("plane_" + std::to_string(j) + "_files") / std::to_string(level);
    std::vector<unsigned char> pixels(std::size_t(width) * std::size_t(height) * 3);
    const int cols = (width + ts - 1) / ts, rows = (height + ts - 1) / ts;
    std::error_code ec;
    for (int row = 0; row < rows; ++row)
        for (int col = 0; col < cols; ++col) {
            const int x0 = std::max(0, col * ts - ov), y0 = std::max(0, row * ts - ov);
            const int x1 = std::min(width, (col + 1) * ts + ov);
            const int y1 = std::min(height, (row + 1) * ts + ov);
            const std::string name =
                (levelFolder / (std::to_string(col) + "_" + std::to_string(row) + ".jpg")).string();
            if (!fs::is_regular_file(name, ec))
                fail(name, "no such file (tile " + std::to_string(col) + "," + std::to_string(row) +
                               " of level " + std::to_string(level) + ", the full size of " +
                               d.path + ")");
            const std::string bytes = readWholeFile(name);
            const std::vector<unsigned char> tile =
                decodeJpeg(name, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(),
                           x1 - x0, y1 - y0, 3,
                           "its place in " + d.path + " gives " + std::to_string(x1 - x0) + "x" +
                               std::to_string(y1 - y0) + " with 3 channels");
            // The tile's own pixels, without the overlap it shares with its neighbours.
            const int ix = col * ts, iy = row * ts;
            const int iw = std::min(width, ix + ts) - ix, ih = std::min(height, iy + ts) - iy;
            for (int y = 0; y < ih; ++y)
                std::copy_n(tile.data() + (std::size_t(y + iy - y0) * std::size_t(x1 - x0) +
                                           std::size_t(ix - x0)) *
                                              3,
                            std::size_t(iw) * 3,
                            pixels.data() +
                                (std::size_t(y + iy) * std::size_t(width) + std::size_t(ix)) * 3);
        }
    return pixels;
}

/** plane_j.jpg, decoded: width x height x 3 bytes, rows top down. */
std::vector<unsigned char> readPlaneJpeg(const std::string& infoPath, int j, const RelightPlanes& p,
                                         const std::string& expected) {
    const int jpegs = (p.planeCount + 2) / 3;
    const std::string name = planeName(infoPath, j);
    std::error_code ec;
    if (!fs::is_regular_file(name, ec))
        fail(name, "no such file (" + infoPath + " has " + std::to_string(p.planeCount) +
                       " planes: plane_0.jpg .. plane_" + std::to_string(jpegs - 1) + ".jpg)");
    const std::uintmax_t size = fs::file_size(name, ec);
    if (ec) fail(name, "cannot be read: " + ec.message());
    checkMemory(size, name);
    const std::string bytes = readWholeFile(name);
    return decodeJpeg(name, reinterpret_cast<const unsigned char*>(bytes.data()), bytes.size(),
                      p.width, p.height, 3, expected);
}

}  // namespace

RelightPlanes readRelightHeader(const std::string& infoPath) {
    Quantisation q;
    return parseInfo(infoPath, q);
}

RelightPlanes readRelightPlanes(const std::string& infoPath) {
    Quantisation q;
    RelightPlanes p = parseInfo(infoPath, q);
    const int jpegs = (p.planeCount + 2) / 3;
    if (p.deepZoom && (p.width == 0 || p.height == 0)) {
        const DziHeader d = readDzi(infoPath, 0);
        p.width = d.width;
        p.height = d.height;
    } else if (p.width == 0 || p.height == 0) {
        // Without width and height in info.json (OpenLIME does not need them): plane_0's size.
        std::string error;
        const std::string first = planeName(infoPath, 0);
        const std::unique_ptr<ImageReader> reader = imageCodecs().openFile(first, 0, error);
        if (!reader) fail(first, error.empty() ? "not a readable JPEG" : error);
        p.width = reader->header().width;
        p.height = reader->header().height;
        if (p.width < 1 || p.height < 1 || p.width > (1 << 20) || p.height > (1 << 20))
            fail(first, "size " + std::to_string(p.width) + "x" + std::to_string(p.height) +
                            " is not 1..1048576 on each side");
    }
    const std::size_t texels = std::size_t(p.width) * std::size_t(p.height);
    // The float planes and one decoded JPEG, before either exists.
    checkMemory(saturatedProduct({std::uint64_t(p.planeCount), texels, sizeof(float)}) +
                    saturatedProduct({texels, 3}),
                infoPath + ": " + std::to_string(p.planeCount) + " planes of " +
                    std::to_string(p.width) + "x" + std::to_string(p.height));
    p.planes.assign(std::size_t(p.planeCount) * texels, 0.0f);
    const std::string expected = "info.json gives " + std::to_string(p.width) + "x" +
                                 std::to_string(p.height) + " with 3 channels";
    for (int j = 0; j < jpegs; ++j) {
        const std::vector<unsigned char> pixels =
            p.deepZoom ? readDeepZoomPlane(infoPath, j, p.width, p.height)
                       : readPlaneJpeg(infoPath, j, p, expected);
        for (int c = 0; c < 3; ++c) {
            const int m = 3 * j + c;
            if (m >= p.planeCount) break;  // the unused channels of the last JPEG
            const double scale = q.scale[std::size_t(m)], bias = q.bias[std::size_t(m)];
            float* plane = p.planes.data() + std::size_t(m) * texels;
            for (int row = 0; row < p.height; ++row) {
                // JPEG rows run top down; the material's from the bottom up.
                const std::size_t y = std::size_t(p.height - 1 - row);
                for (std::size_t x = 0; x < std::size_t(p.width); ++x) {
                    const double byte =
                        pixels[(std::size_t(row) * std::size_t(p.width) + x) * 3 + std::size_t(c)];
                    plane[y * std::size_t(p.width) + x] = float((byte / 255.0 - bias) * scale);
                }
            }
        }
    }
    return p;
}

bool registerRelightType(const std::string& type, RelightBuilder builder, RelightBasis basis) {
    std::lock_guard<std::mutex> lock(registryMutex());
    relightTypeTable()[type] = RelightType{std::move(builder), basis};
    return true;
}

std::vector<std::string> relightTypes() {
    std::lock_guard<std::mutex> lock(registryMutex());
    std::vector<std::string> types;
    for (const auto& entry : relightTypeTable()) types.push_back(entry.first);
    return types;
}

namespace {

RelightBuilder builderFor(const std::string& infoPath, const std::string& type) {
    std::lock_guard<std::mutex> lock(registryMutex());
    const auto it = relightTypeTable().find(type);
    if (it != relightTypeTable().end()) return it->second.builder;
    std::string known;
    for (const auto& entry : relightTypeTable()) known += (known.empty() ? "" : ", ") + entry.first;
    fail(infoPath, "type '" + type + "' is not read (" + known + " are)");
}

/** A number as info.json would write it (6 significant digits). */
std::string shortNumber(double value) {
    std::ostringstream text;
    text << value;
    return text.str();
}

}  // namespace

osg::ref_ptr<Material> readRelightMaterial(const std::string& infoPath) {
    // The type first: a folder of another type is refused before its planes are decoded.
    const RelightBuilder builder = builderFor(infoPath, readRelightHeader(infoPath).type);
    const RelightPlanes planes = readRelightPlanes(infoPath);
    osg::ref_ptr<Material> material = builder(infoPath, planes);
    material->sourceFile = infoPath;
    material->fitInfo["file-format"] =
        "relight web layout, type " + planes.type + ", colorspace " + planes.colorspace;
    return material;
}

std::string relightInfo(const std::string& infoPath) {
    const RelightPlanes p = readRelightHeader(infoPath);
    builderFor(infoPath, p.type);
    return std::string("relight web layout (") +
           (p.deepZoom ? "deep-zoom pyramids" : "single images") + "), type " + p.type +
           ", colorspace " + p.colorspace + ", " + std::to_string(p.planeCount) + " planes (" +
           std::to_string(p.terms) + " terms) in " + std::to_string((p.planeCount + 2) / 3) +
           (p.deepZoom ? " pyramids" : " JPEGs") +
           (p.width ? ", " + std::to_string(p.width) + "x" + std::to_string(p.height) : "") +
           "\nlights: " +
           (p.lights.empty() ? std::string("none recorded")
                             : std::to_string(p.lights.size()) + " recorded") +
           (p.basisKind == RelightBasis::GaussianNodes
                ? "\nbasis: the lights' PCA profiles, Gaussian weights, sigma " +
                      shortNumber(p.sigma)
            : p.resolution > 0
                ? "\nbasis: PCA profiles on a " + std::to_string(p.resolution) + "x" +
                      std::to_string(p.resolution) + " octahedral grid, bilinear weights"
                : std::string());
}

DirectionSet relightLights(const std::string& infoPath, const RelightPlanes& planes) {
    if (planes.lights.empty()) return nominalFileLights();
    std::vector<Direction> directions;
    for (const glm::vec3& l : planes.lights) directions.push_back(Direction::fromVector(l));
    return DirectionSet(infoPath + " lights", std::move(directions));
}

}  // namespace osgBTF
