// osgBTF: relight's web layout of a fitted RTI capture, as OpenLIME loads it (docs/formats.md
// section 8.4): a folder holding info.json and plane_0.jpg .. plane_{N-1}.jpg, N = ceil(nplanes
// / 3), each JPEG carrying three coefficient planes in its R, G and B channels.
//
// This file reads what every type shares (info.json, the layout, the plane images, the per-channel
// dequantisation coef_m = (byte / 255 - bias[m]) * scale[m]) into float planes; the methods turn
// them into their materials: each registers the relight type it reads (registerRelightType, from
// its own folder), and readRelightMaterial dispatches on info.json's "type". The file format
// itself is registered by the ptm method as the foreign file "info.json" (materials/
// ForeignFiles.h), so loadMaterial("DIR/info.json"), `btf info DIR/info.json` and the plugins
// read it. relight's deep-zoom layout (plane_j.dzi + a tile pyramid) is read from its full-size
// level; its other tiled layouts (tarzoom, itarzoom, google, zoomify) are refused with their name.
// Writing the layout: materials/RelightLayoutWriter.h.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <osg/ref_ptr>

#include "core/Directions.h"

namespace osgBTF {

class Material;

/** What a relight type's basis is, which says what info.json holds besides the planes. */
enum class RelightBasis {
    Fixed,           ///< a fixed function of the light (ptm, hsh): colorspace rgb or lrgb
    GaussianNodes,   ///< a PCA basis over the lights, Gaussian weights: mrgb, sigma, basis, range
    OctahedralGrid,  ///< a PCA basis over an octahedral grid: mrgb, resolution, basis, range
};

/** A relight folder's info.json and its decoded planes. */
struct RelightPlanes {
    std::string type;        ///< info.json "type" ("ptm", "hsh", ...)
    std::string colorspace;  ///< "rgb", "lrgb", "mrgb" or "mycc" (ycc is refused)
    int width = 0, height = 0;
    int planeCount = 0;  ///< info.json "nplanes"
    /** Light-dependent terms: nplanes / 3 (rgb), nplanes - 3 (lrgb) or nplanes (mrgb). */
    int terms = 0;
    /** mrgb (types rbf and bilinear): info.json "basis", (nplanes + 1) x nodes x 3 numbers as
     *  written (p-major: the mean profile 0..255, then 127 + range_p E_p per plane), "range"
     *  (nplanes numbers), the rbf's "sigma" and the bilinear's "resolution" (0 for rbf); the
     *  nodes are the lights (rbf) or resolution^2 grid points (bilinear). */
    std::vector<double> basis, range;
    double sigma = 0;
    int resolution = 0;
    RelightBasis basisKind = RelightBasis::Fixed;  ///< the registered type's
    /** The planes are relight's deep-zoom pyramids (plane_j.dzi + plane_j_files/), not
     *  plane_j.jpg; the full-size level is read. */
    bool deepZoom = false;
    /** mycc: info.json "yccplanes" (luminance planes, then the two chroma counts, equal); the
     *  first 3 x yccPlanes[1] planes interleave Y, Co, Cg, the rest are Y. Zeros otherwise. */
    int yccPlanes[3] = {0, 0, 0};
    /** The lights as written (not normalised: relight's rbf weights use them so). */
    std::vector<glm::vec3> rawLights;
    /** The capture's lights (info.json "lights", x right, y up, z towards the viewer); empty
     *  when the file has none. */
    std::vector<glm::vec3> lights;
    /** Dequantised planes, [m][y][x], m = 3 j + c (plane_j.jpg, channel c), rows from the bottom
     *  of the image up (the material's texel order; the JPEGs run top down). Empty after
     *  readRelightHeader. */
    std::vector<float> planes;
    bool luminance() const { return colorspace == "lrgb"; }
    /** Plane m at texel t (rows bottom-up). */
    float at(int m, std::size_t texel) const {
        return planes[std::size_t(m) * std::size_t(width) * std::size_t(height) + texel];
    }
    /** Coefficient of term k (0-based, in the file's order) of colour channel c at a texel: rgb:
     *  plane 3 k + c; lrgb: the luminance term (plane 3 + k) times the base colour (plane c),
     *  which converts a luminance model exactly into per-channel coefficients. */
    float coefficient(int k, int c, std::size_t texel) const {
        return luminance() ? at(3 + k, texel) * at(c, texel) : at(3 * k + c, texel);
    }
};

/** Parses DIR/info.json (`infoPath`) and checks the layout: Error "PATH: problem" for a file that
 *  is not JSON or lacks a key, another colorspace than rgb, lrgb, mrgb and mycc, nplanes that
 *  the colorspace cannot hold, scale or bias arrays whose lengths differ from nplanes or which
 *  hold a value that is not a finite number, lights that are not triples of finite numbers, for
 *  colorspaces mrgb and mycc (types rbf and bilinear) a missing or short "basis", "range",
 *  "sigma", "resolution" or "yccplanes", and a tiled layout (named) or a missing plane_0.jpg.
 *  The planes are left empty. */
RelightPlanes readRelightHeader(const std::string& infoPath);
/** readRelightHeader, then the planes: each plane_j.jpg must be a complete JPEG (Error "PATH:
 *  truncated JPEG (no end-of-image marker)") of the size info.json gives (width and height, or
 *  plane_0.jpg's where info.json has none) with 3 channels. The memory guard (checkMemory) sees
 *  the planes' size before anything is allocated. */
RelightPlanes readRelightPlanes(const std::string& infoPath);

/** Makes a method's material from a relight folder's planes. */
using RelightBuilder =
    std::function<osg::ref_ptr<Material>(const std::string& infoPath, const RelightPlanes& planes)>;
/** Registers the method that reads relight type `type`; each method's .cpp calls it from a static
 *  initialiser. Returns true. */
bool registerRelightType(const std::string& type, RelightBuilder builder,
                         RelightBasis basis = RelightBasis::Fixed);
/** The registered relight types, alphabetically. */
std::vector<std::string> relightTypes();
/** The folder as the material of the method that registered its type; Error "PATH: type 'sh' is
 *  not read (bilinear, hsh, ptm, rbf are)" for others. */
osg::ref_ptr<Material> readRelightMaterial(const std::string& infoPath);
/** What `btf info` prints of info.json (lines). */
std::string relightInfo(const std::string& infoPath);
/** The capture's lights as a direction set (named after the file), or the nominal Bonn lights
 *  (nominalFileLights) when info.json has none. */
DirectionSet relightLights(const std::string& infoPath, const RelightPlanes& planes);

/** The JPEG bytes of `name` are complete: they start with the start-of-image marker FF D8 and
 *  end with the end-of-image marker FF D9 (a file cut short ends inside its entropy-coded data;
 *  the decoders would fill the rest with grey and only warn). Error "NAME: problem" otherwise. */
void checkJpegComplete(const std::string& name, const unsigned char* bytes, std::size_t size);

/** Decodes one JPEG held in memory through the project's image codecs (core/ImageCodecs.h),
 *  checking from its header, before decoding, that it is `width` x `height` with `channels`
 *  channels; returns width x height x channels bytes, rows as stored. Error "NAME: problem". */
std::vector<unsigned char> decodeJpeg(const std::string& name, const unsigned char* bytes,
                                      std::size_t size, int width, int height, int channels,
                                      const std::string& expected);

}  // namespace osgBTF
