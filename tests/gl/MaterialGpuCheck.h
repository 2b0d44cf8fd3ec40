// GPU == CPU check shared by every method's tests: render a flat patch of the material under a
// model transform and a camera (orthographic or perspective) with one directional light into a
// float FBO, and compare each pixel with Material::evaluateFiltered at its texture coordinate
// (every material is filtered), seen from the direction its
// own eye ray comes from, in the surface frame the shader must build.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <glm/mat3x3.hpp>
#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <osg/Drawable>
#include <osg/Geometry>
#include <osg/Matrixd>

#include "core/CoordinateMap.h"
#include "harness/Pictures.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"

namespace osgBTF {
class PtmMaterial;
class HshMaterial;
}  // namespace osgBTF

namespace osgBTF::test {

struct GpuCpuComparison {
    double maxAbsDifference = 0;  ///< over all compared pixels and channels
    int pixelsCompared = 0;
    std::string worst;  ///< where the largest difference was, for failure messages
};

/** The unit patch (XY plane, texture s along +X, t along +Y, normal +Z, tangent attribute +X)
 *  placed in the world by `model`, seen through `camera`, lit by one white directional light
 *  coming from the world direction `toLight`. */
struct PatchRender {
    osg::Matrixd model;  ///< patch -> world (identity by default)
    CameraSetup camera;
    osg::Vec3d toLight{0, 0, 1};
    /** osgBTF_textureScale: the patch shows texture coordinates [0, textureScale]^2. */
    float textureScale = 1.0f;
};

/** The local frame (columns: tangent, bitangent, normal; world coordinates) of the patch under
 *  `model`, as a renderer must build it: the normal is +Z by the inverse transpose of the model's
 *  upper 3x3, the tangent is +X by the upper 3x3 itself (a tangent is a surface direction, not a
 *  normal) made orthogonal to the normal, the bitangent normal x tangent. */
glm::dmat3 patchFrame(const osg::Matrixd& model);

/** An orthographic camera and light for the patch under `model`, seen from `view` and lit from
 *  `light`, both given in the patch's local frame (patchFrame), about 4 pixels per texel along a
 *  texel's shortest side on screen. */
PatchRender orthoPatchRender(const Material& material, const glm::vec3& view,
                             const glm::vec3& light, const osg::Matrixd& model = osg::Matrixd());

/** A magnified top-down orthographic view of the patch: `texels` x `texels` texels around
 *  texture coordinate `centre` (after textureScale; beyond 1 the texture wraps) over `pixels` x
 *  `pixels` pixels, lit from `light` (local). With a centre on a texel corner and pixels / texels
 *  a power of two, every pixel centre's bilinear weights are multiples of a power of two, exact
 *  in any filter's fixed-point weights as in float. */
PatchRender magnifiedPatchRender(const Material& material, const glm::vec2& centre,
                                 float textureScale, const glm::vec3& light, int texels = 4,
                                 int pixels = 64);

/** Renders the patch as `render` says and compares every pixel whose centre is on the patch with
 *  the CPU reference (view = the pixel's eye ray reversed, light = `toLight`, both in
 *  patchFrame(model)): Material::evaluateFiltered at the pixel's texture coordinate, level 0 (the
 *  texels around it, blended). Uses sharedRenderer(). */
GpuCpuComparison compareGpuWithCpu(const Material& material, const PatchRender& render);

/** The flat patch seen orthographically from `view`, lit from `light` (local unit vectors). */
GpuCpuComparison compareGpuWithCpu(const Material& material, const glm::vec3& view,
                                   const glm::vec3& light);

/** A render of a material together with what each fragment shaded: its texel and its local
 *  view and light directions, read back from probe programs that share the method's vertex stage
 *  and frame code (shaders/common/btf.vert, btf_main.glsl) and whose btfEvaluate returns its
 *  inputs. So the CPU evaluator can be asked exactly what every fragment computed, on any
 *  geometry and camera. Pixels rows bottom-up; one light of colour 1 expected. */
struct ProbedRender {
    int width = 0, height = 0;
    std::vector<glm::vec3> color, view, light;
    std::vector<glm::ivec2> texel;
    std::vector<glm::vec2> uv;  ///< the fragment's texture coordinate (after osgBTF_textureScale)
    std::vector<char> shaded;   ///< btfEvaluate ran (geometry, view and light above the horizon)
    std::size_t at(int x, int y) const { return std::size_t(y) * width + x; }
};

/** Renders `drawable` with the material's StateSet, after `configure` added lights and the
 *  like to it, and the same with each probe program. Uses sharedRenderer(). */
ProbedRender renderProbed(const Material& material, osg::Drawable* drawable,
                          const CameraSetup& camera,
                          const std::function<void(osg::StateSet&)>& configure);

/** The material on harness/Pictures' tangent sphere under renderSphere's camera and light for
 *  `setting`, texture repeated `textureScale` times: a perspective, curved, tiled surface. */
ProbedRender renderProbedSphere(const Material& material, const SphereSetting& setting, int size,
                                float textureScale);

/** Every shaded pixel of `render` against the CPU reference at its own directions and texture
 *  coordinate (Material::evaluateFiltered at level 0: the texels around it, blended). */
GpuCpuComparison compareProbedWithCpu(const Material& material, const ProbedRender& render);

/** The GPU-CPU bound of a PTM material: GPU and CPU run the same float operations and may differ
 *  by the rounding of each (a GPU may fuse a multiply and an add): about 8 operations per
 *  polynomial, 3 blended views, and the view weights equal to rounding, so a few tens of u times
 *  the largest sum of |terms| (|a_k| times the colour; every monomial is at most 1). */
double ptmGpuTolerance(const PtmMaterial& material);
/** The same for an HSH material: the basis's ~45 float operations and up to 16 terms, so 64 u
 *  times the largest sum of |c_k| times the largest harmonic (about 1.1; 2 is used). */
double hshGpuTolerance(const HshMaterial& material);

/** The fragment source of the program in `material`'s own state set ("" without one). */
std::string fragmentSourceOf(const Material& material);

/** Expects GPU == CPU within `bound` for `material` rendered from each (view, light) pair (and a
 *  render that covers more than 48 texels); prints the largest difference under `label`. */
void expectGpuEqualsCpuAtPairs(const Material& material, double bound,
                               const std::vector<std::pair<Direction, Direction>>& pairs,
                               const std::string& label);

/** The GPU-CPU bound of the methods' own tests (bilinear_filter_test.cpp's) for a render from
 *  `view` lit from `light`: lambert 1e-5, ptm ptmGpuTolerance, hsh hshGpuTolerance, fmf 1e-3 of the
 * image's largest value (at least 1), the others 1e-3. */
double methodGpuBound(const Material& material, const glm::vec3& view, const glm::vec3& light);

/** A rectified render of the unit patch (harness/MaterialImage.h: rectifiedPatch under
 *  orthoUnitSquare, the view fixed to `view`, one white light from `light`, both local) at a
 *  texture scale, optionally through a coordinate map: what the mip-map, coordinate-map and
 *  dummy-method tests compare with Material::evaluateFiltered / evaluateThroughMap at pixel
 *  centres ((i + 0.5) / width times the scale). */
struct RectifiedPatchRender {
    glm::vec3 view{0, 0, 1}, light{0, 0, 1};
    /** osgBTF_textureScale: the patch shows [0, textureScale]^2 (beyond 1 the texture wraps). */
    float textureScale = 1.0f;
    int width = 32, height = 32;
    /** osgBTF_mipLevels when >= 0 (1: the base level only); < 0: the material's own. */
    int mipLevels = -1;
    /** osgBTF_blendTexels: false reads the nearest texel (of each level) instead of four. */
    bool blendTexels = true;
    /** Rendered through this map (createCoordinateMapStateSet) when not null. */
    const CoordinateMap* map = nullptr;
};

/** Renders `material` (its createStateSet) as `render` says with sharedRenderer(): an RGBA float
 *  image, rows bottom-up (pixel()). */
osg::ref_ptr<osg::Image> renderRectifiedPatch(const Material& material,
                                              const RectifiedPatchRender& render);

/** The unit patch of rectifiedPatch() (normal +Z, tangent attribute +X, texture coordinates =
 *  position) as two indexed triangles (0 1 2, 0 2 3): what environment lighting needs (its
 *  geometry stage takes triangles, environment/VertexEnvironment.h lights only triangles). */
osg::ref_ptr<osg::Geometry> trianglePatch();

/** The largest differences of a render through a coordinate map, magnified and across the wrap,
 *  per channel over every pixel (checkThroughMap). */
struct ThroughMapCheck {
    double gpuCpu = 0;           ///< against evaluateThroughMap
    double materialisedCpu = 0;  ///< evaluateThroughMap against the materialised evaluateFiltered
    double materialisedGpu = 0;  ///< against the render of the materialised material
    double fromNearest = 0;      ///< evaluateThroughMap against the entry under the pixel alone
};

/** Renders `material` through `map` and `remapped` (remapMaterial(material, map)) without it at
 *  texture scale 2, 4 pixels per map entry, as rectified images seen from `view` and lit from
 *  `light`, and compares every pixel with evaluateThroughMap. */
ThroughMapCheck checkThroughMap(const Material& material, const Material& remapped,
                                const CoordinateMap& map, const glm::vec3& view,
                                const glm::vec3& light);

}  // namespace osgBTF::test
