#include "loaders/ImageSet.h"

#include <unistd.h>
#include <algorithm>
#include <cctype>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <functional>
#include <sstream>
#include <vector>

#include <Imath/half.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_pipeline.h>
#include <tbb/task_arena.h>
#include <zip.h>

#include "core/Error.h"
#include "core/ImageCodecs.h"
#include "core/Progress.h"
#include "core/SizeGuard.h"

namespace osgBTF {

namespace {

namespace fs = std::filesystem;

/** Entries that archivers add and that never hold BTF data. */
bool isJunk(const std::string& memberPath) {
    if (memberPath.empty() || memberPath.back() == '/' || memberPath.back() == '\\') return true;
    if (memberPath.rfind("__MACOSX/", 0) == 0 || memberPath.find("/__MACOSX/") != std::string::npos)
        return true;
    return imageSetBasename(memberPath).rfind("._", 0) == 0;
}

}  // namespace

std::string asciiLower(std::string text) {
    for (char& c : text) c = char(std::tolower(static_cast<unsigned char>(c)));
    return text;
}

std::string imageSetBasename(const std::string& entryPath) {
    const auto slash = entryPath.find_last_of("/\\");
    return slash == std::string::npos ? entryPath : entryPath.substr(slash + 1);
}

class ImageSetSource::Impl {
public:
    explicit Impl(const std::string& path) : _path(path) {
        std::error_code ec;
        if (fs::is_directory(path, ec))
            listFolder();
        else
            openZip();
    }
    ~Impl() {
        if (_zip) zip_discard(_zip);
    }
    Impl(const Impl&) = delete;
    Impl& operator=(const Impl&) = delete;

    /** Every entry name with its zip index, junk already removed. */
    const std::vector<std::pair<std::string, std::uint64_t>>& names() const { return _names; }

    /** The member's bytes; `most` bounds what a member may claim (0: no bound but the memory
     *  limit), checked before anything is allocated for it. */
    std::vector<unsigned char> read(const ImageSetEntry& member, std::uint64_t most = 0) const {
        return _zip ? readZip(member, most) : readFile(member, most);
    }

private:
    void openZip() {
        int code = 0;
        _zip = zip_open(_path.c_str(), ZIP_RDONLY, &code);
        if (!_zip) {
            zip_error_t error;
            zip_error_init_with_code(&error, code);
            const std::string text = zip_error_strerror(&error);
            zip_error_fini(&error);
            const char* hint = code == ZIP_ER_NOZIP || code == ZIP_ER_INCONS
                                   ? " (a truncated download or not a zip archive?)"
                                   : "";
            fail(_path, "cannot open zip archive: " + text + hint);
        }
        const zip_int64_t count = zip_get_num_entries(_zip, 0);
        for (zip_int64_t i = 0; i < count; ++i) {
            const char* name = zip_get_name(_zip, zip_uint64_t(i), ZIP_FL_ENC_GUESS);
            if (!name)
                fail(_path, "cannot read the name of entry " + std::to_string(i) + ": " +
                                zip_strerror(_zip));
            if (!isJunk(name)) _names.emplace_back(name, zip_uint64_t(i));
        }
    }

    void listFolder() {
        std::error_code ec;
        fs::recursive_directory_iterator it(_path, ec), end;
        if (ec) fail(_path, "cannot list folder: " + ec.message());
        for (; it != end; it.increment(ec)) {
            if (ec) fail(_path, "cannot list folder: " + ec.message());
            if (!it->is_regular_file(ec)) continue;
            const std::string relative = fs::relative(it->path(), _path, ec).generic_string();
            if (!isJunk(relative)) _names.emplace_back(relative, 0);
        }
        if (ec) fail(_path, "cannot list folder: " + ec.message());
        // Directory iteration order is arbitrary; sorting makes "first" errors reproducible.
        std::sort(_names.begin(), _names.end());
    }

    /** Refuses a member size before it is allocated: above `most`, or above the memory limit. */
    void checkSize(const ImageSetEntry& member, std::uint64_t size, std::uint64_t most) const {
        if (most && size > most)
            fail(_path, "member '" + member.name + "' is " + std::to_string(size) +
                            " bytes, more than any encoding of the archive's images needs (at "
                            "most " +
                            std::to_string(most) + " bytes)");
        checkMemory(size,
                    _path + ": member '" + member.name + "' of " + std::to_string(size) + " bytes");
    }

