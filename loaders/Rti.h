// osgBTF: reader for RTI capture sets (Reflectance Transformation Imaging): photos of a surface
// from one fixed camera, each under one light, with a light-position file (".lp") naming every
// photo and its light direction, as light domes, handheld rigs and RTIBuilder write them. Read as a
// BTF of one view (formats.md section 7).
#pragma once

#include <memory>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "core/MeasuredBtf.h"
#include "loaders/LoadOptions.h"

namespace osgBTF {

/** One line of a light-position file: the image it names (as written) and its light. */
struct RtiLight {
    std::string image;    ///< as written: a bare name, a relative, absolute or Windows path
    glm::vec3 direction;  ///< unit length (the file's vector normalised)
    int line = 0;         ///< 1-based line number in the file
};

/** Parses the text of a light-position file: the image count on the first line, then one line
 *  "IMAGE X Y Z" per image (IMAGE may contain spaces; the last three fields are the direction,
 *  x to the image's right, y up, z toward the camera). CRLF line ends and blank lines are
 *  accepted; directions are normalised. Throws Error "LP:LINE: problem" for a count that is not
 *  a number or not the number of image lines, a line without three numbers after the name, a
 *  direction of zero length or below the horizon (z < 0), and an image named twice. */
std::vector<RtiLight> parseLightPositions(const std::string& text, const std::string& lpPath);

/** Whether loadMeasuredBtf reads `path` as an RTI set: a ".lp" file, or a folder or zip archive
 *  holding a ".lp" file (any case) and no UBO2003-named image. False for what cannot be opened. */
bool isRtiCapture(const std::string& path);

/** Loads an RTI set: `path` is the ".lp" file (its images are looked up beside it, in its folder
 *  tree), or a folder or zip holding exactly one ".lp" file and the images. Each image is found
 *  by its path relative to the .lp file's folder, else by its file name alone (RTIBuilder writes
 *  absolute or Windows paths from the machine that captured). One view, straight on (theta 0,
 *  "rti-view"); the lights in file order ("rti-lights"). 8-bit photos are decoded as sRGB
 *  unless options.curve says otherwise. Throws Error naming the file (and line) for a malformed
 *  .lp, a missing or ambiguous image, images of different sizes, a corrupt image. */
MeasuredBtf loadRti(const std::string& path, const LoadOptions& options = {});

/** What an RTI set is, from its light file and its first photo's header: nothing decoded. */
struct RtiCaptureHeader {
    int width = 0, height = 0;
    bool rawBytes = false;  ///< 8-bit photos (kept as bytes when out of core)
    DirectionSet lights;
    std::string decoding;  ///< the decode curve's label
};
RtiCaptureHeader readRtiCaptureHeader(const std::string& path, const LoadOptions& options = {});

/** Whether openRtiCapture keeps a capture of this size out of core under `options`. */
bool rtiCaptureOnDisk(int width, int height, std::size_t lights, const LoadOptions& options);

/** Opens an RTI set for fitting: in memory as loadRti does when options.placement says Memory, or
 *  says Auto and its floats take at most a quarter of the memory limit; else out of core (an
 *  OutOfCoreImageSet: the photos decoded once to a temporary file, read back in blocks). Same
 *  errors as loadRti. */
std::unique_ptr<BtfSource> openRtiCapture(const std::string& path, const LoadOptions& options = {});

}  // namespace osgBTF
