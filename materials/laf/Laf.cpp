#include "materials/laf/Laf.h"

#include "materials/MethodRegistry.h"
#include "materials/laf/Lobes.h"

namespace osgBTF {

// ---- CPU evaluator ---------------------------------------------------------------------------

glm::vec3 LafMaterial::evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const {
    return bracket(std::size_t(y) * _width + x, view, light);
}

// ---- registration (create, memory, file and StateSet: LobeMethod's) ---------------------------

namespace {
const bool lafRegistered = registerMethodClass<LafMaterial>([] {
    MethodInfo m;
    m.description =
        "Lafortune lobes per texel (McAllister): rho_d + rho_s * sum_k (C . v*l)^n; RGB albedos, "
        "luminance lobes; 14 values / 22 bytes per texel at 2 lobes";
    m.options = {
        OptionSpec::integer("lobes", 2, 1, lobes::kMaxLobes, "number of Lafortune lobes"),
        OptionSpec::integer("iterations", 50, 1, 500, "Levenberg-Marquardt iterations per texel"),
        OptionSpec::flag("cosine", true,
                         "1: the bracket times l_z, the BRDF model times the foreshortening the "
                         "data contain; 0: Meseth et al. 2003, eq. 2, literally, no l_z")};
    m.shaderCost = [](const Material& material) {
        // v*l 1; per lobe: row index 2, dot, test, pow, add; bracket 5. Fetches: lobes + rhoD,
        // rhoS.
        const int k = static_cast<const LafMaterial&>(material).lobeCount();
        return ShaderCost::ofEvaluate(6 + 6 * k, k + 2, "ALU 6k+16, TEX k+2 (k lobes)");
    };
    m.order = 10;
    return m;
}());
}  // namespace

}  // namespace osgBTF
