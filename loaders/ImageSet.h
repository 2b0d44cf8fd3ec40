// osgBTF: a measured BTF stored as one image per (view, light) pair in a zip archive or a folder,
// what the UBO2003 reader (names carrying the directions) and the RTI reader (a light-position
// file naming the images) share: listing the entries, bounded reads, and decoding them in
// parallel into a MeasuredBtf.
#pragma once

#include <cstdint>
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
    friend MeasuredBtf decodeImageSet(const ImageSetSource&, const std::vector<ImageSetEntry>&,
                                      const DirectionSet&, const DirectionSet&, const LoadOptions&,
                                      LoadOptions::DecodeCurve);
    std::string _path;
    std::unique_ptr<Impl> _impl;
};

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
