// osgBTF: the `.rti` files of hemispherical harmonics that RTIBuilder writes and RTIViewer reads,
// as `hsh` materials. The layout in our words: docs/formats.md section 8.
//
//   #HSH1.2            comment lines, each starting with '#' (any number)
//   3                  the RTI type: 3 = hemispherical harmonics
//   W H 3              width, height, colour bands
//   T B 1              terms per band (4, 9 or 16), basis type, bytes per term
//   T float32 (LE)     per term the smallest value its bytes stand for
//   T float32 (LE)     per term the largest
//   <bytes>            rows from the top of the image down; per pixel R's T terms, then G's, B's
//
// Coefficient c_k = min_k + (max_k - min_k) * byte / 255 (RTIViewer's reading of the two float
// arrays), in the basis of Hsh.h, values 0..1.
#pragma once

#include <string>
#include <vector>

#include "materials/RelightLayoutWriter.h"
#include "materials/hsh/Hsh.h"

namespace osgBTF {

struct RtiFileHeader {
    int type = 0;
    int width = 0, height = 0, bands = 0;
    int terms = 0, basisType = 0, elementSize = 0;
    std::vector<float> minimum, maximum;  ///< per term
    std::size_t dataOffset = 0;
    std::uint64_t dataBytes() const;
};

/** Parses the header of an .rti file held in `bytes` (`name` for messages). Throws Error "NAME:
 *  problem" for another RTI type, bands other than 3, terms other than 4, 9 or 16, an element size
 *  other than 1, a missing or non-numeric field, a size that is not positive, a range value that
 *  is not finite, and (when `checkData`) fewer bytes after the header than it announces. */
RtiFileHeader parseRtiHeader(const std::string& name, const std::string& bytes,
                             bool checkData = true);

/** The file as an `hsh` material: front view, order sqrt(T), float storage. Lights: the file
 *  records none; evaluateMeasured uses the 81 Bonn lights. */
osg::ref_ptr<HshMaterial> hshMaterialFromBytes(const std::string& name, const std::string& bytes);
osg::ref_ptr<HshMaterial> readRtiFile(const std::string& path);

struct RelightPlanes;
/** A relight folder of type hsh (materials/RelightFolder.h) as a front-view `hsh` material of
 *  order sqrt(terms): the web order of the terms is Hsh.h's; lrgb (luminance terms times a base
 *  colour) becomes per-channel coefficients colour_c * L_k, the same values. Lights: info.json's,
 *  else the nominal ones. Error "PATH: problem" for a term count other than 4, 9 or 16. */
osg::ref_ptr<HshMaterial> hshMaterialFromRelight(const std::string& infoPath,
                                                 const RelightPlanes& planes);

/** A front-view hsh material as relight's layout holds it (materials/RelightLayoutWriter.h): type
 *  hsh, colorspace rgb, plane 3 k + c term k (Hsh.h's order) of colour c. Error "PATH: problem"
 *  for a per-view material. */
RelightModel relightModelOfHsh(const HshMaterial& material, const std::string& infoPath);

/** Writes a front-view hsh material as 8-bit terms: per term the range of its values over the
 *  image and channels, each byte the nearest step. Written to PATH.tmp<pid> and renamed. Returns
 *  the largest |decoded - stored| over the coefficients and the largest step (range / 255).
 *  Throws Error "PATH: problem" for a views=all or mip-mapped material. */
std::pair<double, double> writeRtiFile(const HshMaterial& material, const std::string& path);

}  // namespace osgBTF
