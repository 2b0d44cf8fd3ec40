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
#include "core/MeasuredBtf.h"
#include "core/SizeGuard.h"
#include "materials/ForeignFiles.h"
#include "materials/MaterialMath.h"
#include "materials/RelightFolder.h"

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
    if (jpeg()) {
        std::uint64_t sum = 0;
        for (std::size_t i = 0; i < compressedSize.size(); ++i)
            for (const std::uint64_t n : {compressedSize[i], sideInfoSize[i]})
                sum = n > UINT64_MAX - sum ? UINT64_MAX : sum + n;
        return sum;
    }
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
    if (h.format != "PTM_FORMAT_RGB" && h.format != "PTM_FORMAT_LRGB" &&
        h.format != "PTM_FORMAT_JPEG_RGB" && h.format != "PTM_FORMAT_JPEG_LRGB")
        fail(name, "format '" + h.format.substr(0, 32) +
                       "' is not read (PTM_FORMAT_RGB, PTM_FORMAT_LRGB, PTM_FORMAT_JPEG_RGB and "
                       "PTM_FORMAT_JPEG_LRGB are)");
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
    if (h.jpeg()) {
        const std::size_t n = std::size_t(h.streams());
        h.compression = int(std::clamp(integer("compression parameter"), -1000000LL, 1000000LL));
        // One line of N integers each, in the order of PtmFile.h.
        const auto list = [&](const std::string& what, long long lo, long long hi) {
            std::vector<long long> values;
            for (std::size_t i = 0; i < n; ++i) {
                const long long v = integer(what + " " + std::to_string(i));
                if (v < lo || v > hi)
                    fail(name, "header: " + what + " " + std::to_string(i) + " = " +
                                   std::to_string(v) + " is out of range");
                values.push_back(v);
            }
            return values;
        };
        const auto ints = [](const std::vector<long long>& v) {
            return std::vector<int>(v.begin(), v.end());
        };
        h.transforms = ints(list("transform", -1000000, 1000000));
        h.motionX = ints(list("motion vector x", -1000000, 1000000));
        h.motionY = ints(list("motion vector y", -1000000, 1000000));
        h.order = ints(list("order", 0, (long long)(n)-1));
        h.reference = ints(list("reference", -1, (long long)(n)-1));
        for (const long long v : list("compressed size", 0, 1LL << 40))
            h.compressedSize.push_back(std::uint64_t(v));
        for (const long long v : list("side-information size", 0, 1LL << 40))
            h.sideInfoSize.push_back(std::uint64_t(v));
        std::vector<int> rankOf(n, -1);
        for (std::size_t i = 0; i < n; ++i) {
            const std::string stream = "stream " + std::to_string(i);
            if (h.transforms[i] == 2)
                fail(name,
                     stream + ": transform 2 (motion compensation) is not read (0 and 1 are)");
            if (h.transforms[i] != 0 && h.transforms[i] != 1)
                fail(name, stream + ": transform " + std::to_string(h.transforms[i]) +
                               " is not read (0: none, 1: inverted reference)");
            if (h.motionX[i] != 0 || h.motionY[i] != 0)
                fail(name, stream + ": motion vector (" + std::to_string(h.motionX[i]) + ", " +
                               std::to_string(h.motionY[i]) + ") is not read (only 0, 0)");
            if (rankOf[std::size_t(h.order[i])] >= 0)
                fail(name, "header: order " + std::to_string(h.order[i]) + " is given to streams " +
                               std::to_string(rankOf[std::size_t(h.order[i])]) + " and " +
                               std::to_string(i) + " (a permutation of 0.." +
                               std::to_string(n - 1) + " is read)");
            rankOf[std::size_t(h.order[i])] = int(i);
            if (h.sideInfoSize[i] % 5 != 0)
                fail(name, stream + ": side-information size " + std::to_string(h.sideInfoSize[i]) +
                               " is not a multiple of 5 (records of 5 bytes)");
        }
        for (std::size_t i = 0; i < n; ++i) {
            const int r = h.reference[i];
            if (r >= 0 && h.order[std::size_t(r)] >= h.order[i])
                fail(name, "stream " + std::to_string(i) + " is predicted from stream " +
                               std::to_string(r) + ", which is not decoded before it (order " +
                               std::to_string(h.order[std::size_t(r)]) +
                               " >= " + std::to_string(h.order[i]) + ")");
        }
    }
    // The data start after the line that ends the biases (JPEG: the side-information sizes).
    while (at < bytes.size() && bytes[at] != '\n') ++at;
    if (at >= bytes.size())
        fail(name, h.jpeg() ? "header: no data after the side-information sizes"
                            : "header: no data after the biases");
    h.dataOffset = at + 1;
    if (checkData && h.jpeg() && bytes.size() - h.dataOffset < h.dataBytes())
        fail(name, "truncated: the " + std::to_string(h.streams()) +
                       " JPEG streams and their side information need " +
                       std::to_string(h.dataBytes()) + " bytes, the file has " +
                       std::to_string(bytes.size() - h.dataOffset));
    if (checkData && bytes.size() - h.dataOffset < h.dataBytes())
        fail(name, "truncated: " + h.format + " " + std::to_string(h.width) + "x" +
                       std::to_string(h.height) + " needs " + std::to_string(h.dataBytes()) +
                       " bytes of coefficients, the file has " +
                       std::to_string(bytes.size() - h.dataOffset));
    return h;
}

