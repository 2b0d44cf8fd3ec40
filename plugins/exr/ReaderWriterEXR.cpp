/* osgdb_btfexr: OpenEXR images for osgDB, built on OpenEXR 3.
 *
 * Usage: osgDB::readImageFile("x.exr"), osgviewer --image x.exr, osgconv in.png out.exr.
 *
 * The module is not named osgdb_exr, OpenSceneGraph's own EXR plugin (built where OSG finds
 * OpenEXR 2), so that installing osgBTF never replaces or hides it. It claims ".exr" and the
 * pseudo-extension ".btfexr" (x.exr.btfexr reads or writes x.exr); osgDB reaches it for ".exr"
 * through the alias exr -> btfexr that libosgBTF registers (scene/OwnPlugins.h), through
 * `-e btfexr` on a stock OSG program's command line, or through such a name.
 *
 * Reading: scanline or tiled, single- or multi-part files ("part=N" picks the part, default 0),
 * half/float/uint channels. The channels of one layer become the image (layer "" when the part
 * has unprefixed channels, else the first layer by name; "layer=NAME" picks another one):
 *   R,G,B[,A] -> GL_RGB / GL_RGBA;  Y[,A] -> GL_LUMINANCE / GL_LUMINANCE_ALPHA;
 *   otherwise 1-4 channels in name order -> GL_LUMINANCE, GL_LUMINANCE_ALPHA, GL_RGB, GL_RGBA.
 * Half channels stay half (GL_HALF_FLOAT, internal GL_*16F_ARB); float (and uint, converted)
 * channels come as GL_FLOAT with GL_*32F_ARB. The image covers the data window; row 0 is the
 * file's BOTTOM row (OSG's origin), the file's top row is row t()-1.
 *
 * Writing: 1-4 channel images (GL_LUMINANCE, GL_RED, GL_ALPHA, GL_LUMINANCE_ALPHA, GL_RGB,
 * GL_RGBA, GL_BGR, GL_BGRA) of GL_FLOAT, GL_HALF_FLOAT, GL_UNSIGNED_BYTE or GL_UNSIGNED_SHORT
 * (integers scaled to [0,1]). Output is half for half images and float for everything else,
 * unless the "half" or "float" option says otherwise; rows are flipped back so the file's top row
 * is the image's last row: reading what was written gives the same image. Files are written to a
 * temporary name and renamed, so a failed write never leaves a partial file.
 *
 * Every OpenEXR exception is caught: errors come back as ERROR_IN_READING_FILE /
 * ERROR_IN_WRITING_FILE results whose message is "FILE: problem". */

#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <sstream>
#include <stdexcept>
#include <string>
#include <vector>

#include <Imath/half.h>
#include <OpenEXR/Iex.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfIO.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfVersion.h>

#include <osg/Image>
#include <osg/Texture>
#include <osgDB/FileNameUtils>
#include <osgDB/FileUtils>
#include <osgDB/ReaderWriter>
#include <osgDB/Registry>