    std::vector<unsigned char> readZip(const ImageSetEntry& member, std::uint64_t most) const {
        zip_stat_t stat;
        zip_stat_init(&stat);
        if (zip_stat_index(_zip, member.zipIndex, 0, &stat) != 0 || !(stat.valid & ZIP_STAT_SIZE))
            fail(_path,
                 "member '" + member.name + "': cannot read its size: " + zip_strerror(_zip));
        // The size is the central directory's claim, not what inflating gives: deflate expands
        // at most 1032:1 (258-byte matches in 2 bits), so a larger claim is a lie (a zip bomb's
        // or a corrupt directory's) and is refused before allocating for it.
        if ((stat.valid & ZIP_STAT_COMP_SIZE) && (stat.valid & ZIP_STAT_COMP_METHOD)) {
            const bool stored = stat.comp_method == ZIP_CM_STORE;
            const bool deflated =
                stat.comp_method == ZIP_CM_DEFLATE || stat.comp_method == ZIP_CM_DEFLATE64;
            const std::uint64_t bound = stored ? stat.comp_size
                                        : stat.comp_size > (UINT64_MAX - 1024) / 1032
                                            ? UINT64_MAX
                                            : stat.comp_size * 1032 + 1024;
            if ((stored || deflated) && stat.size > bound)
                fail(_path, "member '" + member.name + "' claims " + std::to_string(stat.size) +
                                " bytes uncompressed from " + std::to_string(stat.comp_size) +
                                (stored ? " stored bytes"
                                        : " deflated bytes, more than deflate can expand "
                                          "(1032:1)") +
                                ": a corrupt archive or a zip bomb");
        }
        checkSize(member, stat.size, most);
        zip_file_t* file = zip_fopen_index(_zip, member.zipIndex, 0);
        if (!file) fail(_path, "member '" + member.name + "': " + zip_strerror(_zip));
        std::vector<unsigned char> bytes(stat.size);
        zip_uint64_t done = 0;
        while (done < stat.size) {
            const zip_int64_t n = zip_fread(file, bytes.data() + done, stat.size - done);
            if (n <= 0) {
                const std::string text = n < 0 ? zip_file_strerror(file) : "unexpected end of data";
                zip_fclose(file);
                fail(_path, "member '" + member.name + "': " + text);
            }
            done += zip_uint64_t(n);
        }
        // zip_fclose reports a CRC mismatch only now, after the last byte was read.
        const int closeError = zip_fclose(file);
        if (closeError != 0) {
            zip_error_t error;
            zip_error_init_with_code(&error, closeError);
            const std::string text = zip_error_strerror(&error);
            zip_error_fini(&error);
            fail(_path, "member '" + member.name + "': " + text);
        }
        return bytes;
    }

    std::vector<unsigned char> readFile(const ImageSetEntry& member, std::uint64_t most) const {
        const fs::path file = fs::path(_path) / member.name;
        std::error_code ec;
        const std::uint64_t size = fs::file_size(file, ec);
        if (!ec) checkSize(member, size, most);
        std::ifstream in(file, std::ios::binary);
        if (!in) fail(file.string(), std::string("cannot open: ") + std::strerror(errno));
        std::vector<unsigned char> bytes((std::istreambuf_iterator<char>(in)),
                                         std::istreambuf_iterator<char>());
        if (in.bad()) fail(file.string(), "read error");
        return bytes;
    }

