#include "core/FittedMaterialFile.h"

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <exception>
#include <filesystem>
#include <fstream>
#include <set>

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfIntAttribute.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfMultiPartOutputFile.h>
#include <OpenEXR/ImfOutputPart.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfStringAttribute.h>
#include <OpenEXR/ImfVersion.h>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/MeasuredBtf.h"
#include "core/SizeGuard.h"

namespace fs = std::filesystem;

namespace osgBTF {

namespace {

const char* const kMethodAttribute = "osgBTF.method";
const char* const kVersionAttribute = "osgBTF.version";
const char* const kViewsAttribute = "osgBTF.views";
const char* const kLightsAttribute = "osgBTF.lights";
const char* const kDepthAttribute = "osgBTF.depth";
const char* const kStorageAttribute = "osgBTF.storage";
const std::string kParamPrefix = "osgBTF.param.";

std::vector<std::string> channelNames(const std::string& texture, int channels) {
    std::vector<std::string> bases;
    switch (channels) {
        case 1:
            bases = {"Y"};
            break;
        case 2:
            bases = {"R", "G"};
            break;
        case 3:
            bases = {"R", "G", "B"};
            break;
        case 4:
            bases = {"R", "G", "B", "A"};
            break;
        default:
            for (int c = 0; c < channels; ++c) bases.push_back("c" + std::to_string(c));
    }
    for (std::string& base : bases) base = texture + "." + base;
    return bases;
}

/** File row (top-down over all slices) of texture row y (bottom-up) in slice z. */
std::size_t fileRow(const MaterialTexture& t, int z, int y) {
    return std::size_t(z) * std::size_t(t.height) + std::size_t(t.height - 1 - y);
}

std::string joinNames(const std::vector<std::string>& names) {
    std::string text;
    for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
    return text;
}

void validate(const FittedMaterial& material, const std::string& path) {
    if (material.method.empty()) fail(path, "fitted material has no method name");
    if (material.textures.empty())
        fail(path, "fitted material '" + material.method + "' has no textures");
    for (const auto& [key, value] : material.parameters)
        if (key.empty()) fail(path, "fitted material has a parameter with an empty name");
    std::set<std::string> names;
    for (const MaterialTexture& t : material.textures) {
        const std::string what = "texture '" + t.name + "'";
        if (t.name.empty()) fail(path, "a texture has an empty name");
        if (!names.insert(t.name).second) fail(path, "two textures are called '" + t.name + "'");
        if (t.width <= 0 || t.height <= 0 || t.depth <= 0 || t.channels <= 0)
            fail(path, what + " has size " + std::to_string(t.width) + "x" +
                           std::to_string(t.height) + "x" + std::to_string(t.depth) + " with " +
                           std::to_string(t.channels) + " channels");
        if (std::int64_t(t.height) * t.depth > INT32_MAX / 2)
            fail(path, what + " is too tall for an EXR file");
        if (t.storedCount() != t.valueCount())
            fail(path, what + " has " + std::to_string(t.storedCount()) + " values, " +
                           std::to_string(t.valueCount()) + " expected");
        if (int(!t.bytes.empty()) + int(!t.halves.empty()) + int(!t.data.empty()) > 1)
            fail(path, what +
                           " holds its values twice (in more than one of floats, bytes and "
                           "halves)");
        if (!t.bytes.empty() && t.kind != MaterialTexture::UNorm8)
            fail(path, what + " holds bytes but is not stored as 8-bit");
        if (!t.halves.empty() && t.kind != MaterialTexture::Half)
            fail(path, what + " holds halves but is not stored as half");
        if (t.kind == MaterialTexture::UNorm8) {
            const auto bad = std::find_if(t.data.begin(), t.data.end(), [](float v) {
                return !(v >= 0.0f && v <= 1.0f) ||
                       std::abs(v * 255.0f - std::round(v * 255.0f)) > 1e-3f;
            });
            if (bad != t.data.end())
                fail(path, what + " is stored as 8-bit but holds " + std::to_string(*bad) +
                               ", not a multiple of 1/255 in [0, 1]");
        }
        if (t.kind == MaterialTexture::Half) {
            const std::size_t overflow =
                std::size_t(std::count_if(t.data.begin(), t.data.end(), [](float v) {
                    return std::isfinite(v) && std::abs(v) > 65504.0f;
                }));
            if (overflow)
                fail(path, what + " is stored as half but " + std::to_string(overflow) +
                               " values exceed the half range (65504)");
        }
    }
}

Imf::Header partHeader(const FittedMaterial& material, const MaterialTexture& t,
                       const Imath::Box2i& displayWindow) {
    const Imath::Box2i dataWindow({0, 0}, {t.width - 1, t.height * t.depth - 1});
    Imf::Header header(displayWindow, dataWindow);
    header.setName(t.name);
    header.setType(Imf::SCANLINEIMAGE);
    header.compression() = Imf::ZIP_COMPRESSION;
    const Imf::PixelType type = t.kind == MaterialTexture::Float ? Imf::FLOAT : Imf::HALF;
    for (const std::string& name : channelNames(t.name, t.channels))
        header.channels().insert(name, Imf::Channel(type));
    if (t.kind == MaterialTexture::UNorm8)
        header.insert(kStorageAttribute, Imf::StringAttribute("unorm8"));
    header.insert(kMethodAttribute, Imf::StringAttribute(material.method));
    header.insert(kVersionAttribute, Imf::IntAttribute(kFittedMaterialVersion));
    header.insert(kViewsAttribute, Imf::StringAttribute(material.views.serialize()));
    header.insert(kLightsAttribute, Imf::StringAttribute(material.lights.serialize()));
    header.insert(kDepthAttribute, Imf::IntAttribute(t.depth));
    for (const auto& [key, value] : material.parameters)
        header.insert(kParamPrefix + key, Imf::StringAttribute(value));
    return header;
}

void writeTexture(Imf::MultiPartOutputFile& file, int part, const MaterialTexture& t) {
    const std::size_t rowValues = std::size_t(t.width) * std::size_t(t.channels);
    // OpenEXR converts on read but not on write: half channels need half slices. The file rows
    // go out in chunks through one small buffer: a texture of gigabytes (PCA of a full-size
    // UBO2014 file) must not be copied whole.
    const bool half = t.kind != MaterialTexture::Float;
    const std::size_t valueSize = half ? sizeof(Imath::half) : sizeof(float);
    const std::size_t xStride = valueSize * std::size_t(t.channels);
    const std::size_t yStride = xStride * std::size_t(t.width);
    const std::size_t fileRows = std::size_t(t.height) * std::size_t(t.depth);
    const std::size_t chunkRows =
        std::clamp<std::size_t>((std::size_t(8) << 20) / std::max<std::size_t>(yStride, 1), 1,
                                std::max<std::size_t>(fileRows, 1));
    std::vector<float> floats(half ? 0 : chunkRows * rowValues);
    std::vector<Imath::half> halves(half ? chunkRows * rowValues : 0);
    const std::vector<std::string> names = channelNames(t.name, t.channels);
    Imf::OutputPart output(file, part);
    for (std::size_t first = 0; first < fileRows; first += chunkRows) {
        const std::size_t count = std::min(chunkRows, fileRows - first);
        for (std::size_t r = first; r < first + count; ++r) {
            // File row r (top-down over all slices) is texture row y (bottom-up) of slice z.
            const std::size_t z = r / std::size_t(t.height);
            const std::size_t y = std::size_t(t.height) - 1 - r % std::size_t(t.height);
            const std::size_t row = (z * std::size_t(t.height) + y) * rowValues;
            const std::size_t at = (r - first) * rowValues;
            if (!t.bytes.empty()) {
                for (std::size_t i = 0; i < rowValues; ++i)  // integers are exact in half
                    halves[at + i] = Imath::half(float(t.bytes[row + i]));
                continue;
            }
            if (!t.halves.empty()) {
                std::copy_n(t.halves.begin() + std::ptrdiff_t(row), rowValues,
                            halves.begin() + std::ptrdiff_t(at));
                continue;
            }
            const float* source = t.data.data() + row;
            if (!half)
                std::copy_n(source, rowValues, floats.data() + at);
            else if (t.kind == MaterialTexture::UNorm8)
                for (std::size_t i = 0; i < rowValues; ++i)  // integers are exact in half
                    halves[at + i] = Imath::half(std::round(source[i] * 255.0f));
            else
                for (std::size_t i = 0; i < rowValues; ++i) halves[at + i] = Imath::half(source[i]);
        }
        // The slices address pixel (0, y) of the whole data window: offset the chunk by `first`.
        const char* chunk = half ? (const char*)halves.data() : (const char*)floats.data();
        const char* base = chunk - std::ptrdiff_t(first * yStride);
        Imf::FrameBuffer frameBuffer;
        for (std::size_t c = 0; c < names.size(); ++c)
            frameBuffer.insert(
                names[c], Imf::Slice(half ? Imf::HALF : Imf::FLOAT, (char*)(base + c * valueSize),
                                     xStride, yStride));
        output.setFrameBuffer(frameBuffer);
        output.writePixels(int(count));
    }
}

MaterialTexture readTexture(Imf::MultiPartInputFile& file, int part, const std::string& path,
                            CompactTextures compact) {
    const Imf::Header& header = file.header(part);
    if (!header.hasName()) fail(path, "part " + std::to_string(part) + " has no name");
    MaterialTexture t;
    t.name = header.name();
    const std::string what = "texture '" + t.name + "'";
    if (header.hasType() && Imf::isDeepData(header.type()))
        fail(path, what + " holds deep data, which fitted materials never use");

    const Imath::Box2i dw = header.dataWindow();
    const std::int64_t width = std::int64_t(dw.max.x) - dw.min.x + 1;
    const std::int64_t rows = std::int64_t(dw.max.y) - dw.min.y + 1;
    if (width <= 0 || rows <= 0) fail(path, what + " has an empty data window");
    const auto* depth = header.findTypedAttribute<Imf::IntAttribute>(kDepthAttribute);
    t.depth = depth ? depth->value() : 1;
    if (t.depth <= 0 || rows % t.depth != 0)
        fail(path, what + " has " + std::to_string(rows) + " rows, not a multiple of its depth " +
                       std::to_string(t.depth));
    t.width = int(width);
    t.height = int(rows / t.depth);

    std::vector<std::string> found;
    std::set<Imf::PixelType> types;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
        found.push_back(it.name());
        types.insert(it.channel().type);
        if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
            fail(path, what + ": channel '" + it.name() + "' is subsampled");
    }
    t.channels = int(found.size());
    std::vector<std::string> expected = channelNames(t.name, t.channels);
    std::vector<std::string> sortedExpected = expected;
    std::sort(sortedExpected.begin(), sortedExpected.end());
    std::sort(found.begin(), found.end());
    if (found.empty() || found != sortedExpected)
        fail(path, what + " has unexpected channels (" + joinNames(found) + "); expected " +
                       joinNames(expected));
    if (types.size() != 1 || *types.begin() == Imf::UINT)
        fail(path, what + " must have only half or only float channels");
    t.kind = *types.begin() == Imf::HALF ? MaterialTexture::Half : MaterialTexture::Float;
    if (const auto* storage = header.findTypedAttribute<Imf::StringAttribute>(kStorageAttribute)) {
        if (storage->value() != "unorm8" || t.kind != MaterialTexture::Half)
            fail(path, what + " has an unknown osgBTF.storage '" + storage->value() + "'");
        t.kind = MaterialTexture::UNorm8;
    }

