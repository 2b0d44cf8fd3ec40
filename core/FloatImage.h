// osgBTF: float images in and out of files: OpenEXR through OpenEXR, everything else through OIIO.
#pragma once

#include <cstddef>
#include <functional>
#include <string>
#include <vector>

namespace osgBTF {

/** A float image as stored in a file.
 *
 *  Rows are TOP-DOWN, as in the file (row 0 is the top row, the first scanline of an EXR or PNG):
 *  the opposite of osg::Image and MeasuredBtf, whose row 0 is the bottom. Pixels are interleaved:
 *  pixels[(y * width + x) * channels + c]. */
struct FloatImage {
    int width = 0;
    int height = 0;
    int channels = 0;
    /** One name per channel, e.g. "R", "G", "B", "A" or "diffuse.R". Empty names get defaults
     *  when writing (see writeFloatImage). */
    std::vector<std::string> channelNames;
    std::vector<float> pixels;

    FloatImage() = default;
    /** Zero-filled image; channel names left empty. */
    FloatImage(int width, int height, int channels);

    std::size_t index(int x, int y, int c) const {
        return (std::size_t(y) * std::size_t(width) + std::size_t(x)) * std::size_t(channels) +
               std::size_t(c);
    }
    float& at(int x, int y, int c) { return pixels[index(x, y, c)]; }
    float at(int x, int y, int c) const { return pixels[index(x, y, c)]; }
    /** Index of the channel with this exact name, or -1. */
    int channelIndex(const std::string& name) const;
};

/** Reads one image as 32-bit floats.
 *
 *  OpenEXR files (recognised by their magic number, whatever the extension) are read with
 *  OpenEXR: scanline or tiled parts, half/float/uint channels, any channel count, any data window
 *  (the image covers the data window). `part` picks the part of a multi-part file (0 = first).
 *  EXR stores channels sorted by name; they come back grouped by layer ("" first, then "a.", "b."
 *  ...), within a layer R, G, B, A first, then the others in natural order (c2 before c10).
 *
 *  Other formats go through OpenImageIO (`part` = subimage). 8-bit and 16-bit files are scaled to
 *  [0,1] without any colour-space conversion: an sRGB PNG gives its encoded values / 255.
 *
 *  Throws Error "PATH: problem" for a missing, empty, unreadable, corrupt or truncated file, a
 *  part out of range, subsampled or deep EXR data, or an image over memoryLimit(). */
FloatImage readFloatImage(const std::string& path, int part = 0);

/** Every part of an EXR file (a single-part file gives one image). Throws Error like
 *  readFloatImage, also for a file that is not an OpenEXR file. */
std::vector<FloatImage> readExrParts(const std::string& path);

/** Writes an image atomically (see writeFileAtomically); the format follows the extension.
 *
 *  - .exr: OpenEXR, ZIP compression, 32-bit float channels, or half when `half` is true (a
 *    finite value beyond the half range, |v| > 65504, is an error rather than a silent Inf).
 *  - .png, .jpg/.jpeg, .bmp, .tga, .ppm/.pgm/.pnm, .gif, .webp (8-bit formats): values are
 *    clamped to [0,1] (NaN to 0) and written as they are: no sRGB encoding, and colour is never
 *    premultiplied or divided by alpha. JPEG (no alpha) refuses 2- and 4-channel images.
 *  - .hdr (RGBE, 3 channels), .tif/.tiff (float, or half when `half`), anything else OIIO can
 *    write: handed to OIIO as float.
 *  - `srgbEncode` (any format, meant for 8-bit previews): applies the sRGB transfer curve to every
 *    channel except alpha ("A" or "*.A") before writing; negative values become 0.
 *
 *  Channel names come from image.channelNames; missing or empty names default to Y (1 channel),
 *  R,G (2), R,G,B (3), R,G,B,A (4), c0..cN-1 (more). Throws Error "PATH: problem" when the image
 *  is inconsistent (size of pixels), names repeat, the folder is missing, or the writer fails; an
 *  existing file at `path` is then left untouched. */
void writeFloatImage(const FloatImage& image, const std::string& path, bool half = false,
                     bool srgbEncode = false);

/** Number of NaN and infinite values. */
std::size_t countNonFinite(const FloatImage& image);

/** Throws Error "PATH: 3 NaN and 1 Inf values (first at x=4, y=0, channel 'G')" if the image
 *  holds any non-finite value. */
void requireFinite(const FloatImage& image, const std::string& path);

/** Writes `path` so that it either appears complete or not at all: `write` receives a temporary
 *  name in the same folder ("<path>.tmp<pid>"), which is renamed to `path` once `write` returns.
 *  If `write` throws, the temporary file is removed, the exception propagates and an existing
 *  file at `path` is untouched. Throws Error "PATH: folder 'DIR' does not exist" up front. */
void writeFileAtomically(const std::string& path,
                         const std::function<void(const std::string& temporaryPath)>& write);

/** writeFileAtomically of a text (a report, a record) or of any bytes. */
void writeTextAtomically(const std::string& path, const std::string& text);

/** The whole file as bytes. Throws Error "PATH: cannot be read" (with the reason) when it cannot
 *  be opened or read, and "PATH: is not a regular file" for a folder. */
std::string readWholeFile(const std::string& path);

/** Removes what killed writers left in `folder`: entries named "STEM.tmp<pid>" or "STEM.old<pid>"
 *  (the temporary names of writeFileAtomically and of folders published by rename) for which
 *  `matches(STEM)` holds and whose process <pid> no longer runs on this machine. A writer killed
 *  with SIGKILL cannot remove its own temporary; the next run of the same kind cleans it. Errors
 *  are ignored (a temporary left behind is clutter, never taken for a result: readers only open
 *  final names). Returns how many entries it removed. */
std::size_t removeStaleTemporaries(const std::string& folder,
                                   const std::function<bool(const std::string& stem)>& matches);

}  // namespace osgBTF
