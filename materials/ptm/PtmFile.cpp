// Reads top to bottom: the header, reading, writing. The layout: PtmFile.h.
#include "materials/ptm/PtmFile.h"

#include <algorithm>
#include <cctype>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/SizeGuard.h"
#include "materials/ForeignFiles.h"
#include "materials/MaterialMath.h"

namespace osgBTF {

// ---- the header --------------------------------------------------------------------------------

namespace {

/** The next white-space-separated token of the ASCII header from `at` on; empty at the end. */
std::string nextToken(const std::string& bytes, std::size_t& at) {
    while (at < bytes.size() && std::isspace(static_cast<unsigned char>(bytes[at]))) ++at;
    const std::size_t start = at;
    while (at < bytes.size() && !std::isspace(static_cast<unsigned char>(bytes[at])) &&
           at - start < 64)
        ++at;
    return bytes.substr(start, at - start);
}

}  // namespace

std::uint64_t PtmFileHeader::dataBytes() const {
    return saturatedProduct({std::uint64_t(width), std::uint64_t(height), luminance() ? 9u : 18u});
}

PtmFileHeader parsePtmHeader(const std::string& name, const std::string& bytes, bool checkData) {
    std::size_t at = 0;
    const std::string version = nextToken(bytes, at);
    if (version != "PTM_1.2")
        fail(name, "not a PTM 1.2 file (the first line is '" + version.substr(0, 16) +
                       "', not 'PTM_1.2')");
    PtmFileHeader h;
    h.format = nextToken(bytes, at);
    if (h.format.rfind("PTM_FORMAT_JPEG", 0) == 0)
        fail(name, h.format +
                       " (JPEG-compressed coefficient planes) is not read; convert it to "
                       "PTM_FORMAT_RGB or PTM_FORMAT_LRGB");
    if (h.format != "PTM_FORMAT_RGB" && h.format != "PTM_FORMAT_LRGB")
        fail(name, "format '" + h.format.substr(0, 32) +
                       "' is not read (PTM_FORMAT_RGB and PTM_FORMAT_LRGB are)");
    const auto integer = [&](const std::string& what) {
        const std::string token = nextToken(bytes, at);
        char* end = nullptr;
        const long long value = std::strtoll(token.c_str(), &end, 10);
        if (token.empty() || *end != '\0')
            fail(name, "header: " + what + " '" + token.substr(0, 16) + "' is not an integer");
        return value;
    };
    const long long width = integer("width"), height = integer("height");
    if (width <= 0 || height <= 0 || width > (1 << 20) || height > (1 << 20))
        fail(name, "header: size " + std::to_string(width) + "x" + std::to_string(height) +
                       " is not 1..1048576 on each side");
    h.width = int(width);
    h.height = int(height);
    for (int k = 0; k < 6; ++k) {
        const std::string token = nextToken(bytes, at);
        char* end = nullptr;
        const float value = std::strtof(token.c_str(), &end);
        if (token.empty() || *end != '\0')
            fail(name, "header: scale " + std::to_string(k) + " '" + token.substr(0, 16) +
                           "' is not a number");
        if (!std::isfinite(value))
            fail(name, "header: scale " + std::to_string(k) + " is not finite");
        h.scale[std::size_t(k)] = value;
    }
    for (int k = 0; k < 6; ++k) {
        const long long value = integer("bias " + std::to_string(k));
        if (value < -65536 || value > 65536)
            fail(name, "header: bias " + std::to_string(k) + " = " + std::to_string(value) +
                           " is out of range");
        h.bias[std::size_t(k)] = int(value);
    }
    // The data start after the line that ends the biases.
    while (at < bytes.size() && bytes[at] != '\n') ++at;
    if (at >= bytes.size()) fail(name, "header: no data after the biases");
    h.dataOffset = at + 1;
    if (checkData && bytes.size() - h.dataOffset < h.dataBytes())
        fail(name, "truncated: " + h.format + " " + std::to_string(h.width) + "x" +
                       std::to_string(h.height) + " needs " + std::to_string(h.dataBytes()) +
                       " bytes of coefficients, the file has " +
                       std::to_string(bytes.size() - h.dataOffset));
    return h;
}

// ---- reading -----------------------------------------------------------------------------------

osg::ref_ptr<PtmMaterial> ptmMaterialFromBytes(const std::string& name, const std::string& bytes) {
    const PtmFileHeader h = parsePtmHeader(name, bytes);
    PtmMaterial::Shape shape;
    shape.luminance = h.luminance();
    shape.perView = false;
    shape.storage = MaterialTexture::Float;
    osg::ref_ptr<PtmMaterial> m;
    try {
        m = PtmMaterial::create(h.width, h.height, DirectionSet("ptm file view", {{0, 0}}),
                                nominalFileLights(), shape);
    } catch (const Error& e) {
        fail(name, e.what());  // the memory guard
    }
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data() + h.dataOffset);
    const std::size_t texels = std::size_t(h.width) * std::size_t(h.height);
    // Decoded to 0..1 (the polynomial's 8-bit intensity units / 255).
    const auto coefficient = [&](unsigned char byte, int k) {
        return float((double(byte) - h.bias[std::size_t(k)]) * h.scale[std::size_t(k)] / 255.0);
    };
    // File pixel p: rows bottom to top, as the material's texels.
    if (!shape.luminance) {
        for (int c = 0; c < 3; ++c)
            for (std::size_t p = 0; p < texels; ++p)
                for (int k = 0; k < 6; ++k)
                    m->setCoefficient(p, 0, k, c,
                                      coefficient(data[(std::size_t(c) * texels + p) * 6 + k], k));
    } else {
        for (std::size_t p = 0; p < texels; ++p) {
            for (int k = 0; k < 6; ++k)
                m->setCoefficient(p, 0, k, 0, coefficient(data[p * 6 + k], k));
            for (int c = 0; c < 3; ++c)
                m->colour.set(p * 3 + std::size_t(c), float(data[texels * 6 + p * 3 + c]) / 255.0f);
        }
    }
    m->sourceFile = name;
    m->fitInfo["file-format"] = h.format;
    return m;
}

