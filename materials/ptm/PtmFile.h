// osgBTF: the `.ptm` files of the RTI field (Malzbender, Gelb, Wolters, "Polynomial Texture Map
// (.ptm) File Format", HP Labs, version 1.2), read and written as `ptm` materials. The layout in
// our words: docs/formats.md section 8.
//
//   PTM_1.2                          version line
//   PTM_FORMAT_RGB | PTM_FORMAT_LRGB format line
//   W H                              width and height (any white space between the tokens)
//   s0 .. s5                         six float scales
//   b0 .. b5                         six integer biases
//   <bytes>                          after the newline that ends the biases
//
// Coefficient a_k = (byte - b_k) * s_k, in 8-bit intensity units (0..255 is black..white), the
// terms in the order a0 u^2 + a1 v^2 + a2 u v + a3 u + a4 v + a5 of PtmMaterial (u, v: the light's
// x and y). Rows run from the bottom of the image to its top. RGB: three planes (R, G, B), each
// of W x H pixels of 6 bytes. LRGB: W x H pixels of 6 bytes (the luminance polynomial), then
// W x H pixels of 3 bytes (the colour); value = L(u, v) * colour / 255.
//
// The JPEG variants (PTM_FORMAT_JPEG_RGB: 18 streams, R a0..a5, G a0..a5, B a0..a5;
// PTM_FORMAT_JPEG_LRGB: 9 streams, a0..a5 then R, G, B) go on after the biases with one line each
// (docs/formats.md section 8.1.1):
//   q                                compression parameter (the JPEG quality; unused)
//   t_0 .. t_{N-1}                   transforms: 0 none, 1 the reference plane inverted
//   mx_0 .. / my_0 ..                motion vectors x, then y (must be 0)
//   o_0 .. o_{N-1}                   order: stream i is decoded as the o_i-th
//   r_0 .. r_{N-1}                   reference stream of each (-1: none)
//   c_0 .. c_{N-1}                   compressed size of each stream, bytes
//   s_0 .. s_{N-1}                   side-information size of each stream, bytes (5 per record)
//   <bytes>                          per stream i in index order: c_i bytes of a greyscale JPEG
//                                    (W x H, its first scanline the bottom row), s_i bytes of
//                                    records p3 p2 p1 p0 v (position big-endian, value)
// Stream value = its decoded byte, or ((reference, inverted when t_i = 1) + byte - 128) mod 256
// where it has a reference; then each record sets the value at its position.
#pragma once

#include <array>
#include <string>
#include <vector>

#include "materials/RelightLayoutWriter.h"
#include "materials/ptm/Ptm.h"

namespace osgBTF {

struct PtmFileHeader {
    /** "PTM_FORMAT_RGB", "PTM_FORMAT_LRGB", "PTM_FORMAT_JPEG_RGB" or "PTM_FORMAT_JPEG_LRGB" */
    std::string format;
    int width = 0, height = 0;
    std::array<float, 6> scale{};
    std::array<int, 6> bias{};
    std::size_t dataOffset = 0;  ///< where the coefficient bytes start
    // The JPEG variants only (each N entries, N = streams()):
    int compression = 0;  ///< the compression parameter
    std::vector<int> transforms, motionX, motionY, order, reference;
    std::vector<std::uint64_t> compressedSize, sideInfoSize;
    bool luminance() const {
        return format == "PTM_FORMAT_LRGB" || format == "PTM_FORMAT_JPEG_LRGB";
    }
    bool jpeg() const { return format.rfind("PTM_FORMAT_JPEG_", 0) == 0; }
    /** JPEG streams: 18 (JPEG_RGB), 9 (JPEG_LRGB), 0 (the raw formats). */
    int streams() const { return jpeg() ? (luminance() ? 9 : 18) : 0; }
    /** Bytes of coefficients (and colour) the header announces: for the JPEG variants the sum of
     *  the compressed and side-information sizes. */
    std::uint64_t dataBytes() const;
};

/** Parses the header of a .ptm file held in `bytes` (`name` for messages). Throws Error "NAME:
 *  problem" for another version or format, a missing or non-numeric field, a size that is not
 *  positive, a scale that is not finite, (JPEG variants) a transform other than 0 or 1, a motion
 *  vector other than 0, an order that is not a permutation, a reference that is not decoded
 *  before its stream, a side-information size that is no multiple of 5, and (when `checkData`)
 *  fewer bytes after the header than the header announces. */
PtmFileHeader parsePtmHeader(const std::string& name, const std::string& bytes,
                             bool checkData = true);

/** The file as a `ptm` material: front view (one view, straight on), colour rgb (PTM_FORMAT_RGB,
 *  _JPEG_RGB) or luminance (PTM_FORMAT_LRGB, _JPEG_LRGB), float storage holding each decoded
 * coefficient / 255 (values 0..1). Lights: the file records none; evaluateMeasured uses the 81 Bonn
 * lights. */
osg::ref_ptr<PtmMaterial> ptmMaterialFromBytes(const std::string& name, const std::string& bytes);
osg::ref_ptr<PtmMaterial> readPtmFile(const std::string& path);

struct RelightPlanes;
/** A front-view ptm material as relight's layout holds it (materials/RelightLayoutWriter.h):
 *  type ptm; colour rgb as colorspace rgb (plane 3 k + c: term k of relight's order 1, x, y,
 *  x^2, xy, y^2, colour c), luminance as lrgb (planes 0..2 the base colour scaled per texel so
 *  that its largest channel is 1, the polynomial scaled by the inverse: the same product).
 *  Error "PATH: problem" for a per-view material. */
RelightModel relightModelOfPtm(const PtmMaterial& material, const std::string& infoPath);

/** A relight folder of type ptm (materials/RelightFolder.h) as a front-view `ptm` material: rgb
 *  as colour rgb, lrgb as colour luminance (the base colour plane_0 and the luminance planes as
 *  they are); the web order of the terms (1, x, y, x^2, xy, y^2; 3 terms: first degree) mapped
 *  onto the material's. Lights: info.json's, else the nominal ones. Error "PATH: problem" for a
 *  term count other than 3 or 6. */
osg::ref_ptr<PtmMaterial> ptmMaterialFromRelight(const std::string& infoPath,
                                                 const RelightPlanes& planes);

/** What writing quantised. */
struct PtmQuantisation {
    double largestCoefficientError = 0;  ///< max |decoded - stored| over coefficients (0..1 units)
    double largestStep = 0;              ///< the largest scale / 255 (one byte step, 0..1 units)
};

/** Writes a front-view ptm material (rgb: PTM_FORMAT_RGB, luminance: PTM_FORMAT_LRGB) as 8-bit
 *  coefficients: per term the scale and bias that span its values over the image, each byte the
 *  nearest. LRGB colours above 1 are folded into their polynomial (colour / max, polynomial x
 *  max). Written to PATH.tmp<pid> and renamed. Throws Error "PATH: problem" for a views=all or
 *  mip-mapped material, or when the file cannot be written. */
PtmQuantisation writePtmFile(const PtmMaterial& material, const std::string& path);

}  // namespace osgBTF
