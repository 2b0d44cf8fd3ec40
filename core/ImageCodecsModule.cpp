// libosgBTFImageCodecs: the OpenImageIO side of core/ImageCodecs.h, a module of its own that
// libosgBTF loads on first use (why: ImageCodecs.h). It links OpenImageIO and nothing of osgBTF.
#include <unistd.h>
#include <algorithm>
#include <atomic>
#include <cctype>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <map>
#include <mutex>
#include <set>

#include <OpenImageIO/filesystem.h>
#include <OpenImageIO/imagebuf.h>
#include <OpenImageIO/imagebufalgo.h>
#include <OpenImageIO/imageio.h>

#include "core/FloatImage.h"
#include "core/ImageCodecs.h"

namespace osgBTF {

namespace {

namespace fs = std::filesystem;

/** OpenImageIO's plugin name for an extension (creating a reader or writer from a file name that
 *  does not exist fails in OpenImageIO 2.4). */
std::string pluginName(const std::string& extension) {
    if (extension == "jpg" || extension == "jpeg") return "jpeg";
    if (extension == "exr") return "openexr";
    if (extension == "tif") return "tiff";
    return extension;
}

std::string lowerExtension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    if (!ext.empty()) ext.erase(0, 1);
    for (char& c : ext) c = char(std::tolower(static_cast<unsigned char>(c)));
    return ext;
}

/** OpenImageIO's messages name the file it was given (a made-up or temporary name) and may span
 *  lines: name the image the caller knows instead, on one line. */
std::string tidy(std::string text, const std::string& usedName, const std::string& displayName) {
    if (text.empty()) return "unknown error";
    for (std::size_t at; (at = text.find(usedName)) != std::string::npos;)
        text.replace(at, usedName.size(), displayName);
    while (!text.empty() && (text.back() == '\n' || text.back() == ' ')) text.pop_back();
    for (std::size_t at; (at = text.find('\n')) != std::string::npos;) text.replace(at, 1, "; ");
    return text;
}

/** Whether the plugin for `extension` reads (or writes) through an IOProxy, asked once each. */
bool supportsProxy(const std::string& extension, bool output) {
    static std::mutex mutex;
    static std::map<std::pair<std::string, bool>, bool> known;
    const std::lock_guard<std::mutex> lock(mutex);
    const auto key = std::make_pair(extension, output);
    const auto found = known.find(key);
    if (found != known.end()) return found->second;
    bool supports = false;
    if (output) {
        auto probe = OIIO::ImageOutput::create(pluginName(extension));
        supports = probe && probe->supports("ioproxy");
    } else {
        auto probe = OIIO::ImageInput::create(pluginName(extension));
        supports = probe && probe->supports("ioproxy");
    }
    return known[key] = supports;
}

std::string temporaryName(const char* prefix, const std::string& extension) {
    static std::atomic<unsigned> counter{0};
    return (fs::temp_directory_path() / (prefix + std::to_string(::getpid()) + "-" +
                                         std::to_string(counter++) + "." + extension))
        .string();
}

void removeQuietly(const std::string& path) {
    std::error_code ignored;
    if (!path.empty()) fs::remove(path, ignored);
}

OIIO::ImageSpec readConfig() {
    OIIO::ImageSpec config;
    // Without this the PNG reader premultiplies by alpha: values would not be the stored ones.
    config.attribute("oiio:UnassociatedAlpha", 1);
    return config;
}

class OiioReader : public ImageReader {
public:
    /** `usedName`/`displayName` non-empty: messages are tidied (openBytes). */
    OiioReader(std::unique_ptr<OIIO::Filesystem::IOMemReader> proxy,
               std::unique_ptr<OIIO::ImageInput> input, int subimage, std::string usedName,
               std::string displayName, std::string temporaryFile)
        : proxy_(std::move(proxy)),
          input_(std::move(input)),
          subimage_(subimage),
          usedName_(std::move(usedName)),
          displayName_(std::move(displayName)),
          temporaryFile_(std::move(temporaryFile)) {
        const OIIO::ImageSpec& spec = input_->spec();
        header_.width = spec.width;
        header_.height = spec.height;
        header_.channels = spec.nchannels;
        header_.depth = spec.depth;
        header_.deep = spec.deep;
        header_.eightBit = spec.format == OIIO::TypeDesc::UINT8;
        header_.floating = spec.format.is_floating_point();
        header_.orientation = spec.get_int_attribute("Orientation", 1);
        header_.channelNames = spec.channelnames;
    }
    ~OiioReader() override {
        input_.reset();  // closes the file before it is removed
        removeQuietly(temporaryFile_);
    }
    const ImageHeader& header() const override { return header_; }
    void singleThreaded() override { input_->threads(1); }
    bool readBytes(unsigned char* destination) override {
        return input_->read_native_scanlines(subimage_, 0, 0, header_.height, 0, 0,
                                             header_.channels, destination);
    }
    bool readFloats(int channels, float* destination) override {
        return input_->read_image(subimage_, 0, 0, channels, OIIO::TypeDesc::FLOAT, destination);
    }
    std::string error() override {
        std::string text = input_->geterror();
        return usedName_.empty() ? text : tidy(std::move(text), usedName_, displayName_);
    }

private:
    std::unique_ptr<OIIO::Filesystem::IOMemReader> proxy_;  // outlives input_
    std::unique_ptr<OIIO::ImageInput> input_;
    int subimage_;
    std::string usedName_, displayName_, temporaryFile_;
    ImageHeader header_;
};

class OiioCodecs : public ImageCodecs {
public:
    std::unique_ptr<ImageReader> openFile(const std::string& path, int subimage,
                                          std::string& error) const override {
        const OIIO::ImageSpec config = readConfig();
        auto input = OIIO::ImageInput::open(path, &config);
        if (!input) {
            error = OIIO::geterror();
            return nullptr;
        }
        if (subimage != 0 && !input->seek_subimage(subimage, 0)) {
            error = "has no image " + std::to_string(subimage);
            return nullptr;
        }
        return std::make_unique<OiioReader>(nullptr, std::move(input), subimage, "", "", "");
    }

