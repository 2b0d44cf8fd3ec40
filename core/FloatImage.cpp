#include "core/FloatImage.h"

#include <signal.h>
#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <condition_variable>
#include <cstdint>
#include <cstring>
#include <exception>
#include <filesystem>
#include <fstream>
#include <iterator>
#include <memory>
#include <mutex>
#include <set>
#include <sstream>

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfFrameBuffer.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputPart.h>
#include <OpenEXR/ImfMultiPartInputFile.h>
#include <OpenEXR/ImfOutputFile.h>
#include <OpenEXR/ImfPartType.h>
#include <OpenEXR/ImfVersion.h>

#include "core/Error.h"
#include "core/ImageCodecs.h"
#include "core/MeasuredBtf.h"
#include "core/SizeGuard.h"

namespace fs = std::filesystem;

namespace osgBTF {

namespace {

std::string lowerExtension(const std::string& path) {
    std::string ext = fs::path(path).extension().string();
    if (!ext.empty()) ext.erase(0, 1);
    std::transform(ext.begin(), ext.end(), ext.begin(),
                   [](unsigned char c) { return char(std::tolower(c)); });
    return ext;
}

/** Missing and empty files get their own message: the codecs' messages for them are cryptic. */
void checkReadable(const std::string& path) {
    std::error_code ec;
    const fs::file_status status = fs::status(path, ec);
    if (!fs::exists(status)) fail(path, "no such file");
    if (fs::is_directory(status)) fail(path, "is a folder, not an image file");
    if (fs::file_size(path, ec) == 0 && !ec) fail(path, "file is empty");
}

bool hasExrMagic(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    char bytes[4] = {};
    return in.read(bytes, 4) && Imf::isImfMagic(bytes);
}

// Natural order so that c2 comes before c10.
bool naturalLess(const std::string& a, const std::string& b) {
    std::size_t i = 0, j = 0;
    while (i < a.size() && j < b.size()) {
        if (std::isdigit((unsigned char)a[i]) && std::isdigit((unsigned char)b[j])) {
            std::size_t ie = i, je = j;
            while (ie < a.size() && std::isdigit((unsigned char)a[ie])) ++ie;
            while (je < b.size() && std::isdigit((unsigned char)b[je])) ++je;
            std::string na = a.substr(i, ie - i), nb = b.substr(j, je - j);
            na.erase(0, std::min(na.find_first_not_of('0'), na.size()));
            nb.erase(0, std::min(nb.find_first_not_of('0'), nb.size()));
            if (na.size() != nb.size()) return na.size() < nb.size();
            if (na != nb) return na < nb;
            i = ie;
            j = je;
        } else {
            if (a[i] != b[j]) return a[i] < b[j];
            ++i;
            ++j;
        }
    }
    return a.size() - i < b.size() - j;
}

struct ChannelKey {
    std::string layer, base;
    int rank;
};

ChannelKey channelKey(const std::string& name) {
    const std::size_t dot = name.rfind('.');
    ChannelKey key;
    key.layer = dot == std::string::npos ? std::string() : name.substr(0, dot);
    key.base = dot == std::string::npos ? name : name.substr(dot + 1);
    static const char* const kRgba[] = {"R", "G", "B", "A"};
    key.rank = 4;
    for (int i = 0; i < 4; ++i)
        if (key.base == kRgba[i]) key.rank = i;
    return key;
}

/** EXR sorts channels alphabetically (A before R); users expect R, G, B, A. */
std::vector<std::string> canonicalChannelOrder(std::vector<std::string> names) {
    std::stable_sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
        const ChannelKey ka = channelKey(a), kb = channelKey(b);
        if (ka.layer != kb.layer) return ka.layer < kb.layer;
        if (ka.rank != kb.rank) return ka.rank < kb.rank;
        return naturalLess(ka.base, kb.base);
    });
    return names;
}

