#include "harness/sample/Ubo2003Writer.h"

#include <unistd.h>
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <memory>
#include <sstream>
#include <vector>

#include <tbb/parallel_for.h>
#include <zip.h>

#include "core/Error.h"
#include "core/ImageCodecs.h"

namespace osgBTF {

namespace {

namespace fs = std::filesystem;

const char* extensionOf(Ubo2003ImageFormat format) {
    switch (format) {
        case Ubo2003ImageFormat::Png:
            return "png";
        case Ubo2003ImageFormat::Hdr:
            return "hdr";
        case Ubo2003ImageFormat::Exr:
            return "exr";
        case Ubo2003ImageFormat::Jpeg:
            break;
    }
    return "jpg";
}

int integerDegrees(float angle, const std::string& path, const char* what, std::size_t index) {
    const long rounded = std::lround(angle);
    if (!std::isfinite(angle) || std::abs(angle - float(rounded)) > 1e-3f || rounded < 0 ||
        rounded > 999) {
        std::ostringstream problem;
        problem << what << ' ' << index << " has angle " << angle
                << " degrees; UBO2003 names hold only integer degrees in [0, 999]";
        fail(path, problem.str());
    }
    return int(rounded);
}

void checkIntegerDirections(const MeasuredBtf& btf, const std::string& path) {
    if (btf.empty()) fail(path, "cannot write an empty BTF");
    for (std::size_t i = 0; i < btf.lightCount(); ++i) {
        integerDegrees(btf.lights()[i].theta, path, "light", i);
        integerDegrees(btf.lights()[i].phi, path, "light", i);
    }
    for (std::size_t i = 0; i < btf.viewCount(); ++i) {
        integerDegrees(btf.views()[i].theta, path, "view", i);
        integerDegrees(btf.views()[i].phi, path, "view", i);
    }
}

/** Encodes one image to the bytes of a file; path is only for messages. */
std::vector<unsigned char> encode(const MeasuredBtf& btf, std::size_t view, std::size_t light,
                                  Ubo2003ImageFormat format, int jpegQuality,
                                  const std::string& path) {
    const int w = btf.width(), h = btf.height();
    const std::vector<float> image = btf.image(view, light);
    const bool eightBit = format == Ubo2003ImageFormat::Jpeg || format == Ubo2003ImageFormat::Png;
    // Image files are top row first; MeasuredBtf rows are bottom-up.
    std::vector<unsigned char> bytes8;
    std::vector<float> floats;
    if (eightBit) {
        bytes8.resize(image.size());
        for (int y = 0; y < h; ++y) {
            const float* src = image.data() + std::size_t(h - 1 - y) * w * 3;
            unsigned char* dst = bytes8.data() + std::size_t(y) * w * 3;
            for (int i = 0; i < w * 3; ++i)
                dst[i] = (unsigned char)std::lround(std::clamp(src[i], 0.0f, 1.0f) * 255.0f);
        }
    } else {
        floats.resize(image.size());
        for (int y = 0; y < h; ++y)
            std::copy_n(image.data() + std::size_t(h - 1 - y) * w * 3, w * 3,
                        floats.data() + std::size_t(y) * w * 3);
    }
    std::vector<unsigned char> encoded;
    std::string error;
    if (!imageCodecs().encode(w, h, eightBit ? bytes8.data() : nullptr, floats.data(),
                              extensionOf(format), jpegQuality, encoded, error))
        fail(path, std::string("cannot encode ") + extensionOf(format) + ": " + error);
    return encoded;
}

std::uint64_t rawImageBytes(const MeasuredBtf& btf, Ubo2003ImageFormat format) {
    const bool eightBit = format == Ubo2003ImageFormat::Jpeg || format == Ubo2003ImageFormat::Png;
    const std::uint64_t perPixel = eightBit ? 3 : format == Ubo2003ImageFormat::Hdr ? 4 : 12;
    return std::uint64_t(btf.width()) * btf.height() * perPixel;
}

std::string zipErrorText(int code) {
    zip_error_t error;
    zip_error_init_with_code(&error, code);
    std::string text = zip_error_strerror(&error);
    zip_error_fini(&error);
    return text;
}

}  // namespace

std::string ubo2003MemberName(int index, const Direction& light, const Direction& view,
                              Ubo2003ImageFormat format) {
    char name[96];
    std::snprintf(name, sizeof name, "%05d tl%03ld pl%03ld tv%03ld pv%03ld.%s", index,
                  std::lround(light.theta), std::lround(light.phi), std::lround(view.theta),
                  std::lround(view.phi), extensionOf(format));
    return name;
}

void writeUbo2003Zip(const MeasuredBtf& btf, const std::string& zipPath, Ubo2003ImageFormat format,
                     int jpegQuality) {
    checkIntegerDirections(btf, zipPath);
    const std::size_t nL = btf.lightCount(), nV = btf.viewCount(), count = nL * nV;
    // libzip reads the buffers only in zip_close, so all encoded images are alive at once; the raw
    // size bounds the encoded one for every format used here.
    checkMemory(rawImageBytes(btf, format) * count, zipPath + ": encoded images");
    std::vector<std::vector<unsigned char>> encoded(count);
    tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
        encoded[i] = encode(btf, i % nV, i / nV, format, jpegQuality, zipPath);
    });

    // Per process: two writers of one archive never share (and truncate) one temporary.
    const std::string tmp = zipPath + ".tmp" + std::to_string(::getpid());
    int code = 0;
    zip_t* zip = zip_open(tmp.c_str(), ZIP_CREATE | ZIP_TRUNCATE, &code);
    if (!zip) fail(zipPath, "cannot create " + tmp + ": " + zipErrorText(code));
    auto abandon = [&](const std::string& problem) {
        zip_discard(zip);
        std::error_code ignored;
        fs::remove(tmp, ignored);
        fail(zipPath, problem);
    };
    const bool store = format != Ubo2003ImageFormat::Hdr;
    for (std::size_t i = 0; i < count; ++i) {
        const std::size_t light = i / nV, view = i % nV;
        const std::string name =
            ubo2003MemberName(int(i), btf.lights()[light], btf.views()[view], format);
        zip_source_t* src = zip_source_buffer(zip, encoded[i].data(), encoded[i].size(), 0);
        if (!src) abandon("cannot add '" + name + "': " + zip_strerror(zip));
        const zip_int64_t index = zip_file_add(zip, name.c_str(), src, ZIP_FL_ENC_UTF_8);
        if (index < 0) {
            zip_source_free(src);
            abandon("cannot add '" + name + "': " + zip_strerror(zip));
        }
        if (store && zip_set_file_compression(zip, zip_uint64_t(index), ZIP_CM_STORE, 0) != 0)
            abandon("cannot set compression of '" + name + "': " + zip_strerror(zip));
    }
    if (zip_close(zip) != 0) abandon("cannot write archive: " + std::string(zip_strerror(zip)));
    std::error_code ec;
    fs::rename(tmp, zipPath, ec);
    if (ec) {
        fs::remove(tmp, ec);
        fail(zipPath, "cannot rename " + tmp + ": " + ec.message());
    }
}

