// GPU == CPU check shared by every method's tests: render a flat patch of the material with an
// orthographic camera from a view direction under one directional light into a float FBO, and
// compare each pixel with Material::evaluate for the texel it shows.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>
#include <osg/Drawable>

#include "harness/Pictures.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"

namespace osgBTF::test {

struct GpuCpuComparison {
    double maxAbsDifference = 0;  ///< over all compared pixels and channels
    int pixelsCompared = 0;
    std::string worst;  ///< where the largest difference was, for failure messages
};

/** Renders `material` (unit patch in the XY plane, tangent +X, normal +Z) seen from `view` and
 *  lit from `light` (local unit vectors), several pixels per texel, and compares pixels whose
 *  centre is not close to a texel edge with the CPU evaluator. Uses sharedRenderer(). */
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
    std::vector<char> shaded;  ///< btfEvaluate ran (geometry, view and light above the horizon)
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

/** Every shaded pixel of `render` against Material::evaluate at its own texel and directions. */
GpuCpuComparison compareProbedWithCpu(const Material& material, const ProbedRender& render);

}  // namespace osgBTF::test
