// osgBTF harness: the pictures of the comparison report (model renders, error maps, measured vs
// modelled grids, the error-vs-memory plot) as FloatImages / SVG text.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <osg/Geometry>

#include "core/FloatImage.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"

namespace osgBTF {

/** A UV sphere of radius 1 around the origin: normals, texture coordinates (s around the equator,
 *  t from the south to the north pole) and the tangent attribute (location 6, "osgBTF_tangent",
 *  along +s, w = 1) the BTF shaders need. Small on purpose: a stand-in until a scene-graph node
 *  for BTF materials exists. */
osg::ref_ptr<osg::Geometry> createTangentSphere(int segments = 64, int rings = 32);

/** One light/view setting of the model renders. */
struct SphereSetting {
    std::string name;           ///< e.g. "front light"
    float cameraElevation = 0;  ///< degrees: the camera orbits up around the sphere's x axis
    osg::Vec3 lightDirection;   ///< eye space, towards the light
};
/** Front, grazing and back-lit settings (Meseth et al. 2003 Fig. 5/6 show a few such lights). */
std::vector<SphereSetting> defaultSphereSettings();

/** The material on the sphere seen from a perspective camera, one directional light; RGB, rows
 *  top-down, linear values. `textureScale` repeats the texture across the sphere. */
/** The perspective camera renderSphere looks at the unit sphere with (size x size pixels). */
CameraSetup sphereCamera(const SphereSetting& setting, int size);
FloatImage renderSphere(HeadlessRenderer& renderer, const Material& material,
                        const SphereSetting& setting, int size, float textureScale);

/** Nearest-neighbour enlargement by an integer factor. */
FloatImage enlarge(const FloatImage& image, int factor);

/** Images side by side in rows (each row's images the same height is not required: cells are
 *  the largest image's size), `gap` pixels between cells, background `fill`. RGB. */
FloatImage tileImages(const std::vector<std::vector<FloatImage>>& rows, int gap, float fill = 0.0f);

/** `top` above `bottom`, left-aligned, `gap` pixels between; RGB, background `fill`. */
FloatImage stackImages(const FloatImage& top, const FloatImage& bottom, int gap, float fill);

/** Adds a band of `height` pixels above the image (filled with `fill`). */
FloatImage addTopBand(const FloatImage& image, int height, float fill);

/** Draws text through OpenImageIO's render_text (FreeType with a system font such as DejaVu
 *  Sans; core/ImageCodecs.h).
 *  Returns false, drawing nothing, when no font is found. */
bool drawText(FloatImage& image, int x, int y, const std::string& text, int size,
              float value = 1.0f);

/** The colour map of the error maps (viridis: dark blue = 0, yellow = max). t in [0, 1]. */
glm::vec3 colourMap(float t);

/** A per-texel error map (values rows bottom-up, as ErrorSummary::perTexel) colour-mapped over
 *  [0, maxValue], top-down RGB; NaN (a texel outside the compared subsample) is grey, an
 *  infinite error magenta. */
FloatImage colourMappedErrors(const std::vector<float>& perTexel, int width, int height,
                              double maxValue);

/** A horizontal colour bar `width` x `height` of the same map, 0 at the left. */
FloatImage colourBar(int width, int height);

/** A measured (view, light) image of the BTF, top-down RGB (like evaluateMaterialImage). */
FloatImage measuredImage(const BtfSource& btf, std::size_t view, std::size_t light);

/** Index of the direction of `set` closest to (theta, phi) degrees. */
std::size_t nearestDirection(const DirectionSet& set, float theta, float phi);

/** One point of the error-vs-memory plot. */
struct PlotPoint {
    std::string label;
    double bytesPerTexel = 0;
    double error = 0;
};
/** An SVG scatter plot: x = bytes per texel (log10 axis), y = average per-texel error. */
std::string errorMemorySvg(const std::vector<PlotPoint>& points, const std::string& title);

}  // namespace osgBTF