    std::unique_ptr<ImageReader> openBytes(const unsigned char* bytes, std::size_t size,
                                           const std::string& extension,
                                           const std::string& displayName,
                                           std::string& error) const override {
        const OIIO::ImageSpec config = readConfig();
        if (supportsProxy(extension, false)) {
            // ImageInput::open(name, config, proxy) looks for the file on disk in OpenImageIO
            // 2.4; creating the reader by plugin name and attaching the proxy does not.
            const std::string fakeName = "image." + extension;
            auto proxy = std::make_unique<OIIO::Filesystem::IOMemReader>(bytes, size);
            auto input = OIIO::ImageInput::create(pluginName(extension));
            if (!input) {
                error = tidy(OIIO::geterror(), fakeName, displayName);
                return nullptr;
            }
            OIIO::ImageSpec opened;
            if (!(input->set_ioproxy(proxy.get()) && input->open(fakeName, opened, config))) {
                error = tidy(input->geterror(), fakeName, displayName);
                return nullptr;
            }
            return std::make_unique<OiioReader>(std::move(proxy), std::move(input), 0, fakeName,
                                                displayName, "");
        }
        const std::string file = temporaryName("osgbtf-", extension);
        {
            std::ofstream out(file, std::ios::binary);
            out.write(reinterpret_cast<const char*>(bytes), std::streamsize(size));
            if (!out) {
                removeQuietly(file);
                error = "cannot write temporary file " + file;
                return nullptr;
            }
        }
        auto input = OIIO::ImageInput::open(file, &config);
        if (!input) {
            error = tidy(OIIO::geterror(), file, displayName);
            removeQuietly(file);
            return nullptr;
        }
        return std::make_unique<OiioReader>(nullptr, std::move(input), 0, file, displayName, file);
    }

