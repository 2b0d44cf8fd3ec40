// osgBTF: what a method registers to be lit by an environment folded per vertex
// (MethodInfo::environment, materials/MethodRegistry.h; the render state that uses it is
// materials/EnvironmentState.h).
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

#include <glm/vec3.hpp>

namespace osg {
class StateSet;
}

namespace osgBTF {

class Material;

/** Environment lighting folded per vertex (materials/EnvironmentState.h, Sattler et al. 2003
 * section 5.2), for a method whose point-light rendering is linear in the light interpolation
 * weights: the environment projected onto the measured lights (g) folds into the method's own light
 * basis. Its shader is "environment/<name>.frag" (materials/<name>/<name>_environment.frag). The
 *  functions get materials of the method's own class. */
struct EnvironmentHooks {
    /** Whether this material folds (empty: every material of the method does); e.g. fmf only
     *  without dynamic-range reduction. */
    std::function<bool(const Material&)> folds;
    /** One vertex's data from g (one RGB value per measured light); throws Error for g of the
     *  wrong size or a material that does not fold. */
    std::function<std::vector<float>(const Material&, const std::vector<glm::vec3>& g)> fold;
    /** What the environment shader draws from one vertex's data: its CPU reference. */
    std::function<glm::vec3(const Material&, const std::vector<float>& folded, int x, int y,
                            const glm::vec3& view)>
        evaluateFolded;
    /** RGB values per vertex in fold's result. */
    std::function<std::size_t(const Material&)> foldedStride;
    /** Adds the uniforms the environment shader needs beyond the material's StateSet and the
     *  common ones (e.g. a size its loops run to); empty: none. */
    std::function<void(const Material&, osg::StateSet&)> addUniforms;
};

}  // namespace osgBTF
