// LPCA model: CPU evaluator, memory accounting, file I/O, StateSet and registration. The fit is in
// LpcaFit.cpp (the only translation unit that instantiates Eigen's eigensolver).
#include "materials/lpca/Lpca.h"
#include "materials/CoordinateMapRendering.h"

#include <cmath>

#include <osg/Uniform>

#include "core/Error.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

osg::ref_ptr<LpcaMaterial> LpcaMaterial::ofShape(int width, int height, const DirectionSet& views,
                                                 const DirectionSet& lights, int clusters,
                                                 int components) {
    osg::ref_ptr<LpcaMaterial> m = new LpcaMaterial;
    m->setGeometry(width, height, views, lights);
    m->clusterOf.assign(m->texelCount(), 0);
    m->weights = StoredValues(MaterialTexture::Half, lpcaWeightCount(m->texelCount(), components));
    m->eigenBrdfs = StoredValues(MaterialTexture::Half,
                                 std::size_t(clusters) * components * m->eigenBrdfSize());
    m->finishSetup(clusters, components);
    return m;
}

void LpcaMaterial::finishSetup(int clusters, int components) {
    if (clusters < 1 || clusters > 256 || components < 1)
        throw Error("lpca: invalid model shape (" + std::to_string(clusters) + " clusters, " +
                    std::to_string(components) + " components)");
    _clusters = clusters;
    _components = components;
    if (clusterOf.size() != texelCount() ||
        weights.size() != lpcaWeightCount(texelCount(), components) ||
        eigenBrdfs.size() != std::size_t(clusters) * components * eigenBrdfSize())
        throw Error("lpca: array sizes do not match the model's shape");
    _viewLookup = DirectionLookup(_views);
    _lightLookup = _lights == _views ? _viewLookup : DirectionLookup(_lights);
}

glm::vec3 LpcaMaterial::evaluate(int x, int y, const glm::vec3& view,
                                 const glm::vec3& light) const {
    // The shader's arithmetic, in its order: per component the 3x3 interpolated Eigen-BRDF value,
    // then the weighted sum (lpca.frag).
    const std::size_t t = std::size_t(y) * _width + x;
    const InterpolationWeights wv = _viewLookup.weights(view);
    const InterpolationWeights wl = _lightLookup.weights(light);
    const int k = clusterOf[t];
    glm::vec3 sum(0.0f);
    for (int i = 0; i < _components; ++i) {
        glm::vec3 value(0.0f);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b) {
                const std::size_t rgb =
                    eigenBrdfRun(k, i, std::size_t(wv.index[a])) + std::size_t(wl.index[b]) * 3;
                value += (wv.weight[a] * wl.weight[b]) *
                         glm::vec3(eigenBrdfs[rgb], eigenBrdfs[rgb + 1], eigenBrdfs[rgb + 2]);
            }
        sum += weight(t, i) * value;
    }
    return sum;
}

float LpcaMaterial::weight(std::size_t texel, int i) const {
    return weights[lpcaWeightIndex(texelCount(), texel, i)];
}

void LpcaMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    const std::size_t n = eigenBrdfSize();
    std::fill(abrdf, abrdf + n, 0.0f);
    const int k = clusterOf[texel];
    const std::size_t run = _lights.size() * 3;
    for (int i = 0; i < _components; ++i) {
        const float w = weight(texel, i);
        for (std::size_t v = 0; v < _views.size(); ++v) {
            const std::size_t e = eigenBrdfRun(k, i, v);
            float* out = abrdf + v * run;
            for (std::size_t j = 0; j < run; ++j) out[j] += w * eigenBrdfs[e + j];
        }
    }
}

MemoryFootprint LpcaMaterial::memory() const {
    // Meseth et al. 2003 Table 2 counts: per texel the cluster index (8-bit) and c weights (half);
    // per cluster c Eigen-BRDFs of V*L*3 half values, shared by all texels.
    const double texels = double(texelCount());
    // The weights' padding to groups of 4 is not counted (the model has c weights).
    const std::size_t weightCount = texelCount() * std::size_t(_components);
    const double perTexelValues = double(clusterOf.size() + weightCount) / texels;
    const double sharedValues = double(eigenBrdfs.size()) / texels;
    const std::uint64_t bytes =
        std::uint64_t(clusterOf.size()) * 1 + std::uint64_t(weightCount) * 2 + eigenBrdfs.bytes();
    return {perTexelValues + sharedValues, double(bytes) / texels, bytes};
}

// ---- options, shared with lpca-revised ----------------------------------------------------------

