// GPU == CPU check shared by every method's tests: render a flat patch of the material with an
// orthographic camera from a view direction under one directional light into a float FBO, and
// compare each pixel with Material::evaluate for the texel it shows.
#pragma once

#include <string>

#include <glm/vec3.hpp>

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

}  // namespace osgBTF::test
