#include "materials/lpca-revised/LpcaRevised.h"
#include "materials/CoordinateMapRendering.h"

#include <algorithm>
#include <cmath>
#include <set>
#include <sstream>

#include <osg/Uniform>

#include "core/Error.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"
#include "materials/lpca-revised/ConcentricMap.h"

namespace osgBTF {

void LpcaRevisedMaterial::finishSetup() {
    if (_clusters < 1 || _clusters > 256 || _components < 1 || _resolution < 2)
        throw Error("lpca-revised: invalid model shape");
    if (clusterOf.size() != texelCount() ||
        weights.size() != lpcaWeightCount(texelCount(), weightsPerTexel()) ||
        grid.size() != std::size_t(gridWidth()) * gridHeight() * gridDepth() * 3)
        throw Error("lpca-revised: array sizes do not match the model's shape");
    _viewParams.clear();
    _lightParams.clear();
    for (std::size_t v = 0; v < _views.size(); ++v)
        _viewParams.push_back(glm::vec2(elevatedConcentricInverse(glm::dvec3(_views.vector(v)))));
    for (std::size_t l = 0; l < _lights.size(); ++l)
        _lightParams.push_back(glm::vec2(elevatedConcentricInverse(glm::dvec3(_lights.vector(l)))));
}

// ---- CPU evaluator: the shader's arithmetic -----------------------------------------------------

glm::vec3 LpcaRevisedMaterial::trilinear(float x, float y, float z) const {
    // GL's LINEAR filter with CLAMP_TO_EDGE: texel centres at integer + 0.5.
    const int size[3] = {gridWidth(), gridHeight(), gridDepth()};
    const float p[3] = {x - 0.5f, y - 0.5f, z - 0.5f};
    int i0[3], i1[3];
    float f[3];
    for (int a = 0; a < 3; ++a) {
        const float fl = std::floor(p[a]);
        f[a] = p[a] - fl;
        i0[a] = std::clamp(int(fl), 0, size[a] - 1);
        i1[a] = std::clamp(int(fl) + 1, 0, size[a] - 1);
    }
    glm::vec3 sum(0.0f);
    for (int corner = 0; corner < 8; ++corner) {
        const int ix = corner & 1 ? i1[0] : i0[0], iy = corner & 2 ? i1[1] : i0[1],
                  iz = corner & 4 ? i1[2] : i0[2];
        const float w = (corner & 1 ? f[0] : 1 - f[0]) * (corner & 2 ? f[1] : 1 - f[1]) *
                        (corner & 4 ? f[2] : 1 - f[2]);
        const std::size_t rgb = ((std::size_t(iz) * size[1] + iy) * size[0] + ix) * 3;
        sum += w * glm::vec3(grid[rgb], grid[rgb + 1], grid[rgb + 2]);
    }
    return sum;
}

glm::vec3 LpcaRevisedMaterial::evaluateAt(std::size_t texel, const glm::vec2& sv,
                                          const glm::vec2& sl) const {
    const float n = float(_resolution);
    const float x = float(clusterOf[texel]) * n + std::clamp(sv.x * n, 0.5f, n - 0.5f);
    const float yInBlock = std::clamp(sv.y * n, 0.5f, n - 0.5f);
    const float u = std::clamp(sl.y * n - 0.5f, 0.0f, n - 1.0f);
    const int slab = std::min(int(std::floor(u)), _resolution - 2);
    const float w = u - float(slab);
    const float z1 = float(slab) * n + std::clamp(sl.x * n, 0.5f, n - 0.5f), z2 = z1 + n;
    glm::vec3 sum(0.0f);
    for (int i = 0; i < _components; ++i) {
        const float y = float(i) * n + yInBlock;
        const glm::vec3 a = trilinear(x, y, z1), b = trilinear(x, y, z2);
        sum += weight(texel, i) * (a + (b - a) * w);
    }
    if (_eightBit) sum += glm::vec3(weight(texel, _components));
    return sum;
}

glm::vec3 LpcaRevisedMaterial::evaluate(int x, int y, const glm::vec3& view,
                                        const glm::vec3& light) const {
    return evaluateAt(std::size_t(y) * _width + x,
                      glm::vec2(elevatedConcentricInverse(glm::dvec3(view))),
                      glm::vec2(elevatedConcentricInverse(glm::dvec3(light))));
}

void LpcaRevisedMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    for (std::size_t v = 0; v < _viewParams.size(); ++v)
        for (std::size_t l = 0; l < _lightParams.size(); ++l) {
            const glm::vec3 value = evaluateAt(texel, _viewParams[v], _lightParams[l]);
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
}

MemoryFootprint LpcaRevisedMaterial::memory() const {
    const double texels = double(texelCount());
    // The weights' padding to groups of 4 is not counted.
    const std::size_t weightCount = texelCount() * std::size_t(weightsPerTexel());
    const std::uint64_t bytes =
        std::uint64_t(clusterOf.size()) + std::uint64_t(weightCount) * 2 + grid.bytes();
    return {double(clusterOf.size() + weightCount + grid.size()) / texels, double(bytes) / texels,
            bytes};
}

// ---- file ------------------------------------------------------------------------------------

FittedMaterial LpcaRevisedMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["clusters"] = std::to_string(_clusters);
    file.parameters["components"] = std::to_string(_components);
    file.parameters["resolution"] = std::to_string(_resolution);
    file.parameters["storage"] = _eightBit ? "unorm8" : "half";
    file.textures.push_back(lpcaClusterTexture(_width, _height, clusterOf));
    file.textures.push_back(lpcaWeightTexture(_width, _height, weightsPerTexel(), weights));
    file.textures.push_back(grid.texture("grid", gridWidth(), gridHeight(), gridDepth(), 3));
    return file;
}