std::vector<OptionSpec> LpcaSettings::optionTable() {
    const LpcaSettings d;
    return {OptionSpec::integer("clusters", d.clusters, 1, 256,
                                "number of clusters k (the index is stored in 8 bits)"),
            OptionSpec::integer("components", d.components, 1, OptionSpec::kNoLimit,
                                "Eigen-BRDFs per cluster c"),
            OptionSpec::integer("iterations", d.iterations, 1, OptionSpec::kNoLimit,
                                "maximum Lloyd iterations of the clustering"),
            OptionSpec::integer("training", d.trainingTexels, 0, OptionSpec::kNoLimit,
                                "texels sampled to train the clusters, 0 = all"),
            OptionSpec::integer("seed", int(d.seed), 0, OptionSpec::kNoLimit,
                                "random seed of the training sample")};
}

// ---- textures shared with lpca-revised ----------------------------------------------------------

osg::ref_ptr<osg::Texture> createTextureArray(const MaterialTexture& t) {
    return createFloatTextureArray(t);
}

MaterialTexture lpcaClusterTexture(int width, int height,
                                   const std::vector<std::uint8_t>& clusterOf) {
    MaterialTexture t{"cluster", width, height, 1, 1, MaterialTexture::UNorm8, {}};
    t.bytes = clusterOf;  // index k is the 8-bit value k / 255
    return t;
}

MaterialTexture lpcaWeightTexture(int width, int height, int components,
                                  const StoredValues& weights) {
    return weights.texture("weights", width, height, (components + 3) / 4, 4);
}

std::vector<std::uint8_t> lpcaClusterFromTexture(FittedMaterial& file, int clusters) {
    MaterialTexture& t = file.texture("cluster");
    if (t.channels != 1 || t.depth != 1 || t.kind != MaterialTexture::UNorm8)
        fail(file.source, "texture 'cluster' must be one 8-bit channel");
    // The file's bytes are taken as they are (kLoadsBytes); values read as floats are rounded.
    std::vector<std::uint8_t> clusterOf = std::move(t.bytes);
    if (clusterOf.empty()) clusterOf.resize(t.storedCount());
    for (std::size_t i = 0; i < clusterOf.size(); ++i) {
        const long k = t.data.empty() ? long(clusterOf[i]) : std::lround(t.data[i] * 255.0f);
        if (k < 0 || k >= clusters)
            fail(file.source, "cluster index " + std::to_string(k) + " out of range (" +
                                  std::to_string(clusters) + " clusters)");
        clusterOf[i] = std::uint8_t(k);
    }
    t = MaterialTexture{t.name, t.width, t.height, t.depth, t.channels, t.kind, {}};
    return clusterOf;
}

StoredValues lpcaWeightsFromTexture(FittedMaterial& file, int components) {
    MaterialTexture& t = file.texture("weights");
    if (t.channels != 4 || t.depth != (components + 3) / 4)
        fail(file.source, "texture 'weights' must have " + std::to_string((components + 3) / 4) +
                              " RGBA layers for " + std::to_string(components) + " components");
    return StoredValues::take(t, MaterialTexture::Half);
}

// ---- file ------------------------------------------------------------------------------------

FittedMaterial LpcaMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["clusters"] = std::to_string(_clusters);
    file.parameters["components"] = std::to_string(_components);
    file.textures.push_back(lpcaClusterTexture(_width, _height, clusterOf));
    file.textures.push_back(lpcaWeightTexture(_width, _height, _components, weights));
    // One layer per cluster; rows: view-major then component, columns: lights. The same
    // layout as the GPU texture, within GL limits for Bonn (81 x 81c) and UBO2014 (151 x 151c).
    file.textures.push_back(eigenBrdfs.texture("eigenBrdfs", int(_lights.size()),
                                               int(_views.size()) * _components, _clusters, 3));
    return file;
}

