// osgBTF: one (view, light) image of a material, rectified like a measured BTF image: one pixel
// per texel, seen from above with the given view direction used for shading.
#pragma once

#include <vector>

#include <glm/vec3.hpp>
#include <osg/Geode>

#include "core/CoordinateMap.h"
#include "core/FloatImage.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/EnvironmentLighting.h"
#include "materials/Material.h"

namespace osgBTF {

/** The unit square of createFullScreenQuadGeometry with the tangent attribute +X (the patch's
 *  local frame is the measured one): what every rectified image is drawn on. */
osg::ref_ptr<osg::Geode> rectifiedPatch();

/** The uniforms of a rectified image on `stateSet`: the local view fixed to `view`, one white
 *  directional light toward `light`, both in the patch's frame (the camera's view matrix is the
 *  identity there, so eye space is the patch's local frame). The fixed view is set with OVERRIDE:
 *  it also holds for materials' StateSets below `stateSet`, which set the real eye direction. */
void addRectifiedLighting(osg::StateSet& stateSet, const glm::vec3& view, const glm::vec3& light);

/** A w x h RGBA float image as HeadlessRenderer::render reads it back (rows bottom-up) as an RGB
 *  FloatImage with rows top-down (as image files). */
FloatImage rgbTopDown(const osg::Image& image, int w, int h);

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

/** Environment lighting of the patch (normal +Z, tangent +X, nothing occluding it; Sattler et al.
 * 2003 section 5): the map projected onto the material's measured light directions, g_i = sum over
 *  the upper hemisphere's texels of w_i(d) L Omega (materials/EnvironmentLighting.h). */
std::vector<glm::vec3> projectPatchEnvironment(const Material& material, const EnvironmentMap& map);

/** CPU path: sum_i g_i BTF(x, v, l_i) per texel (evaluateProjected: exact for the linear
 *  methods, the projection's approximation for the others, see scene/README.md), times
 *  `exposure`; layout as evaluateMaterialImage. */
FloatImage evaluateEnvironmentImage(const Material& material, const std::vector<glm::vec3>& g,
                                    const glm::vec3& view, float exposure = 1.0f);

/** GPU path: methods with folded environment lighting (foldsEnvironment: pca, fmf, lpca)
 *  through their environment program with the same data at the patch's 4 vertices; the others
 *  as sum_i g_i x the point-light image at l_i (one render per light with g_i != 0), the same sum
 *  as the CPU path. */
FloatImage renderEnvironmentImage(HeadlessRenderer& renderer, const Material& material,
                                  const std::vector<glm::vec3>& g, const glm::vec3& view,
                                  float exposure = 1.0f);

/** The largest absolute difference between two images of the same size (Error otherwise). */
double maxAbsDifference(const FloatImage& a, const FloatImage& b);

}  // namespace osgBTF