osg::ref_ptr<PtmMaterial> readPtmFile(const std::string& path) {
    return ptmMaterialFromBytes(path, readWholeFile(path));
}

// ---- writing -----------------------------------------------------------------------------------

PtmQuantisation writePtmFile(const PtmMaterial& material, const std::string& path) {
    if (material.shape().perView)
        fail(path,
             "a .ptm file holds one view; this ptm material has one per view (views=all): "
             "fit with views=front");
    if (material.mipLayout().levelCount() > 0)
        fail(path, "a .ptm file has no mip levels: fit with --no-mipmap");
    const bool luminance = material.shape().luminance;
    const std::size_t texels = material.texelCount();
    const int channels = luminance ? 1 : 3;
    // What the file stores, in 8-bit intensity units: the polynomial (per channel for RGB; for
    // LRGB the luminance times the colour's largest channel, the colour divided by it).
    std::vector<double> coefficients(texels * std::size_t(channels) * 6);
    std::vector<double> colour(luminance ? texels * 3 : 0);
    for (std::size_t p = 0; p < texels; ++p) {
        double fold = 1;
        if (luminance) {
            float rgb[3];
            material.colour.read(p * 3, 3, rgb);
            fold = std::max({double(rgb[0]), double(rgb[1]), double(rgb[2]), 0.0});
            for (int c = 0; c < 3; ++c)
                colour[p * 3 + std::size_t(c)] =
                    fold > 0 ? std::max(0.0, double(rgb[c])) / fold : 0;
        }
        for (int c = 0; c < channels; ++c)
            for (int k = 0; k < 6; ++k)
                coefficients[(std::size_t(c) * texels + p) * 6 + std::size_t(k)] =
                    double(material.coefficient(p, 0, k, c)) * fold * 255.0;
    }
    PtmFileHeader h;
    h.format = luminance ? "PTM_FORMAT_LRGB" : "PTM_FORMAT_RGB";
    h.width = material.width();
    h.height = material.height();
    // Per term: the scale spans its values in 255 steps; the bias puts the smallest at ~byte 0.
    for (int k = 0; k < 6; ++k) {
        double lo = 0, hi = 0;
        bool first = true;
        for (std::size_t i = std::size_t(k); i < coefficients.size(); i += 6) {
            lo = first ? coefficients[i] : std::min(lo, coefficients[i]);
            hi = first ? coefficients[i] : std::max(hi, coefficients[i]);
            first = false;
        }
        const double scale = hi > lo ? (hi - lo) / 255.0 : std::max(std::abs(lo), 1.0) / 255.0;
        h.scale[std::size_t(k)] = float(scale);
        h.bias[std::size_t(k)] = int(std::lround(-lo / double(h.scale[std::size_t(k)])));
    }
    std::string out = "PTM_1.2\n" + h.format + "\n" + std::to_string(h.width) + "\n" +
                      std::to_string(h.height) + "\n";
    for (int k = 0; k < 6; ++k) out += floatText(h.scale[std::size_t(k)]) + (k < 5 ? " " : "\n");
    for (int k = 0; k < 6; ++k)
        out += std::to_string(h.bias[std::size_t(k)]) + (k < 5 ? " " : "\n");
    PtmQuantisation q;
    for (int k = 0; k < 6; ++k)
        q.largestStep = std::max(q.largestStep, double(h.scale[std::size_t(k)]) / 255.0);
    const std::size_t header = out.size();
    out.resize(header + std::size_t(h.dataBytes()));
    for (std::size_t i = 0; i < coefficients.size(); ++i) {
        const int k = int(i % 6);
        const double scale = h.scale[std::size_t(k)];
        const long byte =
            std::clamp(std::lround(coefficients[i] / scale + h.bias[std::size_t(k)]), 0L, 255L);
        out[header + i] = char(byte);
        const double decoded = (double(byte) - h.bias[std::size_t(k)]) * scale;
        q.largestCoefficientError =
            std::max(q.largestCoefficientError, std::abs(decoded - coefficients[i]) / 255.0);
    }
    for (std::size_t i = 0; i < colour.size(); ++i)
        out[header + coefficients.size() + i] = char(std::lround(colour[i] * 255.0));
    writeTextAtomically(path, out);
    return q;
}

}  // namespace osgBTF
