// Reads top to bottom: the header, reading, writing. The layout: RtiFile.h.
#include "materials/hsh/RtiFile.h"

#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstring>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/SizeGuard.h"
#include "materials/ForeignFiles.h"
#include "materials/RelightFolder.h"

namespace osgBTF {

// ---- the header --------------------------------------------------------------------------------

std::uint64_t RtiFileHeader::dataBytes() const {
    return saturatedProduct(
        {std::uint64_t(width), std::uint64_t(height), std::uint64_t(bands), std::uint64_t(terms)});
}

RtiFileHeader parseRtiHeader(const std::string& name, const std::string& bytes, bool checkData) {
    std::size_t at = 0;
    // One text line (without its CR LF or LF); fails at the end of the file.
    const auto line = [&](const std::string& what) {
        const std::size_t end = bytes.find('\n', at);
        if (end == std::string::npos || end - at > 4096) fail(name, "header: no " + what + " line");
        std::string text = bytes.substr(at, end - at);
        if (!text.empty() && text.back() == '\r') text.pop_back();
        at = end + 1;
        return text;
    };
    std::string first = line("type");
    while (!first.empty() && first[0] == '#') first = line("type");
    // Up to three integers of a line.
    const auto integers = [&](const std::string& text, int count, const std::string& what) {
        std::vector<long long> values;
        const char* p = text.c_str();
        for (int i = 0; i < count; ++i) {
            char* end = nullptr;
            const long long value = std::strtoll(p, &end, 10);
            if (end == p)
                fail(name, "header: the " + what + " line '" + text.substr(0, 40) + "' needs " +
                               std::to_string(count) + " integers");
            values.push_back(value);
            p = end;
        }
        return values;
    };
    RtiFileHeader h;
    h.type = int(integers(first, 1, "type")[0]);
    if (h.type != 3)
        fail(name, "RTI type " + std::to_string(h.type) +
                       " is not read (only 3, hemispherical harmonics)");
    const auto size = integers(line("size"), 3, "size (width height bands)");
    if (size[0] <= 0 || size[1] <= 0 || size[0] > (1 << 20) || size[1] > (1 << 20))
        fail(name, "header: size " + std::to_string(size[0]) + "x" + std::to_string(size[1]) +
                       " is not 1..1048576 on each side");
    if (size[2] != 3)
        fail(name, "header: " + std::to_string(size[2]) + " colour bands (3 are read)");
    const auto basis = integers(line("basis"), 3, "basis (terms type element-size)");
    if (basis[0] != 4 && basis[0] != 9 && basis[0] != 16)
        fail(name, "header: " + std::to_string(basis[0]) +
                       " terms per band (4, 9 or 16: hemispherical harmonics of order 2 to 4)");
    if (basis[2] != 1)
        fail(name,
             "header: element size " + std::to_string(basis[2]) + " (1 byte per term is read)");
    h.width = int(size[0]);
    h.height = int(size[1]);
    h.bands = 3;
    h.terms = int(basis[0]);
    h.basisType = int(basis[1]);
    h.elementSize = 1;
    const std::size_t ranges = std::size_t(h.terms) * 2 * sizeof(float);
    if (bytes.size() - at < ranges)
        fail(name, "truncated: the " + std::to_string(h.terms) + " term ranges need " +
                       std::to_string(ranges) + " bytes, the file has " +
                       std::to_string(bytes.size() - at));
    const auto floatAt = [&](std::size_t offset) {
        // Little-endian IEEE float, as the x86 machines that wrote the files.
        unsigned char b[4];
        std::memcpy(b, bytes.data() + offset, 4);
        const std::uint32_t bits = std::uint32_t(b[0]) | std::uint32_t(b[1]) << 8 |
                                   std::uint32_t(b[2]) << 16 | std::uint32_t(b[3]) << 24;
        float value;
        std::memcpy(&value, &bits, 4);
        return value;
    };
    for (int k = 0; k < h.terms; ++k) {
        h.minimum.push_back(floatAt(at + std::size_t(k) * 4));
        h.maximum.push_back(floatAt(at + std::size_t(h.terms + k) * 4));
        if (!std::isfinite(h.minimum.back()) || !std::isfinite(h.maximum.back()))
            fail(name, "header: the range of term " + std::to_string(k) + " is not finite");
    }
    h.dataOffset = at + ranges;
    if (checkData && bytes.size() - h.dataOffset < h.dataBytes())
        fail(name, "truncated: " + std::to_string(h.width) + "x" + std::to_string(h.height) +
                       " pixels of 3 x " + std::to_string(h.terms) + " terms need " +
                       std::to_string(h.dataBytes()) + " bytes, the file has " +
                       std::to_string(bytes.size() - h.dataOffset));
    return h;
}

// ---- reading -----------------------------------------------------------------------------------

osg::ref_ptr<HshMaterial> hshMaterialFromBytes(const std::string& name, const std::string& bytes) {
    const RtiFileHeader h = parseRtiHeader(name, bytes);
    HshMaterial::Shape shape;
    shape.order = h.terms == 4 ? 2 : h.terms == 9 ? 3 : 4;
    shape.perView = false;
    shape.storage = MaterialTexture::Float;
    osg::ref_ptr<HshMaterial> m;
    try {
        m = HshMaterial::create(h.width, h.height, DirectionSet("rti file view", {{0, 0}}),
                                nominalFileLights(), shape);
    } catch (const Error& e) {
        fail(name, e.what());  // the memory guard
    }
    const auto* data = reinterpret_cast<const unsigned char*>(bytes.data() + h.dataOffset);
    const std::size_t terms = std::size_t(h.terms);
    for (int row = 0; row < h.height; ++row) {
        // File rows run from the top down; the material's from the bottom up.
        const std::size_t y = std::size_t(h.height - 1 - row);
        for (std::size_t x = 0; x < std::size_t(h.width); ++x) {
            const std::size_t pixel = std::size_t(row) * std::size_t(h.width) + x;
            for (int c = 0; c < 3; ++c)
                for (std::size_t k = 0; k < terms; ++k) {
                    const double byte = data[(pixel * 3 + std::size_t(c)) * terms + k];
                    m->setCoefficient(
                        y * std::size_t(h.width) + x, 0, int(k), c,
                        float(h.minimum[k] + (double(h.maximum[k]) - h.minimum[k]) * byte / 255.0));
                }
        }
    }
    m->sourceFile = name;
    m->fitInfo["file-format"] = "RTI type 3 (HSH), " + std::to_string(h.terms) + " terms";
    return m;
}

osg::ref_ptr<HshMaterial> readRtiFile(const std::string& path) {
    return hshMaterialFromBytes(path, readWholeFile(path));
}

osg::ref_ptr<HshMaterial> hshMaterialFromRelight(const std::string& infoPath,
                                                 const RelightPlanes& planes) {
    if (planes.terms != 4 && planes.terms != 9 && planes.terms != 16)
        fail(infoPath, "type hsh with colorspace " + planes.colorspace + " has " +
                           std::to_string(planes.terms) +
                           " terms; 4, 9 or 16 (order 2 to 4) are read");
    HshMaterial::Shape shape;
    shape.order = planes.terms == 4 ? 2 : planes.terms == 9 ? 3 : 4;
    shape.perView = false;
    shape.storage = MaterialTexture::Float;
    osg::ref_ptr<HshMaterial> m;
    try {
        m = HshMaterial::create(planes.width, planes.height,
                                DirectionSet("relight file view", {{0, 0}}),
                                relightLights(infoPath, planes), shape);
    } catch (const Error& e) {
        fail(infoPath, e.what());  // the memory guard
    }
    const std::size_t texels = m->texelCount();
    for (std::size_t t = 0; t < texels; ++t)
        for (int k = 0; k < planes.terms; ++k)
            for (int c = 0; c < 3; ++c) m->setCoefficient(t, 0, k, c, planes.coefficient(k, c, t));
    m->sourceFile = infoPath;
    return m;
}

RelightModel relightModelOfHsh(const HshMaterial& material, const std::string& infoPath) {
    if (material.shape().perView)
        fail(infoPath,
             "relight's web layout holds one view; this hsh material has one per view "
             "(views=all): fit with views=front");
    const int terms = material.terms();
    RelightModel model = relightModelFrame(material, infoPath, "hsh", "rgb", 3 * terms);
    const std::size_t texels = material.texelCount();
    for (int k = 0; k < terms; ++k)
        for (int c = 0; c < 3; ++c) {
            float* plane = model.planes.data() + std::size_t(3 * k + c) * texels;
            for (std::size_t t = 0; t < texels; ++t) plane[t] = material.coefficient(t, 0, k, c);
        }
    return model;
}

// ---- writing -----------------------------------------------------------------------------------

std::pair<double, double> writeRtiFile(const HshMaterial& material, const std::string& path) {
    if (material.shape().perView)
        fail(path,
             "an .rti file holds one view; this hsh material has one per view (views=all): "
             "fit with views=front");
    if (material.mipLayout().levelCount() > 0)
        fail(path, "an .rti file has no mip levels: fit with --no-mipmap");
    const int terms = material.terms(), width = material.width(), height = material.height();
    const std::size_t texels = material.texelCount();
    std::vector<float> minimum(static_cast<std::size_t>(terms)),
        maximum(static_cast<std::size_t>(terms));
    for (int k = 0; k < terms; ++k) {
        float lo = material.coefficient(0, 0, k, 0), hi = lo;
        for (std::size_t t = 0; t < texels; ++t)
            for (int c = 0; c < 3; ++c) {
                lo = std::min(lo, material.coefficient(t, 0, k, c));
                hi = std::max(hi, material.coefficient(t, 0, k, c));
            }
        minimum[std::size_t(k)] = lo;
        maximum[std::size_t(k)] = hi;
    }
    std::string out = "#HSH1.2\n3\n" + std::to_string(width) + " " + std::to_string(height) +
                      " 3\n" + std::to_string(terms) + " 2 1\n";
    const auto appendFloat = [&](float value) {
        std::uint32_t bits;
        std::memcpy(&bits, &value, 4);
        for (int i = 0; i < 4; ++i) out += char((bits >> (8 * i)) & 0xFF);
    };
    for (const float v : minimum) appendFloat(v);
    for (const float v : maximum) appendFloat(v);
    double largestError = 0, largestStep = 0;
    for (int k = 0; k < terms; ++k)
        largestStep = std::max(largestStep,
                               (double(maximum[std::size_t(k)]) - minimum[std::size_t(k)]) / 255.0);
    const std::size_t header = out.size();
    out.resize(header + texels * 3 * std::size_t(terms));
    for (int row = 0; row < height; ++row) {
        const std::size_t y = std::size_t(height - 1 - row);
        for (std::size_t x = 0; x < std::size_t(width); ++x) {
            const std::size_t pixel = std::size_t(row) * std::size_t(width) + x;
            for (int c = 0; c < 3; ++c)
                for (int k = 0; k < terms; ++k) {
                    const double lo = minimum[std::size_t(k)], hi = maximum[std::size_t(k)];
                    const double value = material.coefficient(y * std::size_t(width) + x, 0, k, c);
                    const long byte =
                        hi > lo
                            ? std::clamp(std::lround((value - lo) / (hi - lo) * 255.0), 0L, 255L)
                            : 0L;
                    out[header + (pixel * 3 + std::size_t(c)) * std::size_t(terms) +
                        std::size_t(k)] = char(byte);
                    largestError = std::max(
                        largestError, std::abs(lo + (hi - lo) * double(byte) / 255.0 - value));
                }
        }
    }
    writeTextAtomically(path, out);
    return {largestError, largestStep};
}

}  // namespace osgBTF
