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
#pragma once

#include <array>
#include <string>

#include "materials/ptm/Ptm.h"

namespace osgBTF {

struct PtmFileHeader {
    std::string format;  ///< "PTM_FORMAT_RGB" or "PTM_FORMAT_LRGB"
    int width = 0, height = 0;
    std::array<float, 6> scale{};
    std::array<int, 6> bias{};
    std::size_t dataOffset = 0;  ///< where the coefficient bytes start
    bool luminance() const { return format == "PTM_FORMAT_LRGB"; }
    /** Bytes of coefficients (and colour) the header announces. */
    std::uint64_t dataBytes() const;
};

/** Parses the header of a .ptm file held in `bytes` (`name` for messages). Throws Error "NAME:
 *  problem" for another version or format (the JPEG-compressed formats are named as not read),
 *  a missing or non-numeric field, a size that is not positive, a scale that is not finite, and
 *  (when `checkData`) fewer bytes after the header than the header announces. */
PtmFileHeader parsePtmHeader(const std::string& name, const std::string& bytes,
                             bool checkData = true);

/** The file as a `ptm` material: front view (one view, straight on), colour rgb (PTM_FORMAT_RGB)
 *  or luminance (PTM_FORMAT_LRGB), float storage holding each decoded coefficient / 255 (values
 *  0..1). Lights: the file records none; evaluateMeasured uses the 81 Bonn lights. */
osg::ref_ptr<PtmMaterial> ptmMaterialFromBytes(const std::string& name, const std::string& bytes);
osg::ref_ptr<PtmMaterial> readPtmFile(const std::string& path);

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