    std::string _path;
    zip_t* _zip = nullptr;
    std::vector<std::pair<std::string, std::uint64_t>> _names;
};

ImageSetSource::ImageSetSource(const std::string& path)
    : _path(path), _impl(std::make_unique<Impl>(path)) {}

ImageSetSource::~ImageSetSource() = default;

const std::vector<std::pair<std::string, std::uint64_t>>& ImageSetSource::names() const {
    return _impl->names();
}

std::vector<unsigned char> ImageSetSource::read(const ImageSetEntry& entry,
                                                std::uint64_t most) const {
    return _impl->read(entry, most);
}

namespace {

/** Integer image values to linear radiance. */
class Curve {
public:
    explicit Curve(LoadOptions::DecodeCurve curve) : _curve(curve) {
        for (int i = 0; i < 256; ++i) {
            _lut8[i] = apply(float(i) / 255.0f);
            _lut8Half[i] = Imath::half(_lut8[i]);
        }
    }
    float byte(unsigned char v) const { return _lut8[v]; }
    Imath::half byteHalf(unsigned char v) const { return _lut8Half[v]; }
    float apply(float v) const {
        switch (_curve) {
            case LoadOptions::DecodeCurve::Srgb:
                return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
            case LoadOptions::DecodeCurve::Gamma22:
                return std::pow(std::max(v, 0.0f), 2.2f);
            case LoadOptions::DecodeCurve::Auto:  // resolved by the reader; linear if not
            case LoadOptions::DecodeCurve::Linear:
                break;
        }
        return v;
    }

private:
    LoadOptions::DecodeCurve _curve;
    float _lut8[256];
    Imath::half _lut8Half[256];
};

/** Where one decoded image goes: width*height*3 values, rows bottom-up, in either storage. */
struct Target {
    float* f = nullptr;
    Imath::half* h = nullptr;
};

struct DecodeScratch {
    std::vector<unsigned char> bytes8;
    std::vector<float> floats;
    std::vector<float> image;  ///< the first image, decoded before the BTF exists
};

/** Converts rows of decoded pixels into target, flipping them to bottom-up; src holds `channels`
 *  values per pixel (1 = gray, replicated). */
template <typename In, typename Convert>
void storeRows(const In* src, int width, int height, int channels, Target target, Convert convert) {
    const std::size_t rowValues = std::size_t(width) * 3;
    for (int y = 0; y < height; ++y) {
        const In* in = src + std::size_t(y) * width * channels;
        const std::size_t out = std::size_t(height - 1 - y) * rowValues;
        // RGB rows map value for value; this flat loop is the hot path of every JPEG load.
        if (channels == 3 && target.f) {
            float* dst = target.f + out;
            for (std::size_t i = 0; i < rowValues; ++i) dst[i] = float(convert(in[i]));
        } else if (channels == 3) {
            Imath::half* dst = target.h + out;
            for (std::size_t i = 0; i < rowValues; ++i) dst[i] = Imath::half(convert(in[i]));
        } else if (target.f) {
            float* dst = target.f + out;
            for (int x = 0; x < width; ++x, in += channels, dst += 3)
                for (int c = 0; c < 3; ++c) dst[c] = float(convert(in[channels == 3 ? c : 0]));
        } else {
            Imath::half* dst = target.h + out;
            for (int x = 0; x < width; ++x, in += channels, dst += 3)
                for (int c = 0; c < 3; ++c)
                    dst[c] = Imath::half(convert(in[channels == 3 ? c : 0]));
        }
    }
}

/** The upright image of pixels stored with an EXIF orientation (2..8), done here rather than with
 *  ImageBufAlgo::reorient because OIIO 2.4 swaps orientations 5 and 7. Orientation 5 is what OIIO
 *  reports for Radiance "+X M -Y N" files (ATRIUM_HDR): each stored scanline is an image column. */
std::vector<float> upright(const std::vector<float>& stored, int sw, int sh, int channels,
                           int orientation) {
    const bool swaps = orientation >= 5;
    const int w = swaps ? sh : sw, h = swaps ? sw : sh;
    std::vector<float> out(stored.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            int sx = x, sy = y;
            switch (orientation) {
                case 2:
                    sx = sw - 1 - x;
                    break;
                case 3:
                    sx = sw - 1 - x;
                    sy = sh - 1 - y;
                    break;
                case 4:
                    sy = sh - 1 - y;
                    break;
                case 5:
                    sx = y;
                    sy = x;
                    break;
                case 6:
                    sx = y;
                    sy = sh - 1 - x;
                    break;
                case 7:
                    sx = sw - 1 - y;
                    sy = sh - 1 - x;
                    break;
                case 8:
                    sx = sw - 1 - y;
                    sy = x;
                    break;
                default:
                    break;
            }
            std::copy_n(stored.data() + (std::size_t(sy) * sw + sx) * channels, channels,
                        out.data() + (std::size_t(y) * w + x) * channels);
        }
    return out;
}

/** A JPEG cut short (a download or copy that stopped) ends inside its entropy-coded data, and
 *  libjpeg decodes it anyway, filling the rest with grey and only warning: such a photo would
 *  enter a fit as if measured. A complete one ends with the end-of-image marker FF D9, possibly
 *  followed by zero padding (some cameras and copies pad); anything else is refused. */
void requireJpegEnd(const std::string& archive, const std::string& where,
                    const std::vector<unsigned char>& bytes) {
    std::size_t end = bytes.size();
    while (end > 0 && bytes[end - 1] == 0) --end;
    if (end < 4 || bytes[0] != 0xFF || bytes[1] != 0xD8)
        fail(archive, where + ": not a JPEG (no start-of-image marker)");
    if (bytes[end - 2] != 0xFF || bytes[end - 1] != 0xD9)
        fail(archive, where + ": truncated JPEG (no end-of-image marker)");
}

/** Decodes an image (the bytes of a file) into `scratch`, top-down as stored: 8-bit images
 *  without an EXIF rotation as their raw values (bytes8), others as floats through the curve,
 *  turned upright (floats). `checkSize` receives the upright size and throws when it is wrong,
 *  before pixels are decoded. */
DecodedImage decodePixels(const std::string& archive, const ImageSetEntry& member,
                          const std::vector<unsigned char>& bytes, const Curve& curve,
                          DecodeScratch& scratch, const std::function<void(int, int)>& checkSize) {
    const std::string where = "member '" + member.name + "'";
    // OpenEXR's C++ reader (OpenImageIO's) allocates chunk offset tables sized from the header as
    // it opens a file; the headers are checked against the member's size first.
    if (member.extension == "exr")
        readExrPartSizes(archive + ": " + where, bytes.data(), bytes.size());
    if (member.extension == "jpg" || member.extension == "jpeg")
        requireJpegEnd(archive, where, bytes);
    std::string error;
    const std::unique_ptr<ImageReader> input = imageCodecs().openBytes(
        bytes.data(), bytes.size(), member.extension, imageSetBasename(member.name), error);
    if (!input) fail(archive, where + ": not a decodable image: " + error);
    input->singleThreaded();  // parallelism comes from decoding many images at once
    const ImageHeader& spec = input->header();
    if (spec.channels < 1 || spec.width <= 0 || spec.height <= 0 || spec.depth > 1)
        fail(archive, where + ": unsupported image layout");
    int orientation = spec.orientation;
    if (orientation < 1 || orientation > 8) orientation = 1;
    const bool swapsAxes = orientation >= 5 && orientation <= 8;
    DecodedImage out;
    out.width = swapsAxes ? spec.height : spec.width;
    out.height = swapsAxes ? spec.width : spec.height;
    checkSize(out.width, out.height);

    const int storedW = spec.width, storedH = spec.height;
    out.channels = std::min(spec.channels, 3);
    const std::size_t pixels = std::size_t(storedW) * storedH;
    bool ok;
    if (spec.eightBit && orientation == 1) {
        // Native reads of all channels: OpenImageIO 2.4's converting read allocates a 64 MiB
        // scanline buffer per call, which dominated small-image loads (and crawled under ASan).
        const int fileChannels = spec.channels;
        scratch.bytes8.resize(pixels * fileChannels);
        ok = input->readBytes(scratch.bytes8.data());
        if (ok && fileChannels != out.channels) {
            for (std::size_t p = 0; p < pixels; ++p)
                for (int c = 0; c < out.channels; ++c)
                    scratch.bytes8[p * out.channels + c] = scratch.bytes8[p * fileChannels + c];
            scratch.bytes8.resize(pixels * out.channels);
        }
        out.bytes = scratch.bytes8.data();
    } else {
        scratch.floats.resize(pixels * out.channels);
        ok = input->readFloats(out.channels, scratch.floats.data());
        if (ok && !spec.floating)
            for (float& v : scratch.floats) v = curve.apply(v);
        if (ok && orientation != 1)
            scratch.floats = upright(scratch.floats, storedW, storedH, out.channels, orientation);
        out.floats = scratch.floats.data();
    }
    if (!ok) fail(archive, where + ": corrupt image: " + input->error());
    return out;
}

/** Decodes an image (the bytes of a file) into bottom-up RGB. destination receives the decoded
 *  size and returns where to write; it throws when the size is wrong, before pixels are decoded. */
void decodeImage(const std::string& archive, const ImageSetEntry& member,
                 const std::vector<unsigned char>& bytes, const Curve& curve,
                 DecodeScratch& scratch, const std::function<Target(int, int)>& destination) {
    Target target;
    const DecodedImage image =
        decodePixels(archive, member, bytes, curve, scratch,
                     [&](int width, int height) { target = destination(width, height); });
    if (image.bytes && target.f)
        storeRows(image.bytes, image.width, image.height, image.channels, target,
                  [&](unsigned char v) { return curve.byte(v); });
    else if (image.bytes)
        storeRows(image.bytes, image.width, image.height, image.channels, target,
                  [&](unsigned char v) { return curve.byteHalf(v); });
    else
        storeRows(image.floats, image.width, image.height, image.channels, target,
                  [](float v) { return v; });
}

}  // namespace

MeasuredBtf decodeImageSet(const ImageSetSource& source, const std::vector<ImageSetEntry>& entries,
                           const DirectionSet& views, const DirectionSet& lights,
                           const LoadOptions& options, LoadOptions::DecodeCurve decode) {
    const std::string& path = source.path();
    if (entries.empty()) fail(path, "no images to decode");
    const std::size_t nL = lights.size(), nV = views.size();
    const Curve curve(decode);
    DecodeScratch firstScratch;
    const ImageSetEntry& firstMember = *std::min_element(
        entries.begin(), entries.end(), [&](const ImageSetEntry& a, const ImageSetEntry& b) {
            return std::size_t(a.light) * nV + a.view < std::size_t(b.light) * nV + b.view;
        });
    int width = 0, height = 0;
    decodeImage(
        path, firstMember, source._impl->read(firstMember), curve, firstScratch, [&](int w, int h) {
            width = w;
            height = h;
            // The first header's size decides everything: checked before its pixels
            // are decoded, so an image claiming 100000x100000 pixels allocates nothing.
            std::ostringstream what;
            what << path << ": BTF of " << w << "x" << h << " texels x " << nV << " views x " << nL
                 << " lights";
            checkMemory(MeasuredBtf::bytesNeeded(w, h, nV, nL, options.storage), what.str());
            firstScratch.image.resize(std::size_t(w) * h * 3);
            return Target{firstScratch.image.data(), nullptr};
        });
    // An encoded image of width x height pixels is never larger than twice its raw RGBA float
    // pixels plus 16 MiB of metadata; larger members are refused before they are read, so the
    // members in flight stay bounded by the image size.
    const std::uint64_t mostBytes =
        std::min(saturatedProduct({std::uint64_t(width), std::uint64_t(height), 2 * 16}),
                 UINT64_MAX - (16u << 20)) +
        (16u << 20);

    MeasuredBtf btf(width, height, views, lights, options.storage);
    btf.source = path;
    btf.setImage(firstMember.view, firstMember.light, firstScratch.image.data());

    // Archive order keeps zip reads sequential.
    std::vector<const ImageSetEntry*> order;
    for (const ImageSetEntry& m : entries)
        if (&m != &firstMember) order.push_back(&m);
    std::sort(order.begin(), order.end(), [](const ImageSetEntry* a, const ImageSetEntry* b) {
        return a->zipIndex < b->zipIndex;
    });

    Progress progress(options.progressLabel.empty()
                          ? "loading " + fs::path(path).filename().string()
                          : options.progressLabel,
                      entries.size());
    progress.advance();
    tbb::enumerable_thread_specific<DecodeScratch> scratches;
    struct Job {
        const ImageSetEntry* member;
        std::vector<unsigned char> bytes;
    };
    std::size_t next = 0;
    const std::size_t tokensInFlight = std::size_t(tbb::this_task_arena::max_concurrency()) * 4;
    tbb::parallel_pipeline(
        tokensInFlight,
        tbb::make_filter<void, std::shared_ptr<Job>>(
            tbb::filter_mode::serial_in_order,
            [&](tbb::flow_control& control) -> std::shared_ptr<Job> {
                if (next == order.size()) {
                    control.stop();
                    return nullptr;
                }
                auto job = std::make_shared<Job>();
                job->member = order[next++];
                job->bytes = source._impl->read(*job->member, mostBytes);
                return job;
            }) &
            tbb::make_filter<std::shared_ptr<Job>, void>(
                tbb::filter_mode::parallel, [&](const std::shared_ptr<Job>& job) {
                    const ImageSetEntry& m = *job->member;
                    DecodeScratch& scratch = scratches.local();
                    decodeImage(path, m, job->bytes, curve, scratch, [&](int w, int h) {
                        if (w != width || h != height)
                            fail(path, "member '" + m.name + "' is " + std::to_string(w) + "x" +
                                           std::to_string(h) + " pixels but '" + firstMember.name +
                                           "' is " + std::to_string(width) + "x" +
                                           std::to_string(height));
                        // Straight into the BTF: each image is a disjoint block.
                        const std::size_t at = btf.index(m.view, m.light, 0);
                        return btf.floatData() ? Target{btf.floatData() + at, nullptr}
                                               : Target{nullptr, btf.halfData() + at};
                    });
                    progress.advance();
                }));
    progress.finish();
    btf.decoding = decodeCurveLabel(decode);
    return btf;
}

ImageSetHeader readImageSetHeader(const ImageSetSource& source, const ImageSetEntry& entry) {
    const std::vector<unsigned char> bytes = source._impl->read(entry);
    if (entry.extension == "exr")
        readExrPartSizes(source.path() + ": member '" + entry.name + "'", bytes.data(),
                         bytes.size());
    std::string error;
    const std::unique_ptr<ImageReader> input = imageCodecs().openBytes(
        bytes.data(), bytes.size(), entry.extension, imageSetBasename(entry.name), error);
    if (!input) fail(source.path(), "member '" + entry.name + "': not a decodable image: " + error);
    const ImageHeader& spec = input->header();
    if (spec.channels < 1 || spec.width <= 0 || spec.height <= 0 || spec.depth > 1)
        fail(source.path(), "member '" + entry.name + "': unsupported image layout");
    const int orientation = spec.orientation < 1 || spec.orientation > 8 ? 1 : spec.orientation;
    const bool swapsAxes = orientation >= 5;
    ImageSetHeader header;
    header.width = swapsAxes ? spec.height : spec.width;
    header.height = swapsAxes ? spec.width : spec.height;
    header.rawBytes = spec.eightBit && orientation == 1;
    return header;
}

std::array<float, 256> decodeTable(LoadOptions::DecodeCurve decode) {
    const Curve curve(decode);
    std::array<float, 256> table;
    for (int i = 0; i < 256; ++i) table[std::size_t(i)] = curve.byte((unsigned char)i);
    return table;
}

void decodeEachImage(const ImageSetSource& source, const std::vector<ImageSetEntry>& entries,
                     LoadOptions::DecodeCurve decode, const std::string& label,
                     const std::function<void(const ImageSetEntry&, int, int)>& checkSize,
                     const std::function<void(const ImageSetEntry&, const DecodedImage&)>& store) {
    const std::string& path = source.path();
    const Curve curve(decode);
    std::vector<const ImageSetEntry*> order;
    for (const ImageSetEntry& m : entries) order.push_back(&m);
    std::sort(order.begin(), order.end(), [](const ImageSetEntry* a, const ImageSetEntry* b) {
        return a->zipIndex < b->zipIndex;
    });
    Progress progress(label, entries.size());
    tbb::enumerable_thread_specific<DecodeScratch> scratches;
    struct Job {
        const ImageSetEntry* member;
        std::vector<unsigned char> bytes;
    };
    std::size_t next = 0;
    std::uint64_t mostBytes = 0;  // from the first image's size, as decodeImageSet bounds them
    // One image in flight per worker and one being read: the memory is a few decoded images,
    // whatever the number of photos.
    const std::size_t tokens = std::size_t(tbb::this_task_arena::max_concurrency()) + 1;
    tbb::parallel_pipeline(
        tokens, tbb::make_filter<void, std::shared_ptr<Job>>(
                    tbb::filter_mode::serial_in_order,
                    [&](tbb::flow_control& control) -> std::shared_ptr<Job> {
                        if (next == order.size()) {
                            control.stop();
                            return nullptr;
                        }
                        auto job = std::make_shared<Job>();
                        job->member = order[next++];
                        job->bytes = source._impl->read(*job->member, mostBytes);
                        return job;
                    }) &
                    tbb::make_filter<std::shared_ptr<Job>, void>(
                        tbb::filter_mode::parallel, [&](const std::shared_ptr<Job>& job) {
                            const ImageSetEntry& m = *job->member;
                            DecodeScratch& scratch = scratches.local();
                            const DecodedImage image =
                                decodePixels(path, m, job->bytes, curve, scratch,
                                             [&](int w, int h) { checkSize(m, w, h); });
                            job->bytes = {};
                            store(m, image);
                            progress.advance();
                        }));
    progress.finish();
}

}  // namespace osgBTF