namespace {

/** Lets OpenEXR read from any std::istream (files, archives), relative to where it starts. */
class IStreamAdapter : public Imf::IStream {
public:
    IStreamAdapter(std::istream& in, const std::string& name)
        : Imf::IStream(name.c_str()), _in(in), _start(in.tellg()) {
        if (_start < 0) _start = 0;
    }
    bool read(char c[], int n) override {
        if (!_in) throw Iex::InputExc("Unexpected end of file.");
        _in.read(c, n);
        if (_in.gcount() != n)
            throw Iex::InputExc("Early end of file: read " + std::to_string(_in.gcount()) +
                                " out of " + std::to_string(n) + " requested bytes.");
        return true;
    }
    uint64_t tellg() override { return uint64_t(std::streamoff(_in.tellg()) - _start); }
    void seekg(uint64_t pos) override {
        _in.clear();
        _in.seekg(std::streamoff(_start + std::streamoff(pos)));
    }
    void clear() override { _in.clear(); }

private:
    std::istream& _in;
    std::streamoff _start;
};

class OStreamAdapter : public Imf::OStream {
public:
    OStreamAdapter(std::ostream& out, const std::string& name)
        : Imf::OStream(name.c_str()), _out(out), _start(out.tellp()) {
        if (_start < 0) _start = 0;
    }
    void write(const char c[], int n) override {
        _out.write(c, n);
        if (!_out) throw Iex::IoExc("Cannot write to the output stream.");
    }
    uint64_t tellp() override { return uint64_t(std::streamoff(_out.tellp()) - _start); }
    void seekp(uint64_t pos) override {
        _out.seekp(std::streamoff(_start + std::streamoff(pos)));
        if (!_out) throw Iex::IoExc("Cannot seek in the output stream.");
    }

private:
    std::ostream& _out;
    std::streamoff _start;
};

struct Settings {
    int part = 0;
    std::string layer;
    bool hasLayer = false;
    int forceType = 0;  // 0: keep the image's precision, else Imf::HALF + 1 or Imf::FLOAT + 1
    Imf::Compression compression = Imf::ZIP_COMPRESSION;
};

Settings parseOptions(const osgDB::ReaderWriter::Options* options) {
    Settings settings;
    if (!options) return settings;
    static const std::map<std::string, Imf::Compression> kCompressions = {
        {"none", Imf::NO_COMPRESSION},   {"rle", Imf::RLE_COMPRESSION},
        {"zips", Imf::ZIPS_COMPRESSION}, {"zip", Imf::ZIP_COMPRESSION},
        {"piz", Imf::PIZ_COMPRESSION},   {"pxr24", Imf::PXR24_COMPRESSION},
        {"b44", Imf::B44_COMPRESSION},   {"b44a", Imf::B44A_COMPRESSION},
        {"dwaa", Imf::DWAA_COMPRESSION}, {"dwab", Imf::DWAB_COMPRESSION}};
    std::istringstream words(options->getOptionString());
    std::string word;
    while (words >> word) {
        const std::size_t eq = word.find('=');
        const std::string key = word.substr(0, eq);
        const std::string value = eq == std::string::npos ? std::string() : word.substr(eq + 1);
        if (key == "half") {
            settings.forceType = Imf::HALF + 1;
        } else if (key == "float") {
            settings.forceType = Imf::FLOAT + 1;
        } else if (key == "part") {
            char* end = nullptr;
            const long part = std::strtol(value.c_str(), &end, 10);
            if (value.empty() || *end || part < 0 || part > 1000000)
                throw std::runtime_error("option part=" + value + " is not a part index");
            settings.part = int(part);
        } else if (key == "layer") {
            settings.layer = value;
            settings.hasLayer = true;
        } else if (key == "compression") {
            auto it = kCompressions.find(value);
            if (it == kCompressions.end())
                throw std::runtime_error("option compression=" + value + " is unknown");
            settings.compression = it->second;
        }
        // Other words belong to other plugins: osgDB hands one option string to all of them.
    }
    return settings;
}

std::string layerOf(const std::string& name) {
    const std::size_t dot = name.rfind('.');
    return dot == std::string::npos ? std::string() : name.substr(0, dot);
}

std::string baseOf(const std::string& name) {
    const std::size_t dot = name.rfind('.');
    return dot == std::string::npos ? name : name.substr(dot + 1);
}

std::string join(const std::vector<std::string>& names) {
    std::string text;
    for (const std::string& name : names) text += (text.empty() ? "" : ", ") + name;
    return text;
}

struct Layout {
    std::vector<std::string> channels;  // full channel names, in image order
    GLenum format;
};

Layout chooseChannels(const Imf::ChannelList& list, const Settings& settings) {
    std::map<std::string, std::vector<std::string>> layers;  // layer -> full names, sorted
    for (auto it = list.begin(); it != list.end(); ++it)
        layers[layerOf(it.name())].push_back(it.name());
    if (layers.empty()) throw std::runtime_error("the image has no channels");
    std::string layer = layers.begin()->first;
    if (settings.hasLayer) {
        if (!layers.count(settings.layer)) {
            std::vector<std::string> names;
            for (const auto& entry : layers) names.push_back("'" + entry.first + "'");
            throw std::runtime_error("no layer '" + settings.layer + "' (layers: " + join(names) +
                                     ")");
        }
        layer = settings.layer;
    }
    const std::vector<std::string>& names = layers[layer];
    std::map<std::string, std::string> byBase;
    for (const std::string& name : names) byBase[baseOf(name)] = name;

    Layout layout;
    if (byBase.count("R") && byBase.count("G") && byBase.count("B")) {
        layout.channels = {byBase["R"], byBase["G"], byBase["B"]};
        if (byBase.count("A")) layout.channels.push_back(byBase["A"]);
    } else if (byBase.count("Y")) {
        layout.channels = {byBase["Y"]};
        if (byBase.count("A")) layout.channels.push_back(byBase["A"]);
    } else {
        layout.channels = names;
        if (names.size() > 4)
            throw std::runtime_error("layer '" + layer + "' has " + std::to_string(names.size()) +
                                     " channels (" + join(names) +
                                     "), more than an osg::Image holds; pick a layer with layer=");
    }
    static const GLenum kFormats[] = {GL_LUMINANCE, GL_LUMINANCE_ALPHA, GL_RGB, GL_RGBA};
    layout.format = kFormats[layout.channels.size() - 1];
    return layout;
}

GLint internalFormat(GLenum format, bool half) {
    switch (format) {
        case GL_LUMINANCE:
            return half ? GL_LUMINANCE16F_ARB : GL_LUMINANCE32F_ARB;
        case GL_LUMINANCE_ALPHA:
            return half ? GL_LUMINANCE_ALPHA16F_ARB : GL_LUMINANCE_ALPHA32F_ARB;
        case GL_RGB:
            return half ? GL_RGB16F_ARB : GL_RGB32F_ARB;
        default:
            return half ? GL_RGBA16F_ARB : GL_RGBA32F_ARB;
    }
}

osg::ref_ptr<osg::Image> readExr(Imf::IStream& stream, const Settings& settings) {
    Imf::MultiPartInputFile file(stream);
    if (settings.part >= file.parts())
        throw std::runtime_error("the file has " + std::to_string(file.parts()) +
                                 " part(s), no part " + std::to_string(settings.part));
    const Imf::Header& header = file.header(settings.part);
    if (header.hasType() && Imf::isDeepData(header.type()))
        throw std::runtime_error("deep data is not supported");
    const Layout layout = chooseChannels(header.channels(), settings);
    bool half = true;
    for (const std::string& name : layout.channels) {
        const Imf::Channel& channel = header.channels()[name];
        if (channel.xSampling != 1 || channel.ySampling != 1)
            throw std::runtime_error("channel '" + name +
                                     "' is subsampled, which is not supported");
        half = half && channel.type == Imf::HALF;
    }

    const Imath::Box2i dw = header.dataWindow();
    const int64_t width = int64_t(dw.max.x) - dw.min.x + 1;
    const int64_t height = int64_t(dw.max.y) - dw.min.y + 1;
    if (width <= 0 || height <= 0) throw std::runtime_error("empty data window");
    const std::size_t channels = layout.channels.size();
    const std::size_t valueSize = half ? 2 : 4;
    const std::size_t rowBytes = std::size_t(width) * channels * valueSize;
    // A corrupt header can claim any size: refuse before allocating rather than die in new.
    if (uint64_t(rowBytes) * uint64_t(height) > (uint64_t(1) << 36))
        throw std::runtime_error("data window " + std::to_string(width) + "x" +
                                 std::to_string(height) + " is implausibly large");

    std::vector<unsigned char> topDown(rowBytes * std::size_t(height));
    Imf::FrameBuffer frameBuffer;
    for (std::size_t c = 0; c < channels; ++c)
        frameBuffer.insert(layout.channels[c], Imf::Slice::Make(half ? Imf::HALF : Imf::FLOAT,
                                                                topDown.data() + c * valueSize, dw,
                                                                channels * valueSize, rowBytes));
    Imf::InputPart input(file, settings.part);
    input.setFrameBuffer(frameBuffer);
    input.readPixels(dw.min.y, dw.max.y);

    osg::ref_ptr<osg::Image> image = new osg::Image;
    image->allocateImage(int(width), int(height), 1, layout.format, half ? GL_HALF_FLOAT : GL_FLOAT,
                         1);
    image->setInternalTextureFormat(internalFormat(layout.format, half));
    for (int64_t row = 0; row < height; ++row)
        std::memcpy(image->data(0, int(height - 1 - row)),
                    topDown.data() + std::size_t(row) * rowBytes, rowBytes);
    return image;
}

/** Channel names and image order for an osg::Image's pixel format. */
std::vector<std::string> channelNamesFor(GLenum format) {
    switch (format) {
        case GL_LUMINANCE:
        case GL_RED:
            return {"Y"};
        case GL_ALPHA:
            return {"A"};
        case GL_LUMINANCE_ALPHA:
            return {"Y", "A"};
        case GL_RGB:
            return {"R", "G", "B"};
        case GL_RGBA:
            return {"R", "G", "B", "A"};
        case GL_BGR:
            return {"B", "G", "R"};
        case GL_BGRA:
            return {"B", "G", "R", "A"};
        default:
            return {};
    }
}

float halfBitsToFloat(uint16_t bits) {
    Imath::half h;
    h.setBits(bits);
    return float(h);
}

void writeExr(const osg::Image& image, Imf::OStream& stream, const Settings& settings) {
    if (!image.data() || image.s() <= 0 || image.t() <= 0)
        throw std::runtime_error("the image is empty");
    if (image.r() != 1)
        throw std::runtime_error("3D images (r = " + std::to_string(image.r()) +
                                 ") cannot be written as EXR");
    if (image.isCompressed()) throw std::runtime_error("compressed images cannot be written");
    const std::vector<std::string> names = channelNamesFor(image.getPixelFormat());
    if (names.empty())
        throw std::runtime_error("unsupported pixel format 0x" + [&] {
            char text[16];
            std::snprintf(text, sizeof text, "%x", image.getPixelFormat());
            return std::string(text);
        }());
    const GLenum type = image.getDataType();
    if (type != GL_FLOAT && type != GL_HALF_FLOAT && type != GL_UNSIGNED_BYTE &&
        type != GL_UNSIGNED_SHORT)
        throw std::runtime_error("unsupported data type 0x" + [&] {
            char text[16];
            std::snprintf(text, sizeof text, "%x", type);
            return std::string(text);
        }() + " (use GL_FLOAT, GL_HALF_FLOAT, GL_UNSIGNED_BYTE or GL_UNSIGNED_SHORT)");

    const int width = image.s(), height = image.t();
    const std::size_t channels = names.size();
    std::vector<float> topDown(std::size_t(width) * std::size_t(height) * channels);
    for (int row = 0; row < height; ++row) {
        const unsigned char* src = image.data(0, row);
        float* dst = topDown.data() + std::size_t(height - 1 - row) * std::size_t(width) * channels;
        const std::size_t n = std::size_t(width) * channels;
        for (std::size_t i = 0; i < n; ++i) {
            switch (type) {
                case GL_FLOAT:
                    std::memcpy(&dst[i], src + 4 * i, 4);
                    break;
                case GL_HALF_FLOAT: {
                    uint16_t bits;
                    std::memcpy(&bits, src + 2 * i, 2);
                    dst[i] = halfBitsToFloat(bits);
                    break;
                }
                case GL_UNSIGNED_BYTE:
                    dst[i] = src[i] / 255.0f;
                    break;
                default: {
                    uint16_t v;
                    std::memcpy(&v, src + 2 * i, 2);
                    dst[i] = v / 65535.0f;
                }
            }
        }
    }

    const bool half =
        settings.forceType ? settings.forceType == Imf::HALF + 1 : type == GL_HALF_FLOAT;
    if (half) {
        const auto overflow = std::count_if(topDown.begin(), topDown.end(), [](float v) {
            return std::isfinite(v) && std::abs(v) > 65504.0f;
        });
        if (overflow)
            throw std::runtime_error(std::to_string(overflow) +
                                     " values exceed the half-float range (65504); write with "
                                     "the \"float\" option");
    }

    Imf::Header header(width, height);
    header.compression() = settings.compression;
    for (const std::string& name : names)
        header.channels().insert(name, Imf::Channel(half ? Imf::HALF : Imf::FLOAT));
    // OpenEXR converts on read but not on write: half channels need half slices.
    std::vector<Imath::half> halves;
    if (half) halves.assign(topDown.begin(), topDown.end());
    const std::size_t valueSize = half ? sizeof(Imath::half) : sizeof(float);
    const char* base = half ? (const char*)halves.data() : (const char*)topDown.data();
    const std::size_t xStride = channels * valueSize;
    Imf::FrameBuffer frameBuffer;
    for (std::size_t c = 0; c < channels; ++c)
        frameBuffer.insert(names[c],
                           Imf::Slice(half ? Imf::HALF : Imf::FLOAT, (char*)(base + c * valueSize),
                                      xStride, xStride * std::size_t(width)));
    Imf::OutputFile output(stream, header);
    output.setFrameBuffer(frameBuffer);
    output.writePixels(height);
}

bool hasExrMagic(std::istream& in) {
    const std::streampos start = in.tellg();
    char magic[4] = {};
    const bool ok = bool(in.read(magic, 4)) && Imf::isImfMagic(magic);
    in.clear();
    in.seekg(start);
    return ok;
}

}  // namespace

