#include "core/SizeGuard.h"

#include <algorithm>
#include <cstring>
#include <filesystem>
#include <fstream>

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

/** OpenEXR's C++ reader sizes an attribute's value from the size the file gives, before reading
 *  it: a string attribute claiming 1.8 GB is allocated and zeroed (seconds, and 1 GB of RSS, for
 *  a 3 KB file: fuzz/regression/fitted_material/), and OpenEXR's C library accepts such headers.
 *  Walks the attributes of every header in `head` (the file's first bytes) and refuses one that
 *  claims more bytes than the file (`fileBytes`) has after it. Anything it cannot walk (a header
 *  beyond `head`, a name without its terminator) is left to OpenEXR's own checks. */
void checkExrAttributeSizes(const std::string& name, const unsigned char* head,
                            std::uint64_t headBytes, std::uint64_t fileBytes) {
    if (headBytes < 8) return;
    // The version field's flags (OpenEXR file layout): bit 10 long names, bit 12 multi-part.
    const bool longNames = head[5] & 0x04, multiPart = head[5] & 0x10;
    const std::size_t maxName = longNames ? 255 : 31;
    std::uint64_t at = 8;
    const auto readName = [&](std::string& text) {
        text.clear();
        while (at < headBytes && text.size() <= maxName) {
            const char c = char(head[at++]);
            if (c == 0) return true;
            text += c;
        }
        return false;
    };
    for (;;) {
        std::string attribute, type;
        for (;;) {
            if (!readName(attribute)) return;
            if (attribute.empty()) break;  // the end of this header
            if (!readName(type) || headBytes - at < 4) return;
            std::int32_t size;
            std::memcpy(&size, head + at, 4);  // little-endian, as every platform osgBTF builds on
            at += 4;
            if (size < 0 || std::uint64_t(size) > fileBytes - at)
                fail(name, "OpenEXR header: attribute '" + attribute + "' (" + type + ") claims " +
                               std::to_string(size) + " bytes but " +
                               std::to_string(fileBytes - at) +
                               " remain in the file (truncated or corrupt file)");
            at += std::uint64_t(size);
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
    const std::uint64_t bookkeeping =
        saturatedProduct({std::uint64_t(std::max<std::int64_t>(part.height, 0)), 24}) +
        saturatedProduct({std::uint64_t(std::max<std::int64_t>(part.chunks, 0)), 8});
    return pixels > UINT64_MAX - bookkeeping ? UINT64_MAX : pixels + bookkeeping;
}

}  // namespace osgBTF