std::vector<std::string> defaultChannelNames(int channels) {
    switch (channels) {
        case 1:
            return {"Y"};
        case 2:
            return {"R", "G"};
        case 3:
            return {"R", "G", "B"};
        case 4:
            return {"R", "G", "B", "A"};
        default:
            break;
    }
    std::vector<std::string> names;
    for (int c = 0; c < channels; ++c) names.push_back("c" + std::to_string(c));
    return names;
}

FloatImage readExrPart(Imf::MultiPartInputFile& file, int part, const std::string& path) {
    const std::string where = file.parts() > 1 ? " (part " + std::to_string(part) + ")" : "";
    const Imf::Header& header = file.header(part);
    if (header.hasType() && Imf::isDeepData(header.type()))
        fail(path, "deep data" + where + " is not supported");
    const Imath::Box2i dw = header.dataWindow();
    const std::int64_t width = std::int64_t(dw.max.x) - dw.min.x + 1;
    const std::int64_t height = std::int64_t(dw.max.y) - dw.min.y + 1;
    if (width <= 0 || height <= 0) fail(path, "empty data window" + where);

    std::vector<std::string> names;
    for (auto it = header.channels().begin(); it != header.channels().end(); ++it) {
        if (it.channel().xSampling != 1 || it.channel().ySampling != 1)
            fail(path, "channel '" + std::string(it.name()) + "'" + where +
                           " is subsampled, which is not supported");
        names.push_back(it.name());
    }
    if (names.empty()) fail(path, "no channels" + where);
    names = canonicalChannelOrder(std::move(names));

    const std::int64_t channels = std::int64_t(names.size());
    // readExrPartSizes checked the same sizes before the file was opened; this guards callers
    // that opened it themselves.
    checkMemory(
        saturatedProduct({std::uint64_t(width), std::uint64_t(height), std::uint64_t(channels), 4}),
        path + where);
    FloatImage image{int(width), int(height), int(channels)};
    image.channelNames = names;

    const std::size_t xStride = sizeof(float) * std::size_t(channels);
    Imf::FrameBuffer frameBuffer;
    for (std::size_t c = 0; c < names.size(); ++c)
        frameBuffer.insert(names[c], Imf::Slice::Make(Imf::FLOAT, image.pixels.data() + c, dw,
                                                      xStride, xStride * std::size_t(width)));
    Imf::InputPart input(file, part);
    input.setFrameBuffer(frameBuffer);
    input.readPixels(dw.min.y, dw.max.y);
    return image;
}

std::string exrPartsText(const std::string& path, const std::vector<ExrPartSize>& sizes, int part) {
    const ExrPartSize& p = sizes[std::size_t(part)];
    return path + ": " + std::to_string(p.width) + "x" + std::to_string(p.height) + " pixels x " +
           std::to_string(p.channels) + " channels" +
           (sizes.size() > 1 ? " (part " + std::to_string(part) + ")" : "");
}

/** Runs `body` and turns the codecs' exceptions into Error messages that name the file. */
template <typename Body>
auto withExrErrors(const std::string& path, Body body) -> decltype(body()) {
    try {
        return body();
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        fail(path, std::string("OpenEXR: ") + e.what());
    }
}

FloatImage readWithCodecs(const std::string& path, int part) {
    std::string error;
    const std::unique_ptr<ImageReader> input = imageCodecs().openFile(path, part, error);
    if (!input) fail(path, error.empty() ? "unknown or unsupported image format" : error);
    const ImageHeader& header = input->header();
    if (header.deep) fail(path, "deep images are not supported");
    if (header.depth > 1)
        fail(path, "volume images (depth " + std::to_string(header.depth) + ") are not supported");
    if (header.width <= 0 || header.height <= 0 || header.channels <= 0)
        fail(path, "image has no pixels");
    checkMemory(saturatedProduct({std::uint64_t(header.width), std::uint64_t(header.height),
                                  std::uint64_t(header.channels), 4}),
                path + ": " + std::to_string(header.width) + "x" + std::to_string(header.height) +
                    " pixels x " + std::to_string(header.channels) + " channels");
    FloatImage image(header.width, header.height, header.channels);
    image.channelNames = header.channelNames;
    image.channelNames.resize(std::size_t(header.channels));
    if (!input->readFloats(header.channels, image.pixels.data())) {
        const std::string message = input->error();
        fail(path, message.empty() ? "cannot read the pixels" : message);
    }
    return image;
}