void writeUbo2003Folder(const MeasuredBtf& btf, const std::string& folder,
                        Ubo2003ImageFormat format, int jpegQuality) {
    checkIntegerDirections(btf, folder);
    std::error_code ec;
    if (fs::exists(folder, ec)) fail(folder, "already exists; will not write images into it");
    const fs::path tmp = folder + ".tmp" + std::to_string(::getpid());
    fs::remove_all(tmp, ec);
    if (!fs::create_directories(tmp, ec) || ec)
        fail(folder, "cannot create " + tmp.string() + ": " + ec.message());
    const std::size_t nL = btf.lightCount(), nV = btf.viewCount(), count = nL * nV;
    try {
        tbb::parallel_for(std::size_t(0), count, [&](std::size_t i) {
            const std::size_t light = i / nV, view = i % nV;
            const std::vector<unsigned char> bytes =
                encode(btf, view, light, format, jpegQuality, folder);
            const fs::path file =
                tmp / ubo2003MemberName(int(i), btf.lights()[light], btf.views()[view], format);
            std::ofstream out(file, std::ios::binary);
            out.write(reinterpret_cast<const char*>(bytes.data()), std::streamsize(bytes.size()));
            if (!out) fail(folder, "cannot write " + file.string());
        });
    } catch (...) {
        fs::remove_all(tmp, ec);
        throw;
    }
    fs::rename(tmp, folder, ec);
    if (ec) {
        std::error_code ignored;
        fs::remove_all(tmp, ignored);
        fail(folder, "cannot rename " + tmp.string() + ": " + ec.message());
    }
}

}  // namespace osgBTF
