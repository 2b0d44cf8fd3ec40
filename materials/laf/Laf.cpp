#include "materials/laf/Laf.h"

#include "core/Error.h"
#include "materials/MaterialMath.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"
#include "materials/laf/Lobes.h"

namespace osgBTF {

// ---- model -----------------------------------------------------------------------------------

osg::ref_ptr<LafMaterial> LafMaterial::create(int width, int height, int lobeCount,
                                              const DirectionSet& views,
                                              const DirectionSet& lights) {
    osg::ref_ptr<LafMaterial> m = new LafMaterial;
    m->setGeometry(width, height, views, lights);
    m->initLobes(lobeCount);
    return m;
}

// ---- CPU evaluator ---------------------------------------------------------------------------

glm::vec3 LafMaterial::evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const {
    return bracket(std::size_t(y) * _width + x, view, light);
}

// ---- memory, save / load ---------------------------------------------------------------------

MemoryFootprint LafMaterial::memory() const {
    // Counted from the textures as stored, so the numbers follow their declared storage kinds.
    return footprintOf(toFittedMaterial(), texelCount());
}

FittedMaterial LafMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    writeLobes(file);
    return file;
}

osg::ref_ptr<LafMaterial> LafMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<LafMaterial> m = new LafMaterial;
    m->readCommon(file);
    m->readLobeParameters(file);
    m->readLobeTextures(file);
    return m;
}

// ---- StateSet --------------------------------------------------------------------------------

osg::ref_ptr<osg::StateSet> LafMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addLobeState(*stateSet, kMethod);
    return stateSet;
}

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
