// GPU == CPU check shared by every method's tests: render a flat patch of the material under a
// model transform and a camera (orthographic or perspective) with one directional light into a
// float FBO, and compare each pixel with Material::evaluate for the texel it shows, seen from the
// direction its own eye ray comes from, in the surface frame the shader must build.
#pragma once

#include <string>

#include <glm/mat3x3.hpp>
#include <glm/vec3.hpp>
#include <osg/Matrixd>

#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"

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

/** Renders the patch as `render` says and compares every pixel whose centre is on the patch and
 *  not close to a texel edge with the CPU evaluator (view = the pixel's eye ray reversed, light =
 *  `toLight`, both in patchFrame(model)). Uses sharedRenderer(). */
GpuCpuComparison compareGpuWithCpu(const Material& material, const PatchRender& render);

/** The flat patch seen orthographically from `view`, lit from `light` (local unit vectors). */
GpuCpuComparison compareGpuWithCpu(const Material& material, const glm::vec3& view,
                                   const glm::vec3& light);

}  // namespace osgBTF::test