float srgbEncode(float v) {
    return v <= 0.0031308f ? 12.92f * v : 1.055f * std::pow(v, 1.0f / 2.4f) - 0.055f;
}

void writeExr(const FloatImage& image, const std::vector<std::string>& names,
              const std::vector<float>& pixels, const std::string& path,
              const std::string& temporaryPath, bool half) {
    withExrErrors(path, [&] {
        Imf::Header header(image.width, image.height);
        header.compression() = Imf::ZIP_COMPRESSION;
        for (const std::string& name : names)
            header.channels().insert(name, Imf::Channel(half ? Imf::HALF : Imf::FLOAT));
        // OpenEXR converts on read but not on write: half channels need half slices.
        std::vector<Imath::half> halves;
        if (half) halves.assign(pixels.begin(), pixels.end());
        const std::size_t valueSize = half ? sizeof(Imath::half) : sizeof(float);
        const char* base = half ? (const char*)halves.data() : (const char*)pixels.data();
        const std::size_t xStride = valueSize * std::size_t(image.channels);
        Imf::FrameBuffer frameBuffer;
        for (std::size_t c = 0; c < names.size(); ++c)
            frameBuffer.insert(
                names[c], Imf::Slice(half ? Imf::HALF : Imf::FLOAT, (char*)(base + c * valueSize),
                                     xStride, xStride * std::size_t(image.width)));
        Imf::OutputFile output(temporaryPath.c_str(), header);
        output.setFrameBuffer(frameBuffer);
        output.writePixels(image.height);
    });
}

}  // namespace

FloatImage::FloatImage(int width_, int height_, int channels_)
    : width(width_),
      height(height_),
      channels(channels_),
      pixels(std::size_t(width_) * std::size_t(height_) * std::size_t(channels_), 0.0f) {}

int FloatImage::channelIndex(const std::string& name) const {
    for (std::size_t c = 0; c < channelNames.size(); ++c)
        if (channelNames[c] == name) return int(c);
    return -1;
}

FloatImage readFloatImage(const std::string& path, int part) {
    checkReadable(path);
    if (part < 0) fail(path, "invalid part index " + std::to_string(part));
    if (hasExrMagic(path)) {
        const std::vector<ExrPartSize> sizes = readExrPartSizes(path);
        if (std::size_t(part) < sizes.size())
            checkMemory(exrReadBytes(sizes[std::size_t(part)]), exrPartsText(path, sizes, part));
        return withExrErrors(path, [&] {
            Imf::MultiPartInputFile file(path.c_str());
            if (part >= file.parts())
                fail(path, "has " + std::to_string(file.parts()) + " part(s), no part " +
                               std::to_string(part));
            return readExrPart(file, part, path);
        });
    }
    if (lowerExtension(path) == "exr") fail(path, "not an OpenEXR file (wrong magic number)");
    try {
        return readWithCodecs(path, part);
    } catch (const Error&) {
        throw;
    } catch (const std::exception& e) {
        fail(path, std::string("OpenImageIO: ") + e.what());
    }
}

std::vector<FloatImage> readExrParts(const std::string& path) {
    checkReadable(path);
    if (!hasExrMagic(path)) fail(path, "not an OpenEXR file (wrong magic number)");
    const std::vector<ExrPartSize> sizes = readExrPartSizes(path);
    // All parts are kept at once, so their sum is what must fit.
    std::uint64_t total = 0;
    for (const ExrPartSize& size : sizes) {
        const std::uint64_t bytes = exrReadBytes(size);
        total = bytes > UINT64_MAX - total ? UINT64_MAX : total + bytes;
    }
    checkMemory(total, path + ": " + std::to_string(sizes.size()) +
                           (sizes.size() == 1 ? " part" : " parts"));
    return withExrErrors(path, [&] {
        Imf::MultiPartInputFile file(path.c_str());
        std::vector<FloatImage> images;
        for (int part = 0; part < file.parts(); ++part)
            images.push_back(readExrPart(file, part, path));
        return images;
    });
}

