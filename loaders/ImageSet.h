// osgBTF: a measured BTF stored as one image per (view, light) pair in a zip archive or a folder,
// what the UBO2003 reader (names carrying the directions) and the RTI reader (a light-position
// file naming the images) share: listing the entries, bounded reads, and decoding them in
// parallel into a MeasuredBtf.
#pragma once

#include <array>
#include <cstdint>
#include <functional>
#include <memory>
#include <string>
#include <utility>
#include <vector>

#include "core/Directions.h"
#include "core/MeasuredBtf.h"
#include "loaders/LoadOptions.h"

namespace osgBTF {

/** One image of a set and the (view, light) slot it fills. */
struct ImageSetEntry {
    std::string name;  ///< path inside the archive or relative to the folder
    std::uint64_t zipIndex = 0;
    std::string extension;  ///< lower case, without the dot: jpg, jpeg, png, tif, hdr, exr...
    int view = -1, light = -1;
};

/** One decoded image as stored in its file: rows top-down, `channels` (1 to 3; 1 is gray) values
 *  per pixel. 8-bit images without an EXIF rotation keep their raw values in `bytes` (the decode
 *  curve not applied: decodeTable gives it); every other image is in `floats`, through the curve
 *  and turned upright. Points into the decoder's scratch: valid during the call that gets it. */
struct DecodedImage {
    int width = 0, height = 0, channels = 0;
    const unsigned char* bytes = nullptr;
    const float* floats = nullptr;
};

/** What an image's header says, read without decoding its pixels. */
struct ImageSetHeader {
    int width = 0, height = 0;  ///< upright (EXIF orientation applied)
    /** 8-bit without an EXIF rotation: decodeEachImage gives its raw bytes. */
    bool rawBytes = false;
};
/** The files of a zip archive or of a folder (searched recursively), without what archivers add
 *  (`__MACOSX/`, `._*`, folder entries). Reading is serial (libzip is not thread-safe on one
 *  archive). Throws Error naming the path when it cannot be opened or listed. */
class ImageSetSource {
public:
    explicit ImageSetSource(const std::string& path);
    ~ImageSetSource();
    ImageSetSource(const ImageSetSource&) = delete;
    ImageSetSource& operator=(const ImageSetSource&) = delete;

    const std::string& path() const { return _path; }
    /** Every entry name (sorted for a folder, archive order for a zip) with its zip index. */
    const std::vector<std::pair<std::string, std::uint64_t>>& names() const;
    /** The entry's bytes; `most` bounds what it may claim (0: no bound but the memory limit),
     *  checked before anything is allocated for it. */
    std::vector<unsigned char> read(const ImageSetEntry& entry, std::uint64_t most = 0) const;

private:
    class Impl;
    friend void decodeEachImage(
        const ImageSetSource&, const std::vector<ImageSetEntry>&, LoadOptions::DecodeCurve,
        const std::string&, const std::function<void(const ImageSetEntry&, int, int)>&,
        const std::function<void(const ImageSetEntry&, const DecodedImage&)>&);
    friend ImageSetHeader readImageSetHeader(const ImageSetSource&, const ImageSetEntry&);
    friend MeasuredBtf decodeImageSet(const ImageSetSource&, const std::vector<ImageSetEntry>&,
                                      const DirectionSet&, const DirectionSet&, const LoadOptions&,
                                      LoadOptions::DecodeCurve);
    std::string _path;
    std::unique_ptr<Impl> _impl;
};

/** Reads the header of `entry` (its file's bytes are read, its pixels not decoded). Throws Error
 *  naming the source and the entry for what is not a decodable image. */
ImageSetHeader readImageSetHeader(const ImageSetSource& source, const ImageSetEntry& entry);

/** The linear value decodeImageSet stores for each 8-bit code under `decode`. */
std::array<float, 256> decodeTable(LoadOptions::DecodeCurve decode);

/** Decodes `entries` in parallel, one image per worker at a time (memory: a few decoded images
 *  whatever their number), with a progress bar under `label`. `checkSize(entry, w, h)` sees each
 *  image's upright size before its pixels are decoded (it throws to refuse one); `store` gets each
 *  decoded image, from the decoding thread (several at once, distinct entries). Errors name the
 *  source's path and the entry, as decodeImageSet's. */
void decodeEachImage(const ImageSetSource& source, const std::vector<ImageSetEntry>& entries,
                     LoadOptions::DecodeCurve decode, const std::string& label,
                     const std::function<void(const ImageSetEntry&, int, int)>& checkSize,
                     const std::function<void(const ImageSetEntry&, const DecodedImage&)>& store);

/** `text` with ASCII letters in lower case (file names and extensions). */
std::string asciiLower(std::string text);

/** The file name of an entry path ('/' or '\\' separated). */
std::string imageSetBasename(const std::string& entryPath);

/** Decodes `entries` (every (view, light) slot exactly once: the callers check that and name what
 *  is missing or doubled) into a MeasuredBtf of `views` x `lights`, 8/16-bit values through
 *  `decode`. The first slot's image decides the size, checked against the memory limit before
 *  its pixels are decoded; every other image must have that size ("entry 'B' is WxH pixels but
 *  'A' is wxh"). Rows are flipped bottom-up; EXIF orientations are applied. Decodes in parallel
 *  (TBB) with a progress bar. Errors name the source's path and the entry. */
MeasuredBtf decodeImageSet(const ImageSetSource& source, const std::vector<ImageSetEntry>& entries,
                           const DirectionSet& views, const DirectionSet& lights,
                           const LoadOptions& options, LoadOptions::DecodeCurve decode);

}  // namespace osgBTF
