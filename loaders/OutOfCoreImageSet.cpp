#include "loaders/OutOfCoreImageSet.h"

#include <fcntl.h>
#include <unistd.h>
#include <algorithm>
#include <cerrno>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <numeric>

#include "core/Error.h"
#include "core/SizeGuard.h"

namespace osgBTF {

std::uint64_t OutOfCoreImageSet::diskBytesNeeded(int width, int height, std::size_t images,
                                                 bool rawBytes) {
    return saturatedProduct(
        {std::uint64_t(width), std::uint64_t(height), images, 3, std::uint64_t(rawBytes ? 1 : 4)});
}

std::uint64_t OutOfCoreImageSet::diskBytes() const {
    return diskBytesNeeded(_width, _height, imageCount(), _valueBytes == 1);
}

int OutOfCoreImageSet::rowsInBand(int band) const {
    return std::min(_bandRows, _height - band * _bandRows);
}

std::uint64_t OutOfCoreImageSet::offsetOf(std::size_t image, int y) const {
    // Band-major: band b holds every image's rows [b R, b R + rows), image after image.
    const int band = y / _bandRows;
    const std::uint64_t bandStart =
        std::uint64_t(band) * std::uint64_t(_bandRows) * imageCount() * rowBytes();
    return bandStart +
           (std::uint64_t(image) * std::uint64_t(rowsInBand(band)) + std::uint64_t(y % _bandRows)) *
               rowBytes();
}

void OutOfCoreImageSet::toFloats(const unsigned char* from, std::size_t count, float* out) const {
    if (_valueBytes == 1)
        for (std::size_t i = 0; i < count; ++i) out[i] = _table[from[i]];
    else
        std::memcpy(out, from, count * sizeof(float));
}

OutOfCoreImageSet::OutOfCoreImageSet(const ImageSetSource& images,
                                     const std::vector<ImageSetEntry>& entries, DirectionSet views,
                                     DirectionSet lights, LoadOptions::DecodeCurve decode,
                                     const std::string& label) {
    const std::string& path = images.path();
    if (entries.empty()) fail(path, "no images to decode");
    _views = std::move(views);
    _lights = std::move(lights);
    const ImageSetEntry& first = *std::min_element(
        entries.begin(), entries.end(), [&](const ImageSetEntry& a, const ImageSetEntry& b) {
            return std::size_t(a.view) * _lights.size() + a.light <
                   std::size_t(b.view) * _lights.size() + b.light;
        });
    const ImageSetHeader header = readImageSetHeader(images, first);
    _width = header.width;
    _height = header.height;
    _valueBytes = header.rawBytes ? 1 : 4;
    _table = decodeTable(decode);
    const std::size_t imageTotal = imageCount();
    // A band of every image is ~32 MiB as floats: what a per-texel fit holds per worker.
    _bandRows = int(std::clamp<std::uint64_t>(
        (std::uint64_t(32) << 20) /
            std::max<std::uint64_t>(1, std::uint64_t(_width) * imageTotal * 3 * sizeof(float)),
        1, std::uint64_t(_height)));

    _file = std::make_unique<ScratchFile>(diskBytes(), path, "decoded photos");
    source = path;
    decoding = decodeCurveLabel(decode);

    try {
        decodeEachImage(
            images, entries, decode, label,
            [&](const ImageSetEntry& m, int w, int h) {
                if (w != _width || h != _height)
                    fail(path, "member '" + m.name + "' is " + std::to_string(w) + "x" +
                                   std::to_string(h) + " pixels but '" + first.name + "' is " +
                                   std::to_string(_width) + "x" + std::to_string(_height));
            },
            [&](const ImageSetEntry& m, const DecodedImage& image) {
                if (_valueBytes == 1 && !image.bytes)
                    fail(path, "member '" + m.name + "' is not an 8-bit upright image like '" +
                                   first.name + "' (an out-of-core capture keeps one value type)");
                const std::size_t index =
                    std::size_t(m.view) * _lights.size() + std::size_t(m.light);
                std::vector<unsigned char> band;
                // Top-down rows into bottom-up bands: each band of this image is one write.
                for (int top = 0; top < _height;) {
                    const int y = _height - 1 - top;  // the highest row (bottom-up) still to write
                    const int bandIndex = y / _bandRows, bandFirst = bandIndex * _bandRows;
                    const int rows = y - bandFirst + 1;  // rows bandFirst..y, top-down from y
                    band.resize(std::size_t(rows) * rowBytes());
                    for (int r = 0; r < rows; ++r) {
                        const int fileRow = top + r, by = y - r - bandFirst;
                        unsigned char* to = band.data() + std::size_t(by) * rowBytes();
                        const std::size_t pixel = std::size_t(fileRow) * std::size_t(_width);
                        for (int x = 0; x < _width; ++x)
                            for (int c = 0; c < 3; ++c) {
                                const std::size_t from =
                                    (pixel + std::size_t(x)) * std::size_t(image.channels) +
                                    std::size_t(image.channels == 3 ? c : 0);
                                const std::size_t at = std::size_t(x) * 3 + std::size_t(c);
                                if (_valueBytes == 1)
                                    to[at] = image.bytes[from];
                                else {
                                    const float v = image.bytes ? _table[image.bytes[from]]
                                                                : image.floats[from];
                                    std::memcpy(to + at * 4, &v, 4);
                                }
                            }
                    }
                    _file->write(band.data(), band.size(), offsetOf(index, bandFirst));
                    top += rows;
                }
            });
    } catch (...) {
        _file.reset();
        throw;
    }
}

OutOfCoreImageSet::~OutOfCoreImageSet() = default;

void OutOfCoreImageSet::readImages(std::size_t first, std::size_t count, float* out) const {
    const std::size_t imageValues = texelCount() * 3;
    std::vector<unsigned char> rows;
    for (std::size_t i = 0; i < count; ++i)
        for (int band = 0; band * _bandRows < _height; ++band) {
            const int y = band * _bandRows, n = rowsInBand(band);
            rows.resize(std::size_t(n) * rowBytes());
            readAt(rows.data(), rows.size(), offsetOf(first + i, y));
            toFloats(rows.data(), std::size_t(n) * std::size_t(_width) * 3,
                     out + i * imageValues + std::size_t(y) * std::size_t(_width) * 3);
        }
}

void OutOfCoreImageSet::readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const {
    const std::size_t images = imageCount(), perTexel = images * 3, width = std::size_t(_width);
    std::vector<std::size_t> order(count);
    std::iota(order.begin(), order.end(), std::size_t(0));
    std::sort(order.begin(), order.end(),
              [&](std::size_t a, std::size_t b) { return texels[a] < texels[b]; });
    std::vector<unsigned char> rows;
    for (std::size_t begin = 0; begin < count;) {
        const int band = int(texels[order[begin]] / width) / _bandRows;
        std::size_t end = begin;
        while (end < count && int(texels[order[end]] / width) / _bandRows == band) ++end;
        const int yFirst = int(texels[order[begin]] / width);
        const int yLast = int(texels[order[end - 1]] / width);
        const std::size_t spanTexels = std::size_t(yLast - yFirst + 1) * width;
        if ((end - begin) * 16 >= spanTexels) {
            // Dense: the rows they span, one read per image.
            const std::uint64_t spanBytes = std::uint64_t(yLast - yFirst + 1) * rowBytes();
            rows.resize(spanBytes);
            for (std::size_t i = 0; i < images; ++i) {
                readAt(rows.data(), spanBytes, offsetOf(i, yFirst));
                for (std::size_t k = begin; k < end; ++k) {
                    const std::size_t t = texels[order[k]] - std::size_t(yFirst) * width;
                    toFloats(rows.data() + t * 3 * std::size_t(_valueBytes), 3,
                             out + order[k] * perTexel + i * 3);
                }
            }
        } else {
            // Sparse (a random subsample): each texel's values, a small read per image.
            unsigned char value[12];
            for (std::size_t k = begin; k < end; ++k) {
                const std::size_t texel = texels[order[k]];
                const int y = int(texel / width);
                const std::uint64_t x = texel % width;
                for (std::size_t i = 0; i < images; ++i) {
                    readAt(value, 3 * std::uint64_t(_valueBytes),
                           offsetOf(i, y) + x * 3 * std::uint64_t(_valueBytes));
                    toFloats(value, 3, out + order[k] * perTexel + i * 3);
                }
            }
        }
        begin = end;
    }
}

}  // namespace osgBTF
