// Reads top to bottom: the writer registry, quantisation (relight's, from RtiBuilder), the
// deep-zoom pyramid (relight's DeepZoom), info.json and index.html, then writeRelightLayout putting
// it together. relight (cnr-isti-vclab/relight, snapshot 5cca5c3e) is GPL: its files were read for
// the description (src/cli/rtibuilder.cpp minmaxMaterial, finalizeMaterial, save, saveJSON;
// src/material.h Plane::quantize; src/deepzoom.cpp nLevels, initRows, downsampleGaussian,
// tileFilePath, finalizeMetadata; relightlab/zoom.cpp and src/rti/rtitask.cpp for the tile size
// and overlap), no code was taken.
#include "materials/RelightLayoutWriter.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <sstream>

#include <unistd.h>

#include <nlohmann/json.hpp>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/ImageCodecs.h"
#include "core/Progress.h"
#include "materials/ForeignFiles.h"
#include "materials/Material.h"

namespace osgBTF {

namespace fs = std::filesystem;

// ---- the registry ------------------------------------------------------------------------------

namespace {

std::map<std::string, RelightModelMaker>& writerTable() {
    static std::map<std::string, RelightModelMaker> writers;
    return writers;
}

std::mutex& writerMutex() {
    static std::mutex m;
    return m;
}

}  // namespace

bool registerRelightWriter(const std::string& method, RelightModelMaker maker) {
    std::lock_guard<std::mutex> lock(writerMutex());
    writerTable()[method] = std::move(maker);
    return true;
}

RelightModel relightModelFrame(const Material& material, const std::string& infoPath,
                               const std::string& type, const std::string& colorspace,
                               int planeCount) {
    if (material.mipLayout().levelCount() > 0)
        fail(infoPath, "relight's web layout has no mip levels: fit with --no-mipmap");
    RelightModel model;
    model.type = type;
    model.colorspace = colorspace;
    model.width = material.width();
    model.height = material.height();
    model.planeCount = planeCount;
    model.planes.assign(std::size_t(planeCount) * material.texelCount(), 0.0f);
    for (std::size_t i = 0; i < material.lights().size(); ++i)
        model.lights.push_back(material.lights().vector(i));
    return model;
}

std::vector<std::string> relightWriterMethods() {
    std::lock_guard<std::mutex> lock(writerMutex());
    std::vector<std::string> methods;
    for (const auto& entry : writerTable()) methods.push_back(entry.first);
    return methods;
}

// ---- quantisation ------------------------------------------------------------------------------

unsigned char RelightQuantisation::quantise(float value) const {
    // relight: int v = 255 * (value / scale + bias), truncated, clamped to 0..255.
    const double v = 255.0 * (double(value) / double(scale) + double(bias));
    if (!(v > 0)) return 0;  // NaN too
    return v >= 255 ? 255 : static_cast<unsigned char>(int(v));
}

RelightQuantisation relightRange(std::vector<float>& values, double quantile) {
    RelightQuantisation q;
    const std::size_t n = values.size();
    if (n == 0) return q;
    const std::size_t low = std::min(std::size_t((1.0 - quantile) / 2.0 * double(n)), n - 1);
    const std::size_t high = std::min(std::size_t((1.0 + quantile) / 2.0 * double(n)), n - 1);
    std::nth_element(values.begin(), values.begin() + std::ptrdiff_t(low), values.end());
    const float min = values[low];
    std::nth_element(values.begin() + std::ptrdiff_t(low), values.begin() + std::ptrdiff_t(high),
                     values.end());
    float max = values[high];
    // relight adds 1e-6 in its 0..255 units; a float min much above 1e-6 swallows that (scale 0,
    // then a division by 0), so the step is also at least min's own precision.
    if (max <= min) max = min + std::max(1e-6f / 255.0f, std::fabs(min) * 1e-5f);
    q.scale = max - min;
    q.bias = -min / q.scale;
    return q;
}

std::vector<int> quantiseRelightBasis(const RelightModel& model, std::vector<double>& range) {
    const std::size_t planes = std::size_t(model.planeCount);
    const std::size_t nodes = model.basis.size() / (planes + 1);
    std::vector<int> bytes;
    bytes.reserve(model.basis.size() * 3);
    range.assign(planes, 0.0);
    for (std::size_t i = 0; i < nodes; ++i)
        for (int c = 0; c < 3; ++c)
            bytes.push_back(std::clamp(int(255.0 * double(model.basis[i][c])), 0, 255));
    for (std::size_t p = 0; p < planes; ++p) {
        const glm::vec3* e = model.basis.data() + (p + 1) * nodes;
        float largest = 0;
        for (std::size_t i = 0; i < nodes; ++i)
            for (int c = 0; c < 3; ++c) largest = std::max(largest, std::fabs(e[i][c]));
        // A principal profile of zeros (a constant capture): any range reads it back as zeros.
        const float r = largest > 0 ? 127.0f / largest : 1.0f;
        range[p] = r;
        for (std::size_t i = 0; i < nodes; ++i)
            for (int c = 0; c < 3; ++c) bytes.push_back(int(127.0f + r * e[i][c]));
    }
    return bytes;
}

// ---- the deep-zoom pyramid ---------------------------------------------------------------------

std::vector<std::pair<int, int>> deepZoomLevels(int width, int height, int tileSize) {
    std::vector<std::pair<int, int>> levels{{width, height}};
    while (levels.back().first > tileSize || levels.back().second > tileSize)
        levels.push_back(
            {std::max(1, levels.back().first >> 1), std::max(1, levels.back().second >> 1)});
    std::reverse(levels.begin(), levels.end());
    return levels;
}

namespace {

/** An 8-bit RGB image, rows top down (as JPEGs store them). */
struct ByteImage {
    int width = 0, height = 0;
    std::vector<unsigned char> rgb;
};

/** Half the size (truncated, at least 1), each output pixel the 5-tap binomial (1 4 6 4 1) / 16
 *  around input pixel 2 x + 1, edges clamped, rounded: relight's downsampleGaussian. */
ByteImage halve(const ByteImage& in) {
    ByteImage out;
    out.width = std::max(1, in.width >> 1);
    out.height = std::max(1, in.height >> 1);
    constexpr int kKernel[5] = {1, 4, 6, 4, 1};
    const auto clampTo = [](int v, int size) { return std::clamp(v, 0, size - 1); };
    std::vector<unsigned char> rows(std::size_t(out.width) * std::size_t(in.height) * 3);
    for (int y = 0; y < in.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < 3; ++c) {
                int sum = 0;
                for (int k = -2; k <= 2; ++k)
                    sum += kKernel[k + 2] * in.rgb[(std::size_t(y) * std::size_t(in.width) +
                                                    std::size_t(clampTo(2 * x + 1 + k, in.width))) *
                                                       3 +
                                                   std::size_t(c)];
                rows[(std::size_t(y) * std::size_t(out.width) + std::size_t(x)) * 3 +
                     std::size_t(c)] = static_cast<unsigned char>((sum + 8) / 16);
            }
    out.rgb.resize(std::size_t(out.width) * std::size_t(out.height) * 3);
    for (int y = 0; y < out.height; ++y)
        for (int x = 0; x < out.width; ++x)
            for (int c = 0; c < 3; ++c) {
                int sum = 0;
                for (int k = -2; k <= 2; ++k)
                    sum += kKernel[k + 2] * rows[(std::size_t(clampTo(2 * y + 1 + k, in.height)) *
                                                      std::size_t(out.width) +
                                                  std::size_t(x)) *
                                                     3 +
                                                 std::size_t(c)];
                out.rgb[(std::size_t(y) * std::size_t(out.width) + std::size_t(x)) * 3 +
                        std::size_t(c)] = static_cast<unsigned char>((sum + 8) / 16);
            }
    return out;
}

void writeBytes(const std::string& path, const std::vector<unsigned char>& bytes) {
    std::ofstream out(path, std::ios::binary);
    out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
    out.close();
    if (!out) fail(path, "cannot be written");
}

std::vector<unsigned char> encodeJpeg(const std::string& name, const unsigned char* rgb, int width,
                                      int height, int quality) {
    std::vector<unsigned char> encoded;
    std::string error;
    if (!imageCodecs().encode(width, height, rgb, nullptr, "jpg", quality, encoded, error, true))
        fail(name, "cannot encode the JPEG: " + error);
    return encoded;
}

/** plane_j.dzi and plane_j_files/LEVEL/COL_ROW.jpg in `folder`: tile (col, row) of a level holds
 *  its pixels from col * tile - overlap (0 for the first column) to (col + 1) * tile + overlap,
 *  clipped to the level (DeepZoom's tileFilePath and TileRow::writeLine). */
void writeDeepZoom(const std::string& folder, const std::string& stem, ByteImage image,
                   const RelightWriteOptions& options, Progress& progress) {
    const std::vector<std::pair<int, int>> levels =
        deepZoomLevels(image.width, image.height, options.tileSize);
    const int ts = options.tileSize, ov = options.overlap;
    for (int level = int(levels.size()) - 1; level >= 0; --level) {
        const fs::path dir = fs::path(folder) / (stem + "_files") / std::to_string(level);
        fs::create_directories(dir);
        const int cols = (image.width + ts - 1) / ts, rows = (image.height + ts - 1) / ts;
        for (int row = 0; row < rows; ++row)
            for (int col = 0; col < cols; ++col) {
                const int x0 = std::max(0, col * ts - ov), y0 = std::max(0, row * ts - ov);
                const int x1 = std::min(image.width, (col + 1) * ts + ov);
                const int y1 = std::min(image.height, (row + 1) * ts + ov);
                std::vector<unsigned char> tile(std::size_t(x1 - x0) * std::size_t(y1 - y0) * 3);
                for (int y = y0; y < y1; ++y)
                    std::copy_n(
                        image.rgb.data() +
                            (std::size_t(y) * std::size_t(image.width) + std::size_t(x0)) * 3,
                        std::size_t(x1 - x0) * 3,
                        tile.data() + std::size_t(y - y0) * std::size_t(x1 - x0) * 3);
                const std::string name =
                    (dir / (std::to_string(col) + "_" + std::to_string(row) + ".jpg")).string();
                writeBytes(name, encodeJpeg(name, tile.data(), x1 - x0, y1 - y0, options.quality));
            }
        progress.advance();
        if (level > 0) image = halve(image);
    }
    std::ostringstream dzi;
    dzi << "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
        << "<Image xmlns=\"http://schemas.microsoft.com/deepzoom/2008\"\n"
        << "  Format=\"jpg\"\n"
        << "  Overlap=\"" << ov << "\"\n"
        << "  TileSize=\"" << ts << "\">\n"
        << "  <Size Height=\"" << levels.back().second << "\" Width=\"" << levels.back().first
        << "\"/>\n"
        << "</Image>\n";
    const std::string name = (fs::path(folder) / (stem + ".dzi")).string();
    const std::string text = dzi.str();
    writeBytes(name, std::vector<unsigned char>(text.begin(), text.end()));
}

// ---- info.json and index.html ------------------------------------------------------------------

/** A float as JSON writes it back to the same float (shortest text). */
double jsonFloat(float value) {
    return std::stod(floatText(value));
}

std::string infoJson(const RelightModel& model, const std::vector<RelightQuantisation>& q,
                     const std::vector<int>& basis, const std::vector<double>& range, int quality) {
    // relight's key order (RtiBuilder::saveJSON).
    nlohmann::ordered_json info;
    info["width"] = model.width;
    info["height"] = model.height;
    info["format"] = "jpg";
    info["type"] = model.type;
    // The PCA types' interpolation: bilinear's grid resolution, rbf's sigma (with its lights).
    if (model.resolution > 0) info["resolution"] = model.resolution;
    info["colorspace"] = model.colorspace;
    if (!model.lights.empty()) {
        if (model.sigma > 0) info["sigma"] = jsonFloat(model.sigma);
        nlohmann::json lights = nlohmann::json::array();
        for (const glm::vec3& l : model.lights)
            for (int a = 0; a < 3; ++a)
                lights.push_back(std::round(double(l[a]) * 1000.0) / 1000.0);
        info["lights"] = lights;
    }
    info["nplanes"] = model.planeCount;
    info["quality"] = quality;
    if (!basis.empty()) info["basis"] = basis;
    nlohmann::ordered_json material;
    if (!range.empty()) {
        nlohmann::json r = nlohmann::json::array();
        for (const double v : range) r.push_back(jsonFloat(float(v)));
        material["range"] = r;
    }
    nlohmann::json scale = nlohmann::json::array(), bias = nlohmann::json::array();
    for (const RelightQuantisation& plane : q) {
        scale.push_back(jsonFloat(plane.scale));
        bias.push_back(jsonFloat(plane.bias));
    }
    material["scale"] = scale;
    material["bias"] = bias;
    info["materials"] = nlohmann::json::array({material});
    // One key per line, each value on its line (relight's look; a JSON parser sees no difference).
    std::string text = "{\n";
    for (auto it = info.begin(); it != info.end(); ++it)
        text += (it == info.begin() ? "" : ",\n") + nlohmann::json(it.key()).dump() + ": " +
                it.value().dump();
    return text + "\n}\n";
}

std::string indexHtml(const RelightModel& model, bool deepZoom) {
    const std::string layout = deepZoom ? "deepzoom" : "image";
    std::ostringstream html;
    html << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
         << "<title>Relightable image (" << model.type << ", " << model.width << "x" << model.height
         << ")</title>\n"
         << "<link rel=\"stylesheet\" href=\"openlime.min.css\">\n"
         << "<style>html,body{margin:0;height:100%;font-family:sans-serif}"
            "#viewer{width:100%;height:100%}#help{padding:1em;max-width:50em}</style>\n"
         << "</head>\n<body>\n<div id=\"viewer\"></div>\n<div id=\"help\" hidden>\n"
         << "<h1>A relightable image</h1>\n"
         << "<p>This folder is relight's web layout (type <code>" << model.type
         << "</code>, colorspace <code>" << model.colorspace << "</code>, " << model.planeCount
         << " coefficient planes, " << model.width << " x " << model.height
         << " pixels, layout <code>" << layout << "</code>), written by osgBTF. It is shown by "
         << "<a href=\"https://github.com/cnr-isti-vclab/openlime\">OpenLIME</a>, a separate "
            "project (GPL) that this folder does not include.</p>\n"
         << "<p>To view it: copy OpenLIME's <code>dist/js/openlime.min.js</code> and "
            "<code>dist/css/openlime.min.css</code> next to this file, serve the folder over HTTP "
            "(for instance <code>python3 -m http.server</code>) and open this page; drag with the "
            "light tool to move the light.</p>\n"
         << "</div>\n<script src=\"openlime.min.js\"></script>\n<script>\n"
         << "if (typeof OpenLIME === 'undefined') {\n"
         << "  document.getElementById('help').hidden = false;\n"
         << "  document.getElementById('viewer').hidden = true;\n"
         << "} else {\n"
         << "  const lime = new OpenLIME.Viewer('#viewer');\n"
         << "  const layer = new OpenLIME.Layer({ type: 'rti', url: 'info.json', layout: '"
         << layout << "', normals: false });\n"
         << "  lime.addLayer('rti', layer);\n"
         << "  new OpenLIME.UIBasic(lime);\n"
         << "}\n</script>\n</body>\n</html>\n";
    return html.str();
}

/** plane_* entries an earlier export left (another layout or more planes). */
void removeEarlierPlanes(const fs::path& folder) {
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder, ec)) {
        const std::string name = entry.path().filename().string();
        if (name.rfind("plane_", 0) == 0) fs::remove_all(entry.path(), ec);
    }
}

}  // namespace

