// osgBTF: sizes that files claim, checked before anything sized from them is allocated.
#pragma once

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <string>
#include <vector>

namespace osgBTF {

/** The product of sizes read from a file, saturating at UINT64_MAX instead of wrapping around, so
 *  that absurd header values reach checkMemory (core/MeasuredBtf.h) as absurd rather than as small
 *  numbers. */
std::uint64_t saturatedProduct(std::initializer_list<std::uint64_t> factors);

/** What the headers of one part of an OpenEXR file claim. */
struct ExrPartSize {
    std::int64_t width = 0, height = 0;  ///< of the data window
    int channels = 0;
    std::int64_t chunks = 0;  ///< entries of the part's chunk offset table
    /** Scanlines per chunk (1 uncompressed, RLE and ZIPS; 16 ZIP and PXR24; 32 PIZ and B44; 256
     *  DWAB), for tiled parts 0: the C++ reader's line buffers hold this many lines of the data
     *  window's width, whatever its height. */
    int linesPerChunk = 0;
};

/** Reads the headers of an OpenEXR file, and nothing else, through OpenEXR's C library: its C++
 *  reader allocates (and zeroes) every part's chunk offset table, 8 bytes per chunk counted from
 *  the data window, as it opens a file, before a caller could look at the data window. Throws
 *  Error "PATH: OpenEXR: ..." for unreadable headers, "PATH: OpenEXR header: attribute 'A' (TYPE)
 *  claims N bytes but M remain in the file ..." for an attribute the C++ reader would allocate
 *  from that claim, "PATH: OpenEXR header: attribute 'A' (TYPE) gives its size as N bytes, but a
 *  value of that type takes M (corrupt file)" for a fixed-size type whose size field disagrees
 *  (the C and C++ readers then read different headers), and "PATH: the headers announce N chunks,
 *  whose offset table alone takes ..., but the file holds only B bytes ..." when the tables
 *  could not be in the file. Callers then check exrReadBytes with checkMemory before opening the
 *  file with the C++ API. */
std::vector<ExrPartSize> readExrPartSizes(const std::string& path);
/** The same for an OpenEXR file in memory (e.g. a zip member); messages start with `name`. */
std::vector<ExrPartSize> readExrPartSizes(const std::string& name, const void* bytes,
                                          std::size_t size);

/** Bytes that reading a part into `copies` float buffers needs, with OpenEXR's own bookkeeping
 *  (about 24 bytes per scanline and 8 per chunk) and its line buffers (a compressed and an
 *  uncompressed one of linesPerChunk lines of the full width: a data window 3 million pixels wide
 *  and 1 high takes 400 MB in them under ZIP); saturates instead of wrapping around. */
std::uint64_t exrReadBytes(const ExrPartSize& part, int copies = 1);

}  // namespace osgBTF