// ---- reading -----------------------------------------------------------------------------------

namespace {

/** The JPEG variants' streams after prediction and side information, each W x H bytes in the
 *  JPEG's scanline order (the first scanline is the bottom row: the material's order). */
std::vector<std::vector<unsigned char>> jpegStreams(const std::string& name,
                                                    const std::string& bytes,
                                                    const PtmFileHeader& h) {
    const std::size_t n = std::size_t(h.streams());
    const std::size_t texels = std::size_t(h.width) * std::size_t(h.height);
    checkMemory(saturatedProduct({n + 1, texels}),
                name + ": " + std::to_string(n) + " JPEG planes of " + std::to_string(h.width) +
                    "x" + std::to_string(h.height));
    // Where each stream and its side information start: in stream-index order, whatever the
    // decoding order.
    std::vector<std::size_t> start(n);
    std::size_t at = h.dataOffset;
    for (std::size_t i = 0; i < n; ++i) {
        start[i] = at;
        at += std::size_t(h.compressedSize[i] + h.sideInfoSize[i]);  // within the file (checked)
    }
    std::vector<std::vector<unsigned char>> v(n);
    const std::string expected = "the header gives " + std::to_string(h.width) + "x" +
                                 std::to_string(h.height) + " greyscale";
    for (int rank = 0; rank < int(n); ++rank) {
        const std::size_t i =
            std::size_t(std::find(h.order.begin(), h.order.end(), rank) - h.order.begin());
        const std::string stream = name + ": JPEG stream " + std::to_string(i);
        const auto* data = reinterpret_cast<const unsigned char*>(bytes.data() + start[i]);
        v[i] = decodeJpeg(stream, data, std::size_t(h.compressedSize[i]), h.width, h.height, 1,
                          expected);
        if (const int r = h.reference[i]; r >= 0) {
            // Prediction: the reference (inverted for transform 1) plus the stored byte - 128,
            // modulo 256 (docs/formats.md 8.1.1).
            const std::vector<unsigned char>& ref = v[std::size_t(r)];
            const bool invert = h.transforms[i] == 1;
            for (std::size_t p = 0; p < texels; ++p)
                v[i][p] =
                    static_cast<unsigned char>((invert ? 255 - ref[p] : ref[p]) + v[i][p] - 128);
        }
        // Side information: records of a big-endian position and the value it gets.
        const unsigned char* side = data + h.compressedSize[i];
        for (std::size_t k = 0; k < std::size_t(h.sideInfoSize[i]); k += 5) {
            const std::uint64_t position = std::uint64_t(side[k]) << 24 |
                                           std::uint64_t(side[k + 1]) << 16 |
                                           std::uint64_t(side[k + 2]) << 8 | side[k + 3];
            if (position >= texels)
                fail(name, "JPEG stream " + std::to_string(i) + ": side information " +
                               std::to_string(k / 5) + " sets pixel " + std::to_string(position) +
                               " of " + std::to_string(texels));
            v[i][std::size_t(position)] = side[k + 4];
        }
    }
    return v;
}

}  // namespace

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
    if (h.jpeg()) {
        const std::vector<std::vector<unsigned char>> v = jpegStreams(name, bytes, h);
        for (std::size_t p = 0; p < texels; ++p) {
            if (shape.luminance) {
                // Streams 0..5: a0..a5 of the luminance; 6, 7, 8: R, G, B.
                for (int k = 0; k < 6; ++k)
                    m->setCoefficient(p, 0, k, 0, coefficient(v[std::size_t(k)][p], k));
                for (int c = 0; c < 3; ++c)
                    m->colour.set(p * 3 + std::size_t(c), float(v[6 + std::size_t(c)][p]) / 255.0f);
            } else {
                // Stream 6 c + k: a_k of colour c (ptmlib's order, docs/formats.md 8.1.1).
                for (int c = 0; c < 3; ++c)
                    for (int k = 0; k < 6; ++k)
                        m->setCoefficient(p, 0, k, c, coefficient(v[std::size_t(6 * c + k)][p], k));
            }
        }
    } else if (!shape.luminance) {
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

osg::ref_ptr<PtmMaterial> ptmMaterialFromRelight(const std::string& infoPath,
                                                 const RelightPlanes& planes) {
    if (planes.terms != 3 && planes.terms != 6)
        fail(infoPath, "type ptm with colorspace " + planes.colorspace + " has " +
                           std::to_string(planes.terms) +
                           " terms; 3 (first degree: 1, x, y) or 6 are read");
    PtmMaterial::Shape shape;
    shape.luminance = planes.luminance();
    shape.perView = false;
    shape.storage = MaterialTexture::Float;
    osg::ref_ptr<PtmMaterial> m;
    try {
        m = PtmMaterial::create(planes.width, planes.height,
                                DirectionSet("relight file view", {{0, 0}}),
                                relightLights(infoPath, planes), shape);
    } catch (const Error& e) {
        fail(infoPath, e.what());  // the memory guard
    }
    // Web term k (1, x, y, x^2, xy, y^2) is the material's a_kWeb[k] (x^2, y^2, xy, x, y, 1).
    constexpr int kWeb[6] = {5, 3, 4, 0, 2, 1};
    const std::size_t texels = m->texelCount();
    for (std::size_t t = 0; t < texels; ++t) {
        for (int k = 0; k < planes.terms; ++k)
            for (int c = 0; c < (shape.luminance ? 1 : 3); ++c)
                m->setCoefficient(t, 0, kWeb[k], c,
                                  shape.luminance ? planes.at(3 + k, t) : planes.at(3 * k + c, t));
        if (shape.luminance)
            for (int c = 0; c < 3; ++c) m->colour.set(t * 3 + std::size_t(c), planes.at(c, t));
    }
    m->sourceFile = infoPath;
    return m;
}

RelightModel relightModelOfPtm(const PtmMaterial& material, const std::string& infoPath) {
    if (material.shape().perView)
        fail(infoPath,
             "relight's web layout holds one view; this ptm material has one per view "
             "(views=all): fit with views=front");
    const bool luminance = material.shape().luminance;
    RelightModel model = relightModelFrame(material, infoPath, "ptm", luminance ? "lrgb" : "rgb",
                                           luminance ? 3 + 6 : 18);
    model.baseColourPlanes = luminance;
    constexpr int kWeb[6] = {5, 3, 4, 0, 2, 1};  // as ptmMaterialFromRelight
    const std::size_t texels = material.texelCount();
    const auto plane = [&](int m) { return model.planes.data() + std::size_t(m) * texels; };
    for (std::size_t t = 0; t < texels; ++t) {
        if (luminance) {
            // colour x P = (colour / s) x (s P): the colour fits relight's 0..1 base colour.
            float s = 0;
            for (int c = 0; c < 3; ++c) s = std::max(s, material.colour[t * 3 + std::size_t(c)]);
            if (!(s > 0)) s = 1;
            for (int c = 0; c < 3; ++c) plane(c)[t] = material.colour[t * 3 + std::size_t(c)] / s;
            for (int k = 0; k < 6; ++k)
                plane(3 + k)[t] = s * material.coefficient(t, 0, kWeb[k], 0);
        } else {
            for (int k = 0; k < 6; ++k)
                for (int c = 0; c < 3; ++c)
                    plane(3 * k + c)[t] = material.coefficient(t, 0, kWeb[k], c);
        }
    }
    return model;
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