osg::ref_ptr<LpcaMaterial> LpcaMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<LpcaMaterial> m = new LpcaMaterial;
    m->readCommon(file);
    int clusters = 0, components = 0;
    try {
        clusters = std::stoi(file.parameter("clusters"));
        components = std::stoi(file.parameter("components"));
    } catch (const std::invalid_argument&) {
        fail(file.source, "clusters/components parameters are not integers");
    }
    if (clusters < 1 || clusters > 256 || components < 1)
        fail(file.source, "invalid clusters/components");
    MaterialTexture& e = file.texture("eigenBrdfs");  // the file is ours: its values are taken
    const std::size_t views = m->_views.size(), lights = m->_lights.size();
    if (e.width != int(lights) || e.height != int(views) * components || e.depth != clusters ||
        e.channels != 3)
        fail(file.source, "texture 'eigenBrdfs' does not match the directions and shape");
    m->clusterOf = lpcaClusterFromTexture(file, clusters);
    m->weights = lpcaWeightsFromTexture(file, components);
    const std::size_t expected =
        std::size_t(clusters) * views * std::size_t(components) * lights * 3;
    if (e.storedCount() != expected)
        fail(file.source, "texture 'eigenBrdfs' holds " + std::to_string(e.storedCount()) +
                              " values, " + std::to_string(expected) + " expected");
    m->eigenBrdfs = StoredValues::take(e, MaterialTexture::Half);
    try {
        m->finishSetup(clusters, components);
    } catch (const Error& error) {
        fail(file.source, error.what());
    }
    return m;
}

// ---- GPU -------------------------------------------------------------------------------------

osg::ref_ptr<osg::StateSet> LpcaMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    const FittedMaterial file = toFittedMaterial();
    addTexture(*stateSet, createFloatTexture(file.texture("cluster")).get(), "lpcaCluster", 0);
    addTexture(*stateSet, createTextureArray(file.texture("weights")).get(), "lpcaWeights", 1);
    addTexture(*stateSet, createTextureArray(file.texture("eigenBrdfs")).get(), "lpcaEigenBrdfs",
               2);
    _viewLookup.addToStateSet(*stateSet, "lpcaViewTable", 3);
    _lightLookup.addToStateSet(*stateSet, "lpcaLightTable", 4);
    stateSet->addUniform(new osg::Uniform("lpcaComponents", _components));
    return stateSet;
}

namespace {
const bool lpcaRegistered = registerMethodClass<LpcaMaterial>([] {
    MethodInfo m;
    m.description =
        "local PCA (Mueller 2003): per texel a cluster index and c weights of its cluster's "
        "Eigen-BRDFs, 3x3 view/light interpolation";
    m.options = LpcaSettings::optionTable();
    m.shaderCost = [](const Material& material) {
        // Cluster fetch and decode 2; two lookups; per component: alpha address 2 and fetch,
        // 9 x (weight product, row index 2, multiply-add 2, one fetch), weighted add 2.
        const LpcaMaterial& m = static_cast<const LpcaMaterial&>(material);
        const int c = m.components();
        const DirectionLookup::Cost v = m.viewLookup().cost(), l = m.lightLookup().cost();
        return ShaderCost::ofEvaluate(
            2 + v.alu + l.alu + 49 * c, 1 + v.tex + l.tex + 10 * c,
            "ALU 49c+12+L, TEX 10c+1+T (c components; L = " + std::to_string(v.alu + l.alu) +
                ", T = " + std::to_string(v.tex + l.tex) + ": view and light lookups)");
    };
    // Linear in the light weights; the fragment folds g into its own cluster's Eigen-BRDFs
    // (LpcaEnvironment.cpp, lpca_environment.frag), which loop over the lights.
    EnvironmentHooks environment;
    environment.fold = [](const Material& material, const std::vector<glm::vec3>& g) {
        return foldLpca(static_cast<const LpcaMaterial&>(material), g);
    };
    environment.evaluateFolded = [](const Material& material, const std::vector<float>& folded,
                                    int x, int y, const glm::vec3& view) {
        return evaluateFoldedLpca(static_cast<const LpcaMaterial&>(material), folded, x, y, view);
    };
    environment.foldedStride = [](const Material& material) {
        return material.lights().size() * 3;
    };
    environment.addUniforms = [](const Material& material, osg::StateSet& stateSet) {
        stateSet.addUniform(new osg::Uniform("lpcaLights", int(material.lights().size())));
    };
    m.environment = std::move(environment);
    // What the .btf/.zip plugins fit when the options name no method (docs/scene-graph.md).
    m.pluginDefault = true;
    m.order = 50;
    // A training matrix and its projection: 663 MiB peak for a 48x48 sample (173 MiB of values).
    m.fitWorkingSet = 2.25;
    m.fitWorkingSetFullSizeGiB = 6;  // bench/fit_ubo2014.sh's bound at 400 x 400
    m.quickFitOptions = "clusters=2 components=2";
    return m;
}());
}  // namespace

// The tables every texel shares; the other textures are per texel (remapMaterial).
[[maybe_unused]] const bool lpcaSharedTexturesDeclared =
    declareSharedTextures(LpcaMaterial::kMethod, {"eigenBrdfs"});

}  // namespace osgBTF
