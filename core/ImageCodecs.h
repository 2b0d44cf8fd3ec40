// osgBTF: image files other than OpenEXR (PNG, JPEG, Radiance HDR, TIFF, ...) through OpenImageIO,
// which lives in a module of its own: libosgBTFImageCodecs.so, next to libosgBTF, loaded on first
// use. OpenImageIO's closure (~260 shared libraries: GDAL, OpenVDB, FFmpeg, ...) cost every
// program that linked it 0.35 s and 130 MiB of resident memory at start, the bulk of what the
// `btf` tool and a viewer spent before their first line of work, and almost none of them reads an
// 8-bit image. EXR files do not come here: OpenEXR is read and written directly (FloatImage.h).
//
// The module is a plain adapter: it links OpenImageIO and nothing of osgBTF, reports problems as
// text (the callers turn them into Errors that name the file) and keeps OpenImageIO's types out of
// this interface. Rows are top-down, as stored in files.
#pragma once

#include <cstddef>
#include <memory>
#include <string>
#include <vector>

namespace osgBTF {

struct FloatImage;

/** What an image file holds, before its pixels are read. */
struct ImageHeader {
    int width = 0, height = 0, channels = 0, depth = 1;
    bool deep = false;
    bool eightBit = false;  ///< stored as unsigned 8-bit values
    bool floating = false;  ///< stored as half or float values
    int orientation = 1;    ///< EXIF orientation, 1 (as stored) to 8
    std::vector<std::string> channelNames;
};

/** An opened image (one subimage of a file). Colour values come as stored: never premultiplied
 *  by alpha, no colour-space conversion. */
class ImageReader {
public:
    virtual ~ImageReader() = default;
    virtual const ImageHeader& header() const = 0;
    /** Decodes on the calling thread only (the callers decode many images in parallel). */
    virtual void singleThreaded() = 0;
    /** An 8-bit image's stored bytes, all channels, rows top-down, as stored (orientation
     *  ignored). False on a decoding error (see error()). */
    virtual bool readBytes(unsigned char* destination) = 0;
    /** The first `channels` channels converted to float (8-bit and 16-bit values scaled to
     *  [0,1]), rows top-down, as stored. */
    virtual bool readFloats(int channels, float* destination) = 0;
    /** The decoder's words for the last problem (may be empty). */
    virtual std::string error() = 0;
};

/** The module's entry points. */
class ImageCodecs {
public:
    virtual ~ImageCodecs() = default;

    /** Opens `path`'s image number `subimage`, or returns null and sets `error`
     *  (possibly empty, when the decoder gives no reason). */
    virtual std::unique_ptr<ImageReader> openFile(const std::string& path, int subimage,
                                                  std::string& error) const = 0;

    /** Opens the bytes of an image file in memory; `extension` (lower case, e.g. "png") picks
     *  the decoder. Formats whose decoder cannot read from memory go through a temporary file,
     *  removed with the reader. Messages (error here and the reader's) name the image
     *  `displayName`, are never empty and fit on one line. */
    virtual std::unique_ptr<ImageReader> openBytes(const unsigned char* bytes, std::size_t size,
                                                   const std::string& extension,
                                                   const std::string& displayName,
                                                   std::string& error) const = 0;

    /** Writes `pixels` (width x height x names.size() floats) to `temporaryPath` in the format
     *  that `path`'s extension names: 8-bit for the 8-bit formats (values clamped to [0,1], NaN
     *  to 0), half for TIFF when `half`, float otherwise. A channel named "A" or "*.A" is alpha;
     *  colour is written as given, never divided by alpha. Returns an empty string, or the
     *  problem. */
    virtual std::string writeFile(int width, int height, const std::vector<std::string>& names,
                                  std::vector<float> pixels, const std::string& path,
                                  const std::string& temporaryPath, bool half) const = 0;

    /** The bytes of an image file of the format `extension` names (RGB, 3 channels): from
     *  `bytes` (8-bit) when non-null, else from `floats`; `jpegQuality` 1..100 for JPEG, and
     *  `fullChroma` for JPEG chroma at full resolution (4:4:4: three unrelated planes in one
     *  image keep their own detail) instead of libjpeg's 4:2:0. Returns false and sets `error`
     *  on failure. */
    virtual bool encode(int width, int height, const unsigned char* bytes, const float* floats,
                        const std::string& extension, int jpegQuality,
                        std::vector<unsigned char>& encoded, std::string& error,
                        bool fullChroma = false) const = 0;

    /** Draws `text` with its baseline's left end at (x, y), `size` pixels high, every channel set
     *  to `value`, with the DejaVu Sans font or the decoder library's default. False when no
     *  font could be found. */
    virtual bool drawText(FloatImage& image, int x, int y, const std::string& text, int size,
                          float value) const = 0;
};

/** The module, loaded on the first call (thread-safe). Throws Error naming the module and the
 *  loader's reason when it cannot be loaded. */
const ImageCodecs& imageCodecs();

}  // namespace osgBTF

/** The module's one exported symbol: its ImageCodecs, valid for the process's life. */
extern "C" const osgBTF::ImageCodecs* osgbtfImageCodecs();
