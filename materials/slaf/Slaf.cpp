#include "materials/slaf/Slaf.h"

#include "core/Error.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"
#include "materials/laf/Lobes.h"

namespace osgBTF {

// ---- T (LobeMethod's hooks) ------------------------------------------------------------------

void SlafMaterial::initExtra() {
    scale = StoredValues(MaterialTexture::Half, texelCount() * _views.size() * 3, 1.0f);
    _viewLookup = DirectionLookup(_views);
}

void SlafMaterial::checkFile(const FittedMaterial& file) const {
    if (_views.size() == 0) fail(file.source, "slaf needs at least one view direction");
}

void SlafMaterial::readExtra(FittedMaterial& file) {
    scale = readTexture(file, "scale", int(_views.size()), 3, MaterialTexture::Half);
    _viewLookup = DirectionLookup(_views);
}

void SlafMaterial::writeExtra(FittedMaterial& file) const {
    file.textures.push_back(scale.texture("scale", _width, _height, int(_views.size()), 3));
}

void SlafMaterial::addExtraState(osg::StateSet& stateSet) const {
    // T as a 2D array, one layer per measured view (81 or 151 layers, well below GL's 2048; an
    // array with one view too, as the shader samples it).
    addTexture(
        stateSet,
        createFloatTextureArray(scale.texture("scale", _width, _height, int(_views.size()), 3))
            .get(),
        "slafScale", 3);
    _viewLookup.addToStateSet(stateSet, "slafViewTable", 4);
}

// ---- CPU evaluator ---------------------------------------------------------------------------

glm::vec3 SlafMaterial::evaluate(int x, int y, const glm::vec3& view,
                                 const glm::vec3& light) const {
    const std::size_t t = std::size_t(y) * _width + x, texels = texelCount();
    // The same interpolation and blend order as slaf.frag.
    const InterpolationWeights w = _viewLookup.weights(view);
    glm::vec3 T(0.0f);
    for (int i = 0; i < 3; ++i) {
        const std::size_t s = (std::size_t(w.index[i]) * texels + t) * 3;
        T += w.weight[i] * glm::vec3(scale[s], scale[s + 1], scale[s + 2]);
    }
    return T * bracket(t, view, light);
}

void SlafMaterial::evaluateMeasured(std::size_t t, float* abrdf) const {
    const std::size_t texels = texelCount();
    for (std::size_t v = 0; v < _views.size(); ++v) {
        const glm::vec3 view = _views.vector(v);
        const std::size_t s = (v * texels + t) * 3;
        const glm::vec3 T(scale[s], scale[s + 1], scale[s + 2]);
        for (std::size_t l = 0; l < _lights.size(); ++l) {
            const glm::vec3 value = T * bracket(t, view, _lights.vector(l));
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
    }
}

// ---- registration ------------------------------------------------------------------------------

namespace {
const bool slafRegistered = registerMethodClass<SlafMaterial>([] {
    MethodInfo m;
    m.description =
        "scaled Lafortune lobes (Daubert): T(v) * (rho_d + rho_s * sum_k (C . v*l)^n), T an RGB "
        "table over the measured views; 257 values / 508 bytes per texel at 81 views, 2 lobes";
    m.options = {
        OptionSpec::integer("lobes", 2, 1, lobes::kMaxLobes, "number of Lafortune lobes"),
        OptionSpec::integer("iterations", 50, 1, 500,
                            "Levenberg-Marquardt iterations per texel and round"),
        OptionSpec::integer("rounds", 2, 0, 10,
                            "alternations between the view table T and the lobes"),
        OptionSpec::flag(
            "cosine", true,
            "1: the bracket times l_z; 0: Meseth et al. 2003, eq. 4, literally (see laf)")};
    m.shaderCost = [](const Material& material) {
        // View lookup; T: 3 multiply-adds and 3 fetches; v*l 1; lobes as LAF; bracket 5; T* 1.
        const SlafMaterial& m = static_cast<const SlafMaterial&>(material);
        const int k = m.lobeCount();
        const DirectionLookup::Cost v = m.viewLookup().cost();
        return ShaderCost::ofEvaluate(
            v.alu + 6 + 1 + 6 * k + 5 + 1, v.tex + 3 + k + 2,
            "ALU 6k+23+L, TEX k+5+T (k lobes; L = " + std::to_string(v.alu) +
                ", T = " + std::to_string(v.tex) + ": the view lookup)");
    };
    m.order = 20;
    return m;
}());
}  // namespace

}  // namespace osgBTF