// ---- the layout --------------------------------------------------------------------------------

std::string writeRelightLayout(const Material& material, const std::string& infoPath,
                               const RelightWriteOptions& options) {
    if (fs::path(infoPath).filename() != "info.json")
        fail(infoPath, "relight's web layout is a folder named by its info.json (DIR/info.json)");
    if (options.quality < 1 || options.quality > 100)
        fail(infoPath, "JPEG quality " + std::to_string(options.quality) + " is not 1..100");
    if (options.tileSize < 16 || options.tileSize > 4096 || options.overlap < 0 ||
        options.overlap > options.tileSize / 2)
        fail(infoPath, "tile size " + std::to_string(options.tileSize) + " with overlap " +
                           std::to_string(options.overlap) +
                           " (tiles of 16..4096 pixels, overlap at most half a tile)");
    if (!(options.rangeQuantile > 0 && options.rangeQuantile <= 1))
        fail(infoPath, "range quantile is not in (0, 1]");
    RelightModelMaker maker;
    {
        std::lock_guard<std::mutex> lock(writerMutex());
        const auto it = writerTable().find(material.methodName());
        if (it != writerTable().end()) maker = it->second;
    }
    if (!maker) {
        std::string methods;
        for (const std::string& m : relightWriterMethods())
            methods += (methods.empty() ? "" : ", ") + m;
        fail(infoPath, "relight's web layout holds materials of " + methods + ", not " +
                           material.methodName());
    }
    const RelightModel model = maker(material, infoPath);
    const std::size_t texels = std::size_t(model.width) * std::size_t(model.height);
    const bool deepZoom = options.layout == RelightWriteOptions::Layout::DeepZoom ||
                          (options.layout == RelightWriteOptions::Layout::Automatic &&
                           std::max(model.width, model.height) > kDeepZoomAbove);

    // The ranges, from an even sample of at most quantileSample texels per plane.
    const std::size_t stride = std::max<std::size_t>(
        1, texels / options.quantileSample + (texels % options.quantileSample != 0));
    std::vector<RelightQuantisation> q(std::size_t(model.planeCount));
    std::size_t clamped = 0;
    double largestStep = 0;
    for (int m = 0; m < model.planeCount; ++m) {
        const float* plane = model.planes.data() + std::size_t(m) * texels;
        if (model.baseColourPlanes && m < 3) continue;  // scale 1, bias 0
        std::vector<float> sample;
        sample.reserve(texels / stride + 1);
        for (std::size_t t = 0; t < texels; t += stride) sample.push_back(plane[t]);
        q[std::size_t(m)] = relightRange(sample, options.rangeQuantile);
        largestStep = std::max(largestStep, double(q[std::size_t(m)].scale) / 255.0);
    }
    std::vector<double> range;
    const std::vector<int> basis =
        model.colorspace == "mrgb" ? quantiseRelightBasis(model, range) : std::vector<int>();

    const fs::path folder =
        fs::path(infoPath).parent_path().empty() ? fs::path(".") : fs::path(infoPath).parent_path();
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) fail(folder.string(), "cannot create the folder: " + ec.message());
    const fs::path staging = folder / ("info.json.tmp" + std::to_string(::getpid()));
    fs::remove_all(staging, ec);
    fs::create_directory(staging, ec);
    if (ec) fail(staging.string(), "cannot create the folder: " + ec.message());
    const int jpegs = (model.planeCount + 2) / 3;
    try {
        Progress progress(
            "writing " + infoPath,
            std::size_t(jpegs) *
                (deepZoom ? deepZoomLevels(model.width, model.height, options.tileSize).size()
                          : 1));
        for (int j = 0; j < jpegs; ++j) {
            ByteImage image;
            image.width = model.width;
            image.height = model.height;
            image.rgb.assign(texels * 3, 0);
            for (int c = 0; c < 3; ++c) {
                const int m = 3 * j + c;
                if (m >= model.planeCount) break;
                const float* plane = model.planes.data() + std::size_t(m) * texels;
                const RelightQuantisation& quantisation = q[std::size_t(m)];
                for (int y = 0; y < model.height; ++y) {
                    // The material's rows run bottom-up, a JPEG's top down.
                    const std::size_t from =
                        std::size_t(model.height - 1 - y) * std::size_t(model.width);
                    unsigned char* to = image.rgb.data() +
                                        std::size_t(y) * std::size_t(model.width) * 3 +
                                        std::size_t(c);
                    for (std::size_t x = 0; x < std::size_t(model.width); ++x) {
                        const float v = plane[from + x];
                        const unsigned char b = quantisation.quantise(v);
                        to[x * 3] = b;
                        if ((b == 0 && v < -quantisation.bias * quantisation.scale) ||
                            (b == 255 && v > (1 - quantisation.bias) * quantisation.scale))
                            ++clamped;
                    }
                }
            }
            const std::string stem = "plane_" + std::to_string(j);
            if (deepZoom) {
                writeDeepZoom(staging.string(), stem, std::move(image), options, progress);
            } else {
                const std::string name = (staging / (stem + ".jpg")).string();
                writeBytes(name, encodeJpeg(folder.string() + "/" + stem + ".jpg", image.rgb.data(),
                                            image.width, image.height, options.quality));
                progress.advance();
            }
        }
        progress.finish();
        writeBytes((staging / "index.html").string(), [&] {
            const std::string text = indexHtml(model, deepZoom);
            return std::vector<unsigned char>(text.begin(), text.end());
        }());
        const std::string json = infoJson(model, q, basis, range, options.quality);
        writeBytes((staging / "info.json").string(),
                   std::vector<unsigned char>(json.begin(), json.end()));
        // Into place: the planes first, info.json (what a reader opens) last.
        removeEarlierPlanes(folder);
        for (const auto& entry : fs::directory_iterator(staging)) {
            const std::string name = entry.path().filename().string();
            if (name == "info.json") continue;
            fs::remove_all(folder / name, ec);
            fs::rename(entry.path(), folder / name);
        }
        fs::rename(staging / "info.json", folder / "info.json");
        fs::remove_all(staging, ec);
    } catch (const fs::filesystem_error& e) {
        fs::remove_all(staging, ec);
        fail(infoPath, std::string("cannot write the layout: ") + e.what());
    } catch (...) {
        fs::remove_all(staging, ec);
        throw;
    }
    std::ostringstream line;
    line << model.planeCount << " planes in " << jpegs
         << (deepZoom ? " deep-zoom pyramids" : " JPEGs") << " (quality " << options.quality
         << "), 8-bit: largest step " << largestStep << ", " << clamped << " of "
         << texels * std::size_t(model.planeCount)
         << " values clamped to their plane's range (quantile " << options.rangeQuantile << ")";
    return line.str();
}

}  // namespace osgBTF