/** osgDB ReaderWriter for OpenEXR images; see the top of this file for the mapping. */
class ReaderWriterEXR : public osgDB::ReaderWriter {
public:
    ReaderWriterEXR() {
        supportsExtension("exr", "OpenEXR float image");
        supportsExtension("btfexr", "pseudo-loader: NAME.btfexr reads or writes NAME as OpenEXR");
        supportsOption("half",
                       "Write 16-bit half channels (default: half for GL_HALF_FLOAT "
                       "images, 32-bit float otherwise)");
        supportsOption("float", "Write 32-bit float channels");
        supportsOption("compression=<none|rle|zips|zip|piz|pxr24|b44|b44a|dwaa|dwab>",
                       "Compression when writing (default zip, lossless)");
        supportsOption("part=<n>", "Part of a multi-part file to read (default 0)");
        supportsOption("layer=<name>", "Channel layer to read, e.g. 'diffuse' for diffuse.R/G/B");
    }

    const char* className() const override { return "OpenEXR image reader/writer"; }

    ReadResult readObject(const std::string& file, const Options* options) const override {
        return readImage(file, options);
    }
    ReadResult readObject(std::istream& in, const Options* options) const override {
        return readImage(in, options);
    }

    ReadResult readImage(const std::string& name, const Options* options) const override {
        if (!acceptsExtension(osgDB::getLowerCaseFileExtension(name)))
            return ReadResult::FILE_NOT_HANDLED;
        const std::string file = withoutPseudoExtension(name);
        const std::string path = osgDB::findDataFile(file, options);
        if (path.empty()) return ReadResult::FILE_NOT_FOUND;
        std::ifstream in(path, std::ios::binary);
        if (!in) return ReadResult(path + ": cannot open the file");
        ReadResult result = read(in, path, options);
        // The name as asked for: a scene written back reads it the same way (pseudo-name too).
        if (result.getImage()) result.getImage()->setFileName(name);
        return result;
    }