    checkMemory(saturatedProduct({std::uint64_t(t.width), std::uint64_t(t.height),
                                  std::uint64_t(t.depth), std::uint64_t(t.channels), 8}),
                path + ": " + what);
    // Slice by slice through a buffer of one slice, so that the texture is held once while it
    // is read (a whole-texture buffer doubled the peak: 8x the bytes of an 8-bit texture).
    // Halves kept as halves are read as halves (exact); everything else as floats.
    const bool asBytes = t.kind == MaterialTexture::UNorm8 && compact.bytes;
    const bool asHalves = t.kind == MaterialTexture::Half && compact.halves;
    if (asBytes)
        t.bytes.resize(t.valueCount());
    else if (asHalves)
        t.halves.resize(t.valueCount());
    else
        t.data.resize(t.valueCount());
    const std::size_t rowValues = std::size_t(t.width) * std::size_t(t.channels);
    std::vector<float> sliceRows(asHalves ? 0 : rowValues * std::size_t(t.height));
    std::vector<Imath::half> sliceHalves(asHalves ? rowValues * std::size_t(t.height) : 0);
    const Imf::PixelType readType = asHalves ? Imf::HALF : Imf::FLOAT;
    const std::size_t xStride =
        (asHalves ? sizeof(Imath::half) : sizeof(float)) * std::size_t(t.channels);
    char* const sliceBase = asHalves ? (char*)sliceHalves.data() : (char*)sliceRows.data();
    const std::size_t valueSize = asHalves ? sizeof(Imath::half) : sizeof(float);
    Imf::InputPart input(file, part);
    for (int z = 0; z < t.depth; ++z) {
        const int first = dw.min.y + z * t.height;  // the file's rows of slice z
        const Imath::Box2i window(Imath::V2i(dw.min.x, first),
                                  Imath::V2i(dw.max.x, first + t.height - 1));
        Imf::FrameBuffer frameBuffer;
        for (std::size_t c = 0; c < expected.size(); ++c)
            frameBuffer.insert(
                expected[c], Imf::Slice::Make(readType, sliceBase + c * valueSize, window, xStride,
                                              xStride * std::size_t(t.width)));
        input.setFrameBuffer(frameBuffer);
        input.readPixels(window.min.y, window.max.y);
        const std::size_t firstRow = std::size_t(z) * std::size_t(t.height);
        if (t.kind == MaterialTexture::UNorm8)
            for (float v : sliceRows)
                if (!(v >= 0.0f && v <= 255.0f) || v != std::round(v))
                    fail(path, what + " is 8-bit but holds " + std::to_string(v));
        for (int y = 0; y < t.height; ++y) {
            const std::size_t fromRow = (fileRow(t, z, y) - firstRow) * rowValues;
            const std::size_t to = (firstRow + std::size_t(y)) * rowValues;
            if (asHalves) {
                std::copy_n(sliceHalves.begin() + std::ptrdiff_t(fromRow), rowValues,
                            t.halves.begin() + std::ptrdiff_t(to));
                continue;
            }
            const auto from = sliceRows.begin() + std::ptrdiff_t(fromRow);
            if (asBytes)
                std::transform(from, from + std::ptrdiff_t(rowValues),
                               t.bytes.begin() + std::ptrdiff_t(to),
                               [](float v) { return std::uint8_t(v); });
            else
                std::copy_n(from, rowValues, t.data.begin() + std::ptrdiff_t(to));
        }
    }
    if (t.kind == MaterialTexture::UNorm8 && !asBytes)
        for (float& v : t.data) v /= 255.0f;
    return t;
}

DirectionSet readDirectionAttribute(const Imf::Header& header, const char* attribute,
                                    const std::string& path) {
    const auto* text = header.findTypedAttribute<Imf::StringAttribute>(attribute);
    if (!text) return {};
    try {
        return DirectionSet::deserialize(text->value());
    } catch (const Error& e) {
        fail(path, std::string(attribute) + ": " + e.what());
    }
}

/** Refuses a file whose textures cannot fit before OpenEXR's C++ reader allocates anything sized
 *  from its headers: every texture is kept, each read through one more buffer of its size. */
void checkMaterialSize(const std::string& path) {
    const std::vector<ExrPartSize> sizes = readExrPartSizes(path);
    std::uint64_t total = 0;
    std::size_t largest = 0;
    for (std::size_t i = 0; i < sizes.size(); ++i) {
        const std::uint64_t bytes = exrReadBytes(sizes[i], 2);
        total = bytes > UINT64_MAX - total ? UINT64_MAX : total + bytes;
        if (bytes > exrReadBytes(sizes[largest], 2)) largest = i;
    }
    if (sizes.empty()) return;
    const ExrPartSize& big = sizes[largest];
    checkMemory(total, path + ": textures of " + std::to_string(sizes.size()) +
                           " part(s), the largest " + std::to_string(big.width) + "x" +
                           std::to_string(big.height) + " pixels x " +
                           std::to_string(big.channels) + " channels");
}

FittedMaterial readMaterial(
    const std::string& path,
    const std::function<CompactTextures(const std::string& method)>& compactFor) {
    checkMaterialSize(path);
    Imf::MultiPartInputFile file(path.c_str());
    const Imf::Header& header = file.header(0);
    const auto* method = header.findTypedAttribute<Imf::StringAttribute>(kMethodAttribute);
    if (!method) fail(path, "not an osgBTF fitted-material file (no osgBTF.method attribute)");
    const auto* version = header.findTypedAttribute<Imf::IntAttribute>(kVersionAttribute);
    if (!version) fail(path, "fitted-material file without an osgBTF.version attribute");
    if (version->value() != kFittedMaterialVersion)
        fail(path, "fitted-material container version " + std::to_string(version->value()) +
                       " is not supported (this build reads version " +
                       std::to_string(kFittedMaterialVersion) + ")");

    FittedMaterial material;
    material.source = path;
    material.method = method->value();
    if (material.method.empty()) fail(path, "the osgBTF.method attribute is empty");
    for (auto it = header.begin(); it != header.end(); ++it) {
        const std::string name = it.name();
        if (name.compare(0, kParamPrefix.size(), kParamPrefix) != 0) continue;
        const auto* value = dynamic_cast<const Imf::StringAttribute*>(&it.attribute());
        if (!value) fail(path, "attribute " + name + " is not a string");
        material.parameters[name.substr(kParamPrefix.size())] = value->value();
    }
    material.views = readDirectionAttribute(header, kViewsAttribute, path);
    material.lights = readDirectionAttribute(header, kLightsAttribute, path);
    const CompactTextures compact = compactFor(material.method);
    for (int part = 0; part < file.parts(); ++part)
        material.textures.push_back(readTexture(file, part, path, compact));
    return material;
}

}  // namespace

