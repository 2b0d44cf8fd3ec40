// osgBTF: one (view, light) image of a material, rectified like a measured BTF image: one pixel
// per texel, seen from above with the given view direction used for shading.
#pragma once

#include <glm/vec3.hpp>

#include "core/CoordinateMap.h"
#include "core/FloatImage.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"

namespace osgBTF {

/** GPU path: renders the material's StateSet on a unit patch (tangent +X, normal +Z) with an
 *  orthographic camera from above, the view direction fixed to `view` (uniform
 *  osgBTF_fixedView) and one white directional light from `light`. Returns an RGB image with
 *  rows top-down (as image files; row 0 = the +Y edge). */
FloatImage renderMaterialImage(HeadlessRenderer& renderer, const Material& material,
                               const glm::vec3& view, const glm::vec3& light);

/** CPU path: Material::evaluate for every texel, same layout. */
FloatImage evaluateMaterialImage(const Material& material, const glm::vec3& view,
                                 const glm::vec3& light);

/** The same through a coordinate map (materials/CoordinateMapRendering.h): one pixel per MAP
 *  texel (map.width x map.height), the method's map program picking each pixel's sample texel.
 *  Throws Error when the map points into another sample size than the material's. */
FloatImage renderMaterialImage(HeadlessRenderer& renderer, const Material& material,
                               const CoordinateMap& map, const glm::vec3& view,
                               const glm::vec3& light);

/** CPU path through a map: pixel (x, y) is Material::evaluate at texel map(x, y). */
FloatImage evaluateMaterialImage(const Material& material, const CoordinateMap& map,
                                 const glm::vec3& view, const glm::vec3& light);

/** The largest absolute difference between two images of the same size (Error otherwise). */
double maxAbsDifference(const FloatImage& a, const FloatImage& b);

}  // namespace osgBTF
