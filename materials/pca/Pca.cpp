#include "materials/pca/Pca.h"
#include "materials/CoordinateMapRendering.h"

#include <algorithm>
#include <cmath>

#include <osg/Uniform>

#include "core/Error.h"
#include "materials/MaterialMath.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

void PcaMaterial::setShape(int width, int height, const DirectionSet& views,
                           const DirectionSet& lights, int components,
                           MaterialTexture::PixelKind storage) {
    if (width <= 0 || height <= 0) throw Error("pca: invalid texel size");
    if (components < 1) throw Error("pca: components must be at least 1");
    if (views.size() > std::size_t(kMaxArrayLayers) || lights.size() > kMaxTextureSize)
        throw Error("pca: " + std::to_string(views.size()) + " views x " +
                    std::to_string(lights.size()) + " lights exceed the GPU's texture limits (" +
                    std::to_string(kMaxArrayLayers) + " array layers)");
    const int columns = std::max(1, std::min(components, kMaxTextureSize / width));
    const int rows = (components + columns - 1) / columns;
    if (width > kMaxTextureSize || std::int64_t(rows) * height > kMaxTextureSize)
        throw Error("pca: " + std::to_string(width) + "x" + std::to_string(height) +
                    " texels with " + std::to_string(components) +
                    " components do not fit a texture of " + std::to_string(kMaxTextureSize) + "x" +
                    std::to_string(kMaxTextureSize));
    setGeometry(width, height, views, lights);
    _components = components;
    _tileColumns = columns;
    eigenTextures = {
        "eigenTextures", columns * width, rows * height, int(views.size()), 3, storage, {}};
    weights = {
        "weights", components + 1, int(lights.size()), int(views.size()), 3, MaterialTexture::Float,
        {}};
}

void PcaMaterial::prepareLookups() {
    _viewLookup = DirectionLookup(_views);
    _lightLookup = _lights == _views ? _viewLookup : DirectionLookup(_lights);
}

glm::vec3 PcaMaterial::combination(int x, int y, std::size_t view, std::size_t light) const {
    const float* w = weights.data.data() + weightIndex(view, light, 0);
    const float* bias = w + std::size_t(_components) * 3;
    glm::vec3 sum(bias[0], bias[1], bias[2]);
    for (int k = 0; k < _components; ++k)
        sum += glm::vec3(w[k * 3], w[k * 3 + 1], w[k * 3 + 2]) * eigenTexel(view, k, x, y);
    return sum;
}

glm::vec3 PcaMaterial::evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const {
    // The shader's loop: 3 view x 3 light neighbours of the exact interpolation.
    const InterpolationWeights wv = _viewLookup.weights(view);
    const InterpolationWeights wl = _lightLookup.weights(light);
    glm::vec3 sum(0.0f);
    for (int i = 0; i < 3; ++i) {
        if (!(wv.weight[i] > 0.0f)) continue;
        for (int j = 0; j < 3; ++j) {
            const float w = wv.weight[i] * wl.weight[j];
            if (!(w > 0.0f)) continue;
            sum += w * combination(x, y, std::size_t(wv.index[i]), std::size_t(wl.index[j]));
        }
    }
    return sum;
}

void PcaMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    const int x = int(texel % std::size_t(_width)), y = int(texel / std::size_t(_width));
    for (std::size_t v = 0; v < _views.size(); ++v)
        for (std::size_t l = 0; l < _lights.size(); ++l) {
            const glm::vec3 value = combination(x, y, v, l);
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
}

PcaMaterial::MemoryBreakdown PcaMaterial::memoryBreakdown() const {
    const double texels = double(texelCount());
    MemoryBreakdown m;
    m.perTexelValues = double(eigenTextures.valueCount()) / texels;
    m.perTexelBytes = m.perTexelValues * bytesPerValue(eigenTextures.kind);
    m.sharedValues = double(weights.valueCount()) / texels;
    m.sharedBytes = m.sharedValues * bytesPerValue(weights.kind);
    return m;
}

MemoryFootprint PcaMaterial::memory() const {
    const MemoryBreakdown m = memoryBreakdown();
    const double bytes = double(eigenTextures.valueCount()) * bytesPerValue(eigenTextures.kind) +
                         double(weights.valueCount()) * bytesPerValue(weights.kind);
    return {m.perTexelValues + m.sharedValues, m.perTexelBytes + m.sharedBytes,
            std::uint64_t(bytes)};
}

FittedMaterial PcaMaterial::toFittedMaterial() const {
    return osg::ref_ptr<PcaMaterial>(new PcaMaterial(*this))->releaseFittedMaterial();
}

FittedMaterial PcaMaterial::releaseFittedMaterial() {
    FittedMaterial file = writeCommon();
    file.parameters["components"] = std::to_string(_components);
    file.parameters["tileColumns"] = std::to_string(_tileColumns);
    file.textures.push_back(std::move(eigenTextures));
    file.textures.push_back(std::move(weights));
    eigenTextures = {};
    weights = {};
    return file;
}