    std::string writeFile(int width, int height, const std::vector<std::string>& names,
                          std::vector<float> pixels, const std::string& path,
                          const std::string& temporaryPath, bool half) const override {
        const std::string ext = lowerExtension(path);
        static const std::set<std::string> kEightBit = {"png", "jpg", "jpeg", "bmp", "tga",
                                                        "ppm", "pgm", "pnm",  "gif", "webp"};
        const bool eightBit = kEightBit.count(ext) > 0;
        OIIO::TypeDesc format = OIIO::TypeDesc::FLOAT;
        if (eightBit)
            format = OIIO::TypeDesc::UINT8;
        else if (half && (ext == "tif" || ext == "tiff"))
            format = OIIO::TypeDesc::HALF;
        if (eightBit)  // Done here so that NaN handling does not depend on the library version.
            for (float& v : pixels) v = std::isnan(v) ? 0.0f : std::clamp(v, 0.0f, 1.0f);

        // Chosen by the real name: the temporary name's extension would pick the wrong writer.
        auto output = OIIO::ImageOutput::create(path);
        if (!output) return "no image writer for extension '." + ext + "': " + OIIO::geterror();
        const int channels = int(names.size());
        if ((channels == 2 || channels == 4) && !output->supports("alpha"))
            return std::string(output->format_name()) +
                   " files store no alpha channel; the image has " + std::to_string(channels) +
                   " channels";
        OIIO::ImageSpec spec(width, height, channels, format);
        spec.channelnames = names;
        spec.alpha_channel = -1;
        for (int c = 0; c < channels; ++c) {
            const std::string& name = names[std::size_t(c)];
            if (name == "A" || (name.size() > 2 && name.compare(name.size() - 2, 2, ".A") == 0))
                spec.alpha_channel = c;
        }
        // The pixels are not premultiplied; without this PNG output divides by alpha.
        spec.attribute("oiio:UnassociatedAlpha", 1);
        if (!output->open(temporaryPath, spec)) return output->geterror();
        if (!output->write_image(OIIO::TypeDesc::FLOAT, pixels.data())) {
            const std::string message = output->geterror();
            output->close();
            return message;
        }
        if (!output->close()) return output->geterror();
        return "";
    }

    bool encode(int width, int height, const unsigned char* bytes, const float* floats,
                const std::string& extension, int jpegQuality, std::vector<unsigned char>& encoded,
                std::string& error, bool fullChroma) const override {
        OIIO::ImageSpec spec(width, height, 3,
                             bytes ? OIIO::TypeDesc::UINT8 : OIIO::TypeDesc::FLOAT);
        if (pluginName(extension) == "jpeg") {
            spec.attribute("Compression",
                           "jpeg:" + std::to_string(std::clamp(jpegQuality, 1, 100)));
            if (fullChroma) spec.attribute("jpeg:subsampling", "4:4:4");
        }
        const void* pixels = bytes ? static_cast<const void*>(bytes) : floats;
        encoded.clear();
        std::string file;
        std::unique_ptr<OIIO::ImageOutput> out;
        OIIO::Filesystem::IOVecOutput proxy(encoded);
        if (supportsProxy(extension, true)) {
            out = OIIO::ImageOutput::create(pluginName(extension));
            if (out && !(out->set_ioproxy(&proxy) && out->open("image." + extension, spec)))
                out.reset();
        } else {
            file = temporaryName("osgbtf-w", extension);
            out = OIIO::ImageOutput::create(file);
            if (out && !out->open(file, spec)) out.reset();
        }
        if (!out) {
            error = OIIO::geterror();
            removeQuietly(file);
            return false;
        }
        const bool ok = out->write_image(spec.format, pixels) && out->close();
        if (!ok) error = out->geterror();
        out.reset();
        if (ok && !file.empty()) {
            std::ifstream in(file, std::ios::binary);
            encoded.assign(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
        }
        removeQuietly(file);
        return ok;
    }

    bool drawText(FloatImage& image, int x, int y, const std::string& text, int size,
                  float value) const override {
        OIIO::ImageBuf buffer(
            OIIO::ImageSpec(image.width, image.height, image.channels, OIIO::TypeDesc::FLOAT),
            image.pixels.data());
        const std::vector<float> colour(std::size_t(image.channels), value);
        for (const char* font : {"DejaVuSans", ""}) {
            // A missing font is reported through the buffer's error state; it must be cleared.
            if (OIIO::ImageBufAlgo::render_text(buffer, x, y, text, size, font, colour))
                return true;
            (void)buffer.geterror();
        }
        return false;
    }
};

}  // namespace

}  // namespace osgBTF

extern "C" __attribute__((visibility("default"))) const osgBTF::ImageCodecs* osgbtfImageCodecs() {
    static const osgBTF::OiioCodecs codecs;
    return &codecs;
}
