// osgBTF: reader for UBO2003 / ATRIUM BTFs, a zip archive (or a folder) holding one image per
// (light, view) pair named "tlTTT plPPP tvTTT pvPPP.jpg" (formats.md section 1).
#pragma once

#include <string>

#include "core/MeasuredBtf.h"
#include "loaders/LoadOptions.h"

namespace osgBTF {

/** The parsed basename of one image, e.g. "00008 tl000 pl000 tv030 pv030.jpg". */
struct Ubo2003Name {
    int index = -1;  ///< the optional 5-digit prefix, -1 when absent
    int lightTheta = 0, lightPhi = 0, viewTheta = 0, viewPhi = 0;  ///< integer degrees
    std::string extension;  ///< lower case, without the dot: jpg, jpeg, png, hdr or exr
};

/** Parses the basename of memberPath (folders are ignored). Returns false when the basename is not
 *  "[NNNNN ]tlTTT plPPP tvTTT pvPPP.<jpg|jpeg|png|hdr|exr>" (extension case-insensitive). */
bool parseUbo2003Name(const std::string& memberPath, Ubo2003Name& name);

/** Loads a UBO2003/ATRIUM zip archive, or a folder searched recursively for the same images.
 *  Every (light, view) pair must be present exactly once and all images must have one size.
 *  The light and view sets are DirectionSet::bonn81() when the names hold exactly those 81
 *  directions, else the directions found sorted by theta, then phi. Images are flipped so that
 *  the top row of an image file becomes the top row (height-1) of the bottom-up MeasuredBtf.
 *  Throws osgBTF::Error naming the file and the problem. */
MeasuredBtf loadUbo2003(const std::string& path, const LoadOptions& options = {});

/** False when path is a zip archive or folder that opens and holds no member named like a BTF
 *  image (direction tokens "tlTTT plPPP tvTTT pvPPP"): some other zip, which the osgdb_btfzip
 *  plugin leaves to the next reader. True otherwise, so a damaged BTF zip still gets
 *  loadUbo2003's message. Reads only the member names. */
bool mayBeUbo2003(const std::string& path);

}  // namespace osgBTF