osg::ref_ptr<PcaMaterial> PcaMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<PcaMaterial> m = new PcaMaterial;
    m->readCommon(file);
    int components = 0;
    try {
        components = std::stoi(file.parameter("components"));
    } catch (const std::logic_error&) {
        fail(file.source, "parameter 'components' is not an integer");
    }
    // The file is this function's own: its arrays are taken, not copied.
    MaterialTexture& eigen = file.texture("eigenTextures");
    MaterialTexture& w = file.texture("weights");
    try {
        m->setShape(m->_width, m->_height, file.views, file.lights, components, eigen.kind);
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    const auto check = [&](const MaterialTexture& expected, const MaterialTexture& got) {
        if (got.width != expected.width || got.height != expected.height ||
            got.depth != expected.depth || got.channels != expected.channels ||
            got.kind != expected.kind)
            fail(file.source,
                 "texture '" + expected.name + "' must be " + std::to_string(expected.width) + "x" +
                     std::to_string(expected.height) + "x" + std::to_string(expected.depth) +
                     " RGB " + MaterialTexture::kindName(expected.kind) + " for " +
                     std::to_string(components) + " components");
    };
    check(m->eigenTextures, eigen);
    check(m->weights, w);
    for (const MaterialTexture* t : {&eigen, &w})
        if (t->storedCount() != t->valueCount())
            fail(file.source, "texture '" + t->name + "' holds " +
                                  std::to_string(t->storedCount()) + " values, " +
                                  std::to_string(t->valueCount()) + " expected");
    if (eigen.kind == MaterialTexture::UNorm8 && eigen.bytes.empty()) {
        // Held as bytes like a fit's (values k / 255.0f: exact).
        m->eigenTextures.bytes.resize(eigen.valueCount());
        for (std::size_t i = 0; i < eigen.valueCount(); ++i)
            m->eigenTextures.bytes[i] = std::uint8_t(std::lround(eigen.value(i) * 255.0f));
    } else if (eigen.kind == MaterialTexture::UNorm8) {
        m->eigenTextures.bytes = std::move(eigen.bytes);
    } else {
        m->eigenTextures.data = std::move(eigen.data);
    }
    m->weights.data = std::move(w.data);
    m->prepareLookups();
    return m;
}

osg::ref_ptr<osg::StateSet> PcaMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    // Arrays even with one layer (one measured view): the shader's samplers are sampler2DArray.
    addTexture(*stateSet, createFloatTextureArray(eigenTextures).get(), "pcaEigenTextures", 0);
    addTexture(*stateSet, createFloatTextureArray(weights).get(), "pcaWeights", 1);
    _viewLookup.addToStateSet(*stateSet, "pcaViewTable", 2);
    _lightLookup.addToStateSet(*stateSet, "pcaLightTable", 3);
    stateSet->addUniform(new osg::Uniform("pcaComponents", _components));
    stateSet->addUniform(new osg::Uniform("pcaTileColumns", _tileColumns));
    return stateSet;
}

namespace {
const bool pcaRegistered = registerMethodClass<PcaMaterial>([] {
    MethodInfo m;
    m.description =
        "per-view Eigen-Textures (Sattler 2003): rank-c PCA of each view's light images, "
        "3x3 view/light interpolation; 3888 values / 3888 bytes per texel at 81 views, 16 "
        "components, unorm8";
    m.options = {
        OptionSpec::integer("components", 16, 1, OptionSpec::kNoLimit,
                            "Eigen-Textures per view (at most the lights, or 3 x texels if fewer)"),
        OptionSpec::choice("storage", "unorm8", {"unorm8", "half", "float"},
                           "Eigen-Texture precision: unorm8 is 1 byte per value, as Meseth et "
                           "al. 2003, Table 2, counts")};
    // Per-texel Eigen-Texture values times per-direction weights; pca.frag blends the four
    // texels itself (tiled components).
    m.filtersParameters = true;
    m.shaderCost = [](const Material& material) {
        // View + light lookups; 3 view-weight tests; per (view, light) pair (9): weight product
        // and test, bias fetch, per component: tile address 4, multiply-add 2 and 2 fetches;
        // weighted add 2.
        const PcaMaterial& m = static_cast<const PcaMaterial&>(material);
        const int c = m.components();
        const DirectionLookup::Cost v = m.viewLookup().cost(), l = m.lightLookup().cost();
        return ShaderCost::ofEvaluate(
            v.alu + l.alu + 3 + 9 * (4 + 6 * c), v.tex + l.tex + 9 * (1 + 2 * c),
            "ALU 54c+49+L, TEX 18c+9+T (c components; L = " + std::to_string(v.alu + l.alu) +
                ", T = " + std::to_string(v.tex + l.tex) + ": view and light lookups)");
    };
    // Linear in the light weights: an environment folds into each view's weights once per vertex
    // (PcaEnvironment.cpp, pca_environment.frag).
    EnvironmentHooks environment;
    environment.fold = [](const Material& material, const std::vector<glm::vec3>& g) {
        return foldPca(static_cast<const PcaMaterial&>(material), g);
    };
    environment.evaluateFolded = [](const Material& material, const std::vector<float>& folded,
                                    int x, int y, const glm::vec3& view) {
        return evaluateFoldedPca(static_cast<const PcaMaterial&>(material), folded, x, y, view);
    };
    environment.foldedStride = [](const Material& material) {
        const PcaMaterial& pca = static_cast<const PcaMaterial&>(material);
        return pca.views().size() * std::size_t(pca.components() + 1) * 3;
    };
    m.environment = std::move(environment);
    m.order = 40;
    // 337 MiB peak for a 48x48 sample (173 MiB of values); 2.72 GB at 400 x 400 from factors.
    m.fitWorkingSet = 0.75;
    m.quickFitOptions = "components=2";
    return m;
}());
}  // namespace

// The tables every texel shares; the other textures are per texel (remapMaterial).
[[maybe_unused]] const bool pcaSharedTexturesDeclared =
    declareSharedTextures(PcaMaterial::kMethod, {"weights"});

}  // namespace osgBTF