osg::ref_ptr<LpcaRevisedMaterial> LpcaRevisedMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<LpcaRevisedMaterial> m = new LpcaRevisedMaterial;
    m->readCommon(file);
    try {
        m->_clusters = std::stoi(file.parameter("clusters"));
        m->_components = std::stoi(file.parameter("components"));
        m->_resolution = std::stoi(file.parameter("resolution"));
    } catch (const std::invalid_argument&) {
        fail(file.source, "clusters/components/resolution parameters are not integers");
    }
    const std::string& storage = file.parameter("storage");
    if (storage != "half" && storage != "unorm8")
        fail(file.source, "unknown storage '" + storage + "'");
    m->_eightBit = storage == "unorm8";
    if (m->_clusters < 1 || m->_clusters > 256 || m->_components < 1 || m->_resolution < 2)
        fail(file.source, "invalid clusters/components/resolution");
    MaterialTexture& g = file.texture("grid");  // the file is ours: its values are taken
    if (g.width != m->gridWidth() || g.height != m->gridHeight() || g.depth != m->gridDepth() ||
        g.channels != 3)
        fail(file.source, "texture 'grid' does not match clusters, components and resolution");
    m->clusterOf = lpcaClusterFromTexture(file, m->_clusters);
    m->weights = lpcaWeightsFromTexture(file, m->weightsPerTexel());
    m->grid = StoredValues::take(g, m->_eightBit ? MaterialTexture::UNorm8 : MaterialTexture::Half);
    try {
        m->finishSetup();
    } catch (const Error& error) {
        fail(file.source, error.what());
    }
    return m;
}

// ---- GPU -------------------------------------------------------------------------------------

osg::ref_ptr<osg::StateSet> LpcaRevisedMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addTexture(*stateSet, createFloatTexture(lpcaClusterTexture(_width, _height, clusterOf)).get(),
               "lpcaRevisedCluster", 0);
    addTexture(
        *stateSet,
        createTextureArray(lpcaWeightTexture(_width, _height, weightsPerTexel(), weights)).get(),
        "lpcaRevisedWeights", 1);
    addTexture(
        *stateSet,
        createFloatTexture3D(grid.texture("grid", gridWidth(), gridHeight(), gridDepth(), 3), true)
            .get(),
        "lpcaRevisedGrid", 2);
    stateSet->addUniform(new osg::Uniform("lpcaRevisedComponents", _components));
    stateSet->addUniform(new osg::Uniform("lpcaRevisedResolution", _resolution));
    stateSet->addUniform(new osg::Uniform("lpcaRevisedOffset", _eightBit ? 1 : 0));
    return stateSet;
}

namespace {
const bool lpcaRevisedRegistered = registerMethodClass<LpcaRevisedMaterial>([] {
    MethodInfo m;
    m.description =
        "revised local PCA (Schneider 2004): LPCA Eigen-BRDFs resampled over the elevated "
        "concentric map into one filtered 3D texture, 2 fetches + 1 lerp per component";
    m.options = LpcaSettings::optionTable();
    // n^2 <= 2048 (the 3D texture's depth): n <= 45.
    m.options.push_back(
        OptionSpec::integer("resolution", 16, 2, 45, "grid samples per direction parameter n"));
    m.options.push_back(OptionSpec::choice("storage", "half", {"half", "unorm8"},
                                           "grid precision (unorm8: the scales are folded into "
                                           "the weights)"));
    m.shaderCost = [](const Material& material) {
        // Cluster 2; two concentric maps 17 each; grid coordinates 22; per component: row 2, two
        // filtered 3D fetches with their scaling 2, weight address 2 and fetch, mix, multiply-add
        // 2; offset test 1 (+3 and a fetch when the grid is 8-bit).
        const auto& revised = static_cast<const LpcaRevisedMaterial&>(material);
        const int c = revised.components();
        const bool offset = revised.eightBit();
        return ShaderCost::ofEvaluate(58 + 9 * c + 1 + (offset ? 3 : 0),
                                      1 + 3 * c + (offset ? 1 : 0),
                                      offset ? "ALU 9c+72, TEX 3c+2 (c components, 8-bit)"
                                             : "ALU 9c+69, TEX 3c+1 (c components)");
    };
    m.order = 60;
    // Peaks of 577 and 715 MiB for 24x24 and 48x48 samples (43 and 173 MiB of values): ~1.06x
    // the values and ~380 MiB of tables beyond the program.
    m.fitWorkingSet = 1.25;
    m.fitTablesMiB = 450;
    m.fitWorkingSetFullSizeGiB = 6;
    m.quickFitOptions = "clusters=2 components=2 resolution=4";
    return m;
}());
}  // namespace

// The tables every texel shares; the other textures are per texel (remapMaterial).
[[maybe_unused]] const bool lpcaRevisedSharedTexturesDeclared =
    declareSharedTextures(LpcaRevisedMaterial::kMethod, {"grid"});

}  // namespace osgBTF