void writeFloatImage(const FloatImage& image, const std::string& path, bool half,
                     bool srgbEncodeValues) {
    if (image.width <= 0 || image.height <= 0 || image.channels <= 0)
        fail(path, "cannot write an empty image (" + std::to_string(image.width) + "x" +
                       std::to_string(image.height) + ", " + std::to_string(image.channels) +
                       " channels)");
    const std::size_t expected =
        std::size_t(image.width) * std::size_t(image.height) * std::size_t(image.channels);
    if (image.pixels.size() != expected)
        fail(path, "image has " + std::to_string(image.pixels.size()) + " values, " +
                       std::to_string(image.width) + "x" + std::to_string(image.height) + "x" +
                       std::to_string(image.channels) + " needs " + std::to_string(expected));
    if (image.channelNames.size() > std::size_t(image.channels))
        fail(path, "image has " + std::to_string(image.channelNames.size()) +
                       " channel names for " + std::to_string(image.channels) + " channels");

    std::vector<std::string> names = defaultChannelNames(image.channels);
    for (std::size_t c = 0; c < image.channelNames.size(); ++c)
        if (!image.channelNames[c].empty()) names[c] = image.channelNames[c];
    if (std::set<std::string>(names.begin(), names.end()).size() != names.size())
        fail(path, "channel names repeat");

    const std::string ext = lowerExtension(path);
    if (ext == "exr" && half) {
        std::size_t overflow = 0;
        for (float v : image.pixels)
            if (std::isfinite(v) && std::abs(v) > 65504.0f) ++overflow;
        if (overflow)
            fail(path, std::to_string(overflow) +
                           " values exceed the half-float range (65504); write float instead");
    }

    std::vector<float> pixels = image.pixels;
    if (srgbEncodeValues) {
        for (std::size_t c = 0; c < names.size(); ++c) {
            if (channelKey(names[c]).base == "A") continue;
            for (std::size_t i = c; i < pixels.size(); i += names.size())
                pixels[i] = srgbEncode(std::max(pixels[i], 0.0f));
        }
    }

    writeFileAtomically(path, [&](const std::string& temporaryPath) {
        if (ext == "exr")
            writeExr(image, names, pixels, path, temporaryPath, half);
        else if (const std::string problem =
                     imageCodecs().writeFile(image.width, image.height, names, std::move(pixels),
                                             path, temporaryPath, half);
                 !problem.empty())
            fail(path, problem);
    });
}

std::size_t countNonFinite(const FloatImage& image) {
    return std::size_t(std::count_if(image.pixels.begin(), image.pixels.end(),
                                     [](float v) { return !std::isfinite(v); }));
}

void requireFinite(const FloatImage& image, const std::string& path) {
    std::size_t nan = 0, inf = 0, first = image.pixels.size();
    for (std::size_t i = 0; i < image.pixels.size(); ++i) {
        const float v = image.pixels[i];
        if (std::isfinite(v)) continue;
        (std::isnan(v) ? nan : inf) += 1;
        first = std::min(first, i);
    }
    if (nan == 0 && inf == 0) return;
    const std::size_t channels = std::size_t(std::max(image.channels, 1));
    const std::size_t c = first % channels, pixel = first / channels;
    const std::size_t width = std::size_t(std::max(image.width, 1));
    std::ostringstream message;
    message << nan << " NaN and " << inf << " Inf values (first at x=" << pixel % width
            << ", y=" << pixel / width << ", channel ";
    if (c < image.channelNames.size() && !image.channelNames[c].empty())
        message << "'" << image.channelNames[c] << "')";
    else
        message << c << ")";
    fail(path, message.str());
}