    ReadResult readImage(std::istream& in, const Options* options) const override {
        return read(in, "<stream>", options);
    }

    WriteResult writeImage(const osg::Image& image, const std::string& name,
                           const Options* options) const override {
        if (!acceptsExtension(osgDB::getLowerCaseFileExtension(name)))
            return WriteResult::FILE_NOT_HANDLED;
        const std::string file = withoutPseudoExtension(name);
        // Written under a temporary name and renamed, so a failure never leaves a partial file.
        const std::string temporary = file + ".tmp" + std::to_string(getpid());
        WriteResult result;
        {
            std::ofstream out(temporary, std::ios::binary | std::ios::trunc);
            if (!out) return WriteResult(file + ": cannot create '" + temporary + "'");
            result = write(image, out, file, options);
            out.close();
            if (result.success() && !out)
                result = WriteResult(file + ": cannot finish writing '" + temporary + "'");
        }
        if (result.success() && std::rename(temporary.c_str(), file.c_str()) != 0)
            result = WriteResult(file + ": cannot rename '" + temporary +
                                 "' to it: " + std::strerror(errno));
        if (!result.success()) std::remove(temporary.c_str());
        return result;
    }

    WriteResult writeImage(const osg::Image& image, std::ostream& out,
                           const Options* options) const override {
        return write(image, out, "<stream>", options);
    }

private:
    /** "x.exr.btfexr" names the file x.exr. */
    static std::string withoutPseudoExtension(const std::string& name) {
        return osgDB::getLowerCaseFileExtension(name) == "btfexr"
                   ? osgDB::getNameLessExtension(name)
                   : name;
    }

    static ReadResult read(std::istream& in, const std::string& name, const Options* options) {
        try {
            if (!hasExrMagic(in)) {
                in.clear();
                const std::streampos start = in.tellg();
                in.seekg(0, std::ios::end);
                const bool empty = in.tellg() == start;
                return ReadResult(name + (empty ? ": file is empty"
                                                : ": not an OpenEXR file (wrong magic number)"));
            }
            const Settings settings = parseOptions(options);
            IStreamAdapter stream(in, name);
            return ReadResult(readExr(stream, settings).release());
        } catch (const std::exception& e) {
            return ReadResult(name + ": " + e.what());
        } catch (...) {
            return ReadResult(name + ": unknown error while reading");
        }
    }

    static WriteResult write(const osg::Image& image, std::ostream& out, const std::string& name,
                             const Options* options) {
        try {
            const Settings settings = parseOptions(options);
            OStreamAdapter stream(out, name);
            writeExr(image, stream, settings);
            return WriteResult::FILE_SAVED;
        } catch (const std::exception& e) {
            return WriteResult(name + ": " + e.what());
        } catch (...) {
            return WriteResult(name + ": unknown error while writing");
        }
    }
};

REGISTER_OSGPLUGIN(btfexr, ReaderWriterEXR)
