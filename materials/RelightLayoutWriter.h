// osgBTF: writes a fitted material as relight's web layout, the folder OpenLIME shows in a browser
// (docs/formats.md section 8.4, docs/real-captures.md "Publishing a capture"): info.json, the
// coefficient planes quantised to 8 bits three to a JPEG as relight's RtiBuilder quantises them,
// and, for large images or on request, relight's deep-zoom pyramid of each plane (plane_j.dzi +
// plane_j_files/LEVEL/COL_ROW.jpg) instead of plane_j.jpg; and an index.html that says how to
// view it.
//
// The writing is the reader's inverse (materials/RelightFolder.h): each method that has a relight
// type registers a function that turns its material into a RelightModel (the unquantised planes
// in display units 0..1 and, for the PCA types, the unquantised basis); this file quantises and
// writes what every type shares.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace osgBTF {

class Material;

/** A material as relight's layout holds it, before quantisation. */
struct RelightModel {
    std::string type;        ///< "ptm", "hsh", "rbf", "bilinear"
    std::string colorspace;  ///< "rgb", "lrgb" or "mrgb"
    int width = 0, height = 0;
    int planeCount = 0;
    /** [m][y][x], rows bottom-up (the material's order), display units. */
    std::vector<float> planes;
    /** lrgb: planes 0..2 (the base colour, 0..1) are stored with scale 1, bias 0, as relight
     *  stores them; every other plane gets its own range. */
    bool baseColourPlanes = false;
    /** Written as info.json "lights" (3 decimals, as relight writes them); for rbf they are the
     *  nodes the weights interpolate between. */
    std::vector<glm::vec3> lights;
    /** mrgb: (planeCount + 1) x nodes RGB values, index p * nodes + i: p = 0 the mean profile
     *  (0..1), p >= 1 the principal profile E_{p-1}. */
    std::vector<glm::vec3> basis;
    float sigma = 0;     ///< rbf (written when positive)
    int resolution = 0;  ///< bilinear (written when positive)
};

/** How a method's material becomes a RelightModel; Error "PATH: problem" for a material the
 *  layout cannot hold (several views, mip levels). */
using RelightModelMaker =
    std::function<RelightModel(const Material& material, const std::string& infoPath)>;
/** The frame every maker starts from: type, colorspace, the material's size and lights, zero
 *  planes; Error "PATH: relight's web layout has no mip levels: fit with --no-mipmap" for a
 *  mip-mapped material. */
RelightModel relightModelFrame(const Material& material, const std::string& infoPath,
                               const std::string& type, const std::string& colorspace,
                               int planeCount);
/** Registers the writer of a method's materials (from the method's folder, at static
 *  initialisation); returns true. */
bool registerRelightWriter(const std::string& method, RelightModelMaker maker);
/** The methods whose materials the layout can hold, alphabetically. */
std::vector<std::string> relightWriterMethods();

struct RelightWriteOptions {
    /** JPEG quality 1..100; relight's default. */
    int quality = 95;
    enum class Layout { Automatic, Image, DeepZoom };
    /** Automatic: the deep-zoom pyramid when the image is larger than kDeepZoomAbove on a side. */
    Layout layout = Layout::Automatic;
    /** The deep-zoom tiles: relight's defaults (relight-cli's deepZoom call: 256, overlap 0). */
    int tileSize = 256;
    int overlap = 0;
    /** Each plane's range is the central fraction of its values (relight's rangeQuantile; the
     *  rest clamps to the range's ends); 1 keeps every value in range. */
    double rangeQuantile = 0.995;
    /** The quantiles are taken over at most this many texels (a deterministic even sample). */
    std::size_t quantileSample = std::size_t(1) << 22;
};

/** A side above which Layout::Automatic tiles: 4096 is the largest texture every WebGL device is
 *  sure to allow, and OpenLIME's image layout loads each plane as one texture. */
constexpr int kDeepZoomAbove = 4096;

/** One plane's quantisation: byte = clamp(int(255 (v / scale + bias)), 0, 255), v = (byte / 255 -
 *  bias) scale back (RtiBuilder::finalizeMaterial and Material::Plane::quantize). */
struct RelightQuantisation {
    float scale = 1, bias = 0;
    unsigned char quantise(float value) const;
};

/** A plane's range as relight's RtiBuilder::minmaxMaterial takes it: the values at the quantiles
 *  (1 - q) / 2 and (1 + q) / 2 (indices truncated) of `values` (reordered), max raised to min +
 *  1e-6 / 255 (or 1e-5 |min|, where float precision needs it) when equal; scale = max - min,
 *  bias = -min / (max - min). */
RelightQuantisation relightRange(std::vector<float>& values, double quantile);

/** The bytes of relight's basis for an mrgb model: the mean truncated to 0..255, then per plane
 *  p 127 + range_p E_p truncated, range_p = 127 / max |E_p| (RtiBuilder::minmaxMaterial, save);
 *  `range` receives range_p. */
std::vector<int> quantiseRelightBasis(const RelightModel& model, std::vector<double>& range);

/** Writes `material` as relight's layout in the folder of `infoPath` (which must be named
 *  info.json; the folder is created): info.json, plane_j.jpg or plane_j.dzi + plane_j_files/,
 *  index.html. Every file is written under a temporary name first and moved in at the end,
 *  info.json last; plane files of an earlier export left in the folder are removed. Returns one
 *  line on what quantisation did (planes, the largest step, values clamped). Error "PATH:
 *  problem" for a material of a method without a writer, a bad option or a failed write. */
std::string writeRelightLayout(const Material& material, const std::string& infoPath,
                               const RelightWriteOptions& options = {});

/** The sizes of relight's deep-zoom levels of a width x height image: element k is level k's,
 *  the last the full size, each level half the next (truncated, at least 1), level 0 the first
 *  that fits one tile (DeepZoom::nLevels, initRows; OpenLIME's layout "deepzoom"). */
std::vector<std::pair<int, int>> deepZoomLevels(int width, int height, int tileSize);

}  // namespace osgBTF
