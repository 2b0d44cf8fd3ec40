// osgBTF: a measured BTF of photos (an RTI capture) too large for memory as floats. Each photo is
// decoded once into a temporary file, as its 8-bit values where it has them (3 bytes a texel and
// image, a quarter of floats), in bands of rows holding every image: a block of texels is then one
// read per image, a few texels a few small reads, and memory holds a band, never the capture.
// What relight does for camera-size captures (it reads its JPEGs in row chunks within a fixed
// budget); here any fit can come back for another pass, so the decoded values stay on disk.
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "core/BtfSource.h"
#include "core/ScratchFile.h"
#include "loaders/ImageSet.h"

namespace osgBTF {

class OutOfCoreImageSet : public BtfSource {
public:
    /** Decodes every entry (each (view, light) slot once, as decodeImageSet) into an unnamed
     *  temporary file in outOfCoreFolder(), with a progress bar. The first entry's header decides
     *  the size and the value type (raw bytes for 8-bit photos without an EXIF rotation, else
     *  floats); every other image must match ("member 'B' is WxH pixels but 'A' is wxh"). Throws
     *  Error naming the folder when it has not the room ("needs N of disk ..., M free ..."). */
    OutOfCoreImageSet(const ImageSetSource& source, const std::vector<ImageSetEntry>& entries,
                      DirectionSet views, DirectionSet lights, LoadOptions::DecodeCurve decode,
                      const std::string& label);
    ~OutOfCoreImageSet() override;
    OutOfCoreImageSet(const OutOfCoreImageSet&) = delete;
    OutOfCoreImageSet& operator=(const OutOfCoreImageSet&) = delete;

    /** Bytes the decoded values take on disk. */
    static std::uint64_t diskBytesNeeded(int width, int height, std::size_t images, bool rawBytes);
    std::uint64_t diskBytes() const;
    /** Rows per band: a band of every image is ~32 MiB as floats. */
    int bandRows() const { return _bandRows; }

    void readImages(std::size_t first, std::size_t count, float* out) const override;
    void readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const override;
    /** One band of rows: a read per image. */
    std::size_t abrdfBlockTexels() const override {
        return std::size_t(_bandRows) * std::size_t(_width);
    }
    std::size_t imageBlock() const override { return 1; }
    bool inMemory() const override { return false; }
    std::uint64_t residentBytes() const override { return 0; }

private:
    std::uint64_t rowBytes() const { return std::uint64_t(_width) * 3 * _valueBytes; }
    int rowsInBand(int band) const;
    /** Where row y (bottom-up) of image i starts in the file. */
    std::uint64_t offsetOf(std::size_t image, int y) const;
    void readAt(void* to, std::uint64_t bytes, std::uint64_t offset) const {
        _file->read(to, bytes, offset);
    }
    /** `count` stored values at `from` as floats. */
    void toFloats(const unsigned char* from, std::size_t count, float* out) const;

    std::unique_ptr<ScratchFile> _file;
    int _bandRows = 1;
    int _valueBytes = 1;  ///< 1: raw 8-bit values through _table; 4: floats
    std::array<float, 256> _table{};
};

/** Where out-of-core captures keep their decoded values: scratchFolder() (core/ScratchFile.h). */
inline std::string outOfCoreFolder() {
    return scratchFolder();
}

}  // namespace osgBTF