namespace {

/** Threads of one process writing the same path would share its temporary name ("<path>.tmp" +
 *  the process id): they take turns instead (e.g. two threads filling one fit-cache entry). */
class PathTurn {
public:
    explicit PathTurn(std::string path) : _path(std::move(path)) {
        std::unique_lock<std::mutex> lock(mutex());
        changed().wait(lock, [&] { return busy().count(_path) == 0; });
        busy().insert(_path);
    }
    ~PathTurn() {
        {
            std::lock_guard<std::mutex> lock(mutex());
            busy().erase(_path);
        }
        changed().notify_all();
    }
    PathTurn(const PathTurn&) = delete;
    PathTurn& operator=(const PathTurn&) = delete;

private:
    static std::mutex& mutex() {
        static std::mutex m;
        return m;
    }
    static std::condition_variable& changed() {
        static std::condition_variable c;
        return c;
    }
    static std::set<std::string>& busy() {
        static std::set<std::string> paths;
        return paths;
    }
    std::string _path;
};

}  // namespace

void writeFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temporaryPath)>& write) {
    const PathTurn turn(fs::absolute(path).lexically_normal().string());
    fs::path folder = fs::path(path).parent_path();
    if (folder.empty()) folder = ".";
    std::error_code ec;
    if (!fs::is_directory(folder, ec))
        fail(path, "folder '" + folder.string() + "' does not exist");
    if (fs::is_directory(path, ec)) fail(path, "is a folder; cannot write a file there");
    // The process id keeps two processes writing the same file from sharing a temporary file.
    const std::string temporaryPath = path + ".tmp" + std::to_string(getpid());
    try {
        write(temporaryPath);
    } catch (...) {
        fs::remove(temporaryPath, ec);
        throw;
    }
    fs::rename(temporaryPath, path, ec);
    if (ec) {
        std::error_code ignored;
        fs::remove(temporaryPath, ignored);
        fail(path, "cannot move the finished temporary file into place: " + ec.message());
    }
}

std::string readWholeFile(const std::string& path) {
    std::error_code ec;
    if (std::filesystem::is_directory(path, ec)) fail(path, "is not a regular file");
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, std::string("cannot be read: ") + std::strerror(errno));
    std::string bytes((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
    if (in.bad()) fail(path, "cannot be read");
    return bytes;
}

void writeTextAtomically(const std::string& path, const std::string& text) {
    writeFileAtomically(path, [&](const std::string& temporary) {
        std::ofstream out(temporary);
        out << text;
        out.close();
        if (!out) fail(path, "cannot write");
    });
}

std::size_t removeStaleTemporaries(const std::string& folder,
                                   const std::function<bool(const std::string& stem)>& matches) {
    std::size_t removed = 0;
    std::error_code ec;
    for (const auto& entry : fs::directory_iterator(folder.empty() ? "." : folder, ec)) {
        const std::string name = entry.path().filename().string();
        std::size_t digits = name.size();
        while (digits > 0 && std::isdigit(static_cast<unsigned char>(name[digits - 1]))) --digits;
        if (digits == name.size() || digits < 4 || name.size() - digits > 9) continue;
        const std::string mark = name.substr(digits - 4, 4);
        if (mark != ".tmp" && mark != ".old") continue;
        if (!matches(name.substr(0, digits - 4))) continue;
        const pid_t pid = pid_t(std::stol(name.substr(digits)));
        // kill(pid, 0) only asks whether the process exists; EPERM means it does (another user).
        if (pid <= 0 || pid == getpid() || ::kill(pid, 0) == 0 || errno != ESRCH) continue;
        std::error_code ignored;
        if (fs::remove_all(entry.path(), ignored) > 0 && !ignored) ++removed;
    }
    return removed;
}

}  // namespace osgBTF
