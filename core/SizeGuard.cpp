#include "core/SizeGuard.h"

#include <algorithm>
#include <cctype>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <limits>
#include <map>
#include <set>
#include <string>

#include <OpenEXR/openexr.h>

#include "core/Error.h"
#include "core/MeasuredBtf.h"

namespace osgBTF {

namespace fs = std::filesystem;

std::uint64_t saturatedProduct(std::initializer_list<std::uint64_t> factors) {
    std::uint64_t product = 1;
    for (const std::uint64_t f : factors) {
        if (f == 0) return 0;
        if (__builtin_mul_overflow(product, f, &product)) product = UINT64_MAX;
    }
    return product;
}

namespace {

/** The OpenEXR C library reports details through a callback (by default, to stderr). */
thread_local std::string exrCoreMessage;

void keepExrCoreMessage(exr_const_context_t, exr_result_t, const char* message) {
    exrCoreMessage = message ? message : "";
}

struct MemoryStream {
    const unsigned char* bytes;
    std::uint64_t size;
};

std::int64_t readMemory(exr_const_context_t, void* user, void* buffer, std::uint64_t size,
                        std::uint64_t offset, exr_stream_error_func_ptr_t) {
    const auto* stream = static_cast<const MemoryStream*>(user);
    if (offset >= stream->size) return 0;
    const std::uint64_t n = std::min(size, stream->size - offset);
    std::memcpy(buffer, stream->bytes + offset, n);
    return std::int64_t(n);
}

std::int64_t memorySize(exr_const_context_t, void* user) {
    return std::int64_t(static_cast<const MemoryStream*>(user)->size);
}

/** Bytes that OpenEXR 3.1's C++ reader takes for a value of one of these types, whatever the
 *  attribute's size field says (it reads the type's fields); 0: another type. */
std::uint64_t fixedExrValueBytes(const std::string& type) {
    static const std::pair<const char*, std::uint64_t> fixed[] = {{"box2i", 16},
                                                                  {"box2f", 16},
                                                                  {"int", 4},
                                                                  {"float", 4},
                                                                  {"double", 8},
                                                                  {"v2i", 8},
                                                                  {"v2f", 8},
                                                                  {"v2d", 16},
                                                                  {"v3i", 12},
                                                                  {"v3f", 12},
                                                                  {"v3d", 24},
                                                                  {"m33f", 36},
                                                                  {"m33d", 72},
                                                                  {"m44f", 64},
                                                                  {"m44d", 128},
                                                                  {"compression", 1},
                                                                  {"lineOrder", 1},
                                                                  {"envmap", 1},
                                                                  {"deepImageState", 1},
                                                                  {"tiledesc", 9},
                                                                  {"chromaticities", 32},
                                                                  {"keycode", 28},
                                                                  {"timecode", 8},
                                                                  {"rational", 8}};
    for (const auto& [name, bytes] : fixed)
        if (type == name) return bytes;
    return 0;
}

/** OpenEXR's C++ reader sizes some attribute values from the file before reading them: a string
 *  or an unknown type from the size field (a 3 KB file claiming a 1.8 GB string is allocated and
 *  zeroed: seconds and 1 GB of RSS, fuzz/regression/fitted_material/), a preview image from its
 *  width and height. OpenEXR's C library accepts such headers. Walks every header in `head` (the
 *  file's first bytes) as the C++ reader does (types of fixed size and channel lists by their
 *  fields, not by their size field, which it ignores for them) and refuses a claim beyond the
 *  bytes that the file (`fileBytes`) has left. What it cannot walk (a header beyond `head`, a
 *  name without its terminator) is left to OpenEXR's own checks. */
void checkExrAttributeSizes(const std::string& name, const unsigned char* head,
                            std::uint64_t headBytes, std::uint64_t fileBytes) {
    if (headBytes < 8) return;
    // The version field's flags (OpenEXR file layout): bit 12 multi-part. Names may take 255
    // bytes: OpenEXR 3.1's C++ reader accepts those whether or not the long-names flag is set.
    const bool multiPart = head[5] & 0x10;
    std::uint64_t at = 8;
    const auto readName = [&](std::string& text) {
        text.clear();
        while (at < headBytes && text.size() <= 255) {
            const char c = char(head[at++]);
            if (c == 0) return true;
            text += c;
        }
        return false;
    };
    const auto readInt = [&](std::int64_t& value) {
        if (headBytes - at < 4) return false;
        std::int32_t v;
        std::memcpy(&v, head + at, 4);  // little-endian, as every platform osgBTF builds on
        at += 4;
        value = v;
        return true;
    };
    std::string attribute, type;
    // Names from a damaged file can hold any byte: control bytes are written as \xNN.
    const auto printable = [](const std::string& text) {
        std::string out;
        for (const char c : text) {
            if (std::isprint(static_cast<unsigned char>(c))) {
                out += c;
            } else {
                static const char digits[] = "0123456789abcdef";
                out += "\\x";
                out += digits[static_cast<unsigned char>(c) >> 4];
                out += digits[static_cast<unsigned char>(c) & 15];
            }
        }
        return out;
    };
    const auto check = [&](std::int64_t claim, const char* what) {
        if (claim < 0 || std::uint64_t(claim) > fileBytes - at)
            fail(name, "OpenEXR header: attribute '" + printable(attribute) + "' (" +
                           printable(type) + ") claims " + std::to_string(claim) + " bytes" + what +
                           " but " + std::to_string(fileBytes - at) +
                           " remain in the file (truncated or corrupt file)");
    };
    // What sizes a part, where the C++ reader and OpenEXR's C library must agree: the C++ reader
    // starts from defaults (ZIP, a 64 x 64 window) that a missing attribute leaves in place, the
    // C library from its own (fuzz/regression/coordinate_map/), and of two attributes of one name
    // they keep different ones. A header without them, or with one twice, is refused.
    const std::map<std::string, std::string> required = {
        {"channels", "chlist"}, {"compression", "compression"}, {"dataWindow", "box2i"}};
    std::set<std::string> names;
    for (;;) {
        for (;;) {
            std::int64_t size = 0;
            if (!readName(attribute)) return;
            if (attribute.empty()) {  // the end of this header
                for (const auto& [needed, neededType] : required)
                    if (!names.count(needed))
                        fail(name, "OpenEXR header: no '" + needed + "' attribute (" + neededType +
                                       "), which every part has (corrupt file)");
                names.clear();
                break;
            }
            if (!names.insert(attribute).second)
                fail(name, "OpenEXR header: attribute '" + printable(attribute) +
                               "' appears twice (corrupt file)");
            if (!readName(type) || !readInt(size)) return;
            if (const std::uint64_t bytes = fixedExrValueBytes(type)) {
                // The C++ reader reads `bytes` and goes on from there; OpenEXR's C library calls
                // the attribute invalid and reads on differently. The two see different headers
                // (e.g. a ZIP window 3 million pixels wide that the size guard, reading through the
                // C library, never saw: fuzz/regression/coordinate_map/), so neither is trusted.
                if (size != std::int64_t(bytes))
                    fail(name, "OpenEXR header: attribute '" + printable(attribute) + "' (" +
                                   printable(type) + ") gives its size as " + std::to_string(size) +
                                   " bytes, but a value of that type takes " +
                                   std::to_string(bytes) + " (corrupt file)");
                at += bytes;
            } else if (type == "chlist") {
                std::string channel;
                while (readName(channel) && !channel.empty()) at += 16;
            } else if (type == "preview") {
                std::int64_t width = 0, height = 0;
                if (!readInt(width) || !readInt(height)) return;
                // Up to (2^32 - 1)^2 pixels of 4 bytes: the count is bounded before it is scaled.
                const std::uint64_t pixels =
                    std::uint64_t(std::uint32_t(width)) * std::uint32_t(height);
                const std::uint64_t most =
                    std::uint64_t(std::numeric_limits<std::int64_t>::max()) / 4;
                check(std::int64_t(std::min(pixels, most) * 4), " of preview pixels");
                at += pixels * 4;
            } else if (type == "stringvector") {
                check(size, "");
                for (const std::uint64_t end = at + std::uint64_t(size); at < end;) {
                    std::int64_t length = 0;
                    if (!readInt(length)) return;
                    check(length, " for one string");
                    at += std::uint64_t(length);
                }
            } else {  // string, floatvector, idmanifest, unknown types: sized by the field
                check(size, "");
                at += std::uint64_t(size);
            }
            if (at > headBytes) return;
        }
        // Multi-part: another header follows unless an empty one ends the list.
        if (!multiPart || at >= headBytes || head[at] == 0) return;
    }
}

/** The headers through an initialised context; `name` starts every message. */
std::vector<ExrPartSize> exrPartSizes(const std::string& name, exr_context_initializer_t init,
                                      const std::string& filename, std::uint64_t fileBytes) {
    init.error_handler_fn = keepExrCoreMessage;
    exr_context_t context = nullptr;
    exrCoreMessage.clear();
    struct Finish {
        exr_context_t* context;
        ~Finish() {
            if (*context) exr_finish(context);
        }
    } finish{&context};
    auto check = [&](exr_result_t result) {
        if (result == EXR_ERR_SUCCESS) return;
        fail(name, "OpenEXR: " + (exrCoreMessage.empty()
                                      ? std::string(exr_get_default_error_message(result))
                                      : exrCoreMessage));
    };
    check(exr_start_read(&context, filename.c_str(), &init));
    int parts = 0;
    check(exr_get_count(context, &parts));
    std::vector<ExrPartSize> sizes;
    std::uint64_t chunks = 0;
    for (int part = 0; part < parts; ++part) {
        ExrPartSize size;
        exr_attr_box2i_t window;
        check(exr_get_data_window(context, part, &window));
        size.width = std::int64_t(window.max.x) - window.min.x + 1;
        size.height = std::int64_t(window.max.y) - window.min.y + 1;
        const exr_attr_chlist_t* channels = nullptr;
        // Deep parts have no channel list the C++ reader would fill; it refuses them later.
        if (exr_get_channels(context, part, &channels) == EXR_ERR_SUCCESS && channels)
            size.channels = channels->num_channels;
        std::int32_t count = 0;
        check(exr_get_chunk_count(context, part, &count));
        size.chunks = count;
        chunks += std::uint64_t(std::max(count, 0));
        exr_storage_t storage = EXR_STORAGE_SCANLINE;
        std::int32_t lines = 0;
        if (exr_get_storage(context, part, &storage) == EXR_ERR_SUCCESS &&
            (storage == EXR_STORAGE_SCANLINE) &&
            exr_get_scanlines_per_chunk(context, part, &lines) == EXR_ERR_SUCCESS)
            size.linesPerChunk = std::max(lines, 0);
        sizes.push_back(size);
    }
    if (chunks * 8 > fileBytes)
        fail(name, "the headers announce " + std::to_string(chunks) +
                       " chunks, whose offset table alone takes " + formatBytes(chunks * 8) +
                       ", but the file holds only " + std::to_string(fileBytes) +
                       " bytes (truncated or corrupt file)");
    return sizes;
}

}  // namespace

std::vector<ExrPartSize> readExrPartSizes(const std::string& path) {
    std::error_code ec;
    const std::uint64_t fileBytes = fs::file_size(path, ec);
    if (ec) fail(path, "cannot read its size: " + ec.message());
    // The headers' attributes are walked in the first MiB (real headers take a few KB).
    std::vector<unsigned char> head(std::size_t(std::min<std::uint64_t>(fileBytes, 1u << 20)));
    std::ifstream in(path, std::ios::binary);
    in.read(reinterpret_cast<char*>(head.data()), std::streamsize(head.size()));
    checkExrAttributeSizes(path, head.data(), std::uint64_t(in.gcount()), fileBytes);
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    return exrPartSizes(path, init, path, fileBytes);
}

std::vector<ExrPartSize> readExrPartSizes(const std::string& name, const void* bytes,
                                          std::size_t size) {
    MemoryStream stream{static_cast<const unsigned char*>(bytes), size};
    checkExrAttributeSizes(name, stream.bytes, size, size);
    exr_context_initializer_t init = EXR_DEFAULT_CONTEXT_INITIALIZER;
    init.user_data = &stream;
    init.read_fn = readMemory;
    init.size_fn = memorySize;
    return exrPartSizes(name, init, name, size);
}

std::uint64_t exrReadBytes(const ExrPartSize& part, int copies) {
    const std::uint64_t pixels = saturatedProduct(
        {std::uint64_t(std::max<std::int64_t>(part.width, 0)),
         std::uint64_t(std::max<std::int64_t>(part.height, 0)),
         std::uint64_t(std::max(part.channels, 0)), 4, std::uint64_t(std::max(copies, 0))});
    const std::uint64_t lineBuffers =
        saturatedProduct({std::uint64_t(std::max<std::int64_t>(part.width, 0)),
                          std::uint64_t(std::max(part.linesPerChunk, 0)),
                          std::uint64_t(std::max(part.channels, 0)), 4, 2});
    const std::uint64_t bookkeeping =
        saturatedProduct({std::uint64_t(std::max<std::int64_t>(part.height, 0)), 24}) +
        saturatedProduct({std::uint64_t(std::max<std::int64_t>(part.chunks, 0)), 8});
    const std::uint64_t overhead =
        lineBuffers > UINT64_MAX - bookkeeping ? UINT64_MAX : lineBuffers + bookkeeping;
    return pixels > UINT64_MAX - overhead ? UINT64_MAX : pixels + overhead;
}

}  // namespace osgBTF