const MaterialTexture* FittedMaterial::findTexture(const std::string& name) const {
    for (const MaterialTexture& t : textures)
        if (t.name == name) return &t;
    return nullptr;
}

const MaterialTexture& FittedMaterial::texture(const std::string& name) const {
    if (const MaterialTexture* t = findTexture(name)) return *t;
    std::vector<std::string> names;
    for (const MaterialTexture& t : textures) names.push_back(t.name);
    fail(source, "fitted material '" + method + "' has no texture '" + name +
                     "' (textures: " + (names.empty() ? "none" : joinNames(names)) + ")");
}

const std::string& FittedMaterial::parameter(const std::string& key) const {
    auto it = parameters.find(key);
    if (it == parameters.end())
        fail(source, "fitted material '" + method + "' has no parameter '" + key + "'");
    return it->second;
}

void saveFittedMaterial(const FittedMaterial& material, const std::string& path) {
    validate(material, path);
    int maxWidth = 1, maxRows = 1;
    for (const MaterialTexture& t : material.textures) {
        maxWidth = std::max(maxWidth, t.width);
        maxRows = std::max(maxRows, t.height * t.depth);
    }
    // OpenEXR requires every part to share one display window.
    const Imath::Box2i displayWindow({0, 0}, {maxWidth - 1, maxRows - 1});
    std::vector<Imf::Header> headers;
    for (const MaterialTexture& t : material.textures)
        headers.push_back(partHeader(material, t, displayWindow));

    writeFileAtomically(path, [&](const std::string& temporaryPath) {
        try {
            Imf::MultiPartOutputFile file(temporaryPath.c_str(), headers.data(),
                                          int(headers.size()));
            for (std::size_t i = 0; i < material.textures.size(); ++i)
                writeTexture(file, int(i), material.textures[i]);
        } catch (const Error&) {
            throw;
        } catch (const std::exception& e) {
            fail(path, std::string("OpenEXR: ") + e.what());
        }
    });
}

FittedMaterial loadFittedMaterial(const std::string& path, CompactTextures compact) {
    return loadFittedMaterial(path, [compact](const std::string&) { return compact; });
}

FittedMaterial loadFittedMaterial(
    const std::string& path,
    const std::function<CompactTextures(const std::string& method)>& compactFor) {
    std::error_code ec;
    if (!fs::exists(path, ec)) fail(path, "no such file");
    if (fs::is_directory(path, ec)) fail(path, "is a folder, not a fitted-material file");
    if (fs::file_size(path, ec) == 0 && !ec) fail(path, "file is empty");
    {
        std::ifstream in(path, std::ios::binary);
        char magic[4] = {};
        if (!in.read(magic, 4) || !Imf::isImfMagic(magic))
            fail(path, "not an OpenEXR file (wrong magic number), so not a fitted-material file");
    }
    try {
        return readMaterial(path, compactFor);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        fail(path, std::string("OpenEXR: ") + e.what());
    }
}

}  // namespace osgBTF
