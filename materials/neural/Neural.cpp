#include "materials/neural/Neural.h"

#include <algorithm>
#include <cmath>

#include <string>
#include <vector>

#include <glm/geometric.hpp>
#include <osg/Uniform>

#include "core/Error.h"
#include "materials/BilinearTaps.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

namespace {

/** The neuron's weighted sum: bias, then each group of 4 inputs as ((w.x x.x + w.y x.y) + w.z x.z)
 *  + w.w x.w added on; the shader's `sum += dot(w, x)` in the same order. */
float neuron(const float* row, const float* inputs, int count) {
    float sum = row[0];
    for (int c = 0; c < count; c += 4) {
        const float* w = row + 4 + c;
        sum +=
            w[0] * inputs[c] + w[1] * inputs[c + 1] + w[2] * inputs[c + 2] + w[3] * inputs[c + 3];
    }
    return sum;
}

}  // namespace

void NeuralMaterial::directionFeatures(const glm::vec3& view, const glm::vec3& light, float* out) {
    const glm::vec3 h = glm::normalize(view + light);
    out[0] = view.x;
    out[1] = view.y;
    out[2] = light.x;
    out[3] = light.y;
    out[4] = h.x;
    out[5] = h.y;
    out[6] = h.z;
    out[7] = light.z;
}

void NeuralMaterial::setShape(int width, int height, const DirectionSet& views,
                              const DirectionSet& lights, int latentSize, int hiddenLayers,
                              int units) {
    setGeometry(width, height, views, lights);
    setNetworkShape(latentSize, hiddenLayers, units);
}

void NeuralMaterial::setNetworkShape(int latentSize, int hiddenLayers, int units,
                                     bool allocateLatent) {
    if (latentSize < 4 || latentSize > kMaxLatent || latentSize % 4 != 0)
        throw Error("neural: the latent size must be a multiple of 4 in 4.." +
                    std::to_string(kMaxLatent) + ", got " + std::to_string(latentSize));
    if (hiddenLayers < 1 || hiddenLayers > kMaxHiddenLayers)
        throw Error("neural: the hidden layers must be 1.." + std::to_string(kMaxHiddenLayers) +
                    ", got " + std::to_string(hiddenLayers));
    if (units < 4 || units > kMaxUnits || units % 4 != 0)
        throw Error("neural: the units per layer must be a multiple of 4 in 4.." +
                    std::to_string(kMaxUnits) + ", got " + std::to_string(units));
    _latentSize = latentSize;
    _hiddenLayers = hiddenLayers;
    _units = units;
    latent = StoredValues(MaterialTexture::Half,
                          allocateLatent ? texelCount() * std::size_t(latentSize) : 0);
    const int columns = 1 + std::max(inputs(), units) / 4;
    decoder = {"decoder", columns, hiddenLayers * units + 3, 1, 4, MaterialTexture::Float, {}};
    decoder.data.assign(decoder.valueCount(), 0.0f);
}

glm::vec3 NeuralMaterial::decode(const float* inputs) const {
    float buffers[2][kMaxUnits];
    const float* in = inputs;
    for (int k = 0; k < _hiddenLayers; ++k) {
        float* out = buffers[k % 2];
        for (int j = 0; j < _units; ++j)
            out[j] =
                std::max(neuron(&decoder.data[std::size_t(decoderRow(k, j)) * decoder.width * 4],
                                in, layerInputs(k)),
                         0.0f);
        in = out;
    }
    glm::vec3 rgb;
    for (int j = 0; j < 3; ++j)
        rgb[j] =
            neuron(&decoder.data[std::size_t(decoderRow(_hiddenLayers, j)) * decoder.width * 4], in,
                   _units);
    return rgb;
}

glm::vec3 NeuralMaterial::evaluate(int x, int y, const glm::vec3& view,
                                   const glm::vec3& light) const {
    float in[kMaxLatent + kDirectionFeatures];
    for (int i = 0; i < _latentSize; ++i) in[i] = latent[latentIndex(x, y, i)];
    directionFeatures(view, light, in + _latentSize);
    return decode(in) * light.z;
}

glm::vec3 NeuralMaterial::evaluateTaps(const FilterTaps& taps, const glm::vec3& view,
                                       const glm::vec3& light) const {
    // The shader's vec4 `z += w * texelFetch(...)` per group, tap by tap.
    float in[kMaxLatent + kDirectionFeatures] = {};
    for (int k = 0; k < taps.count; ++k) {
        const FilterTap& t = taps.taps[k];
        for (int i = 0; i < _latentSize; ++i) in[i] += t.weight * latent[latentIndex(t.x, t.y, i)];
    }
    directionFeatures(view, light, in + _latentSize);
    return decode(in) * light.z;
}

MemoryFootprint NeuralMaterial::memory() const {
    const double texels = double(_width) * _height;
    const std::uint64_t shared = std::uint64_t(decoder.valueCount()) * 4;
    const std::uint64_t perTexel = latent.bytes();
    return {double(_latentSize) + double(decoder.valueCount()) / texels,
            2.0 * _latentSize + double(shared) / texels, perTexel + shared, shared};
}

FittedMaterial NeuralMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["latent"] = std::to_string(_latentSize);
    file.parameters["layers"] = std::to_string(_hiddenLayers);
    file.parameters["units"] = std::to_string(_units);
    file.textures.push_back(latentTexture());
    file.textures.push_back(decoder);
    return file;
}

osg::ref_ptr<NeuralMaterial> NeuralMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<NeuralMaterial> m = new NeuralMaterial;
    m->readCommon(file);
    int shape[3];
    const char* keys[3] = {"latent", "layers", "units"};
    for (int i = 0; i < 3; ++i) {
        try {
            std::size_t used = 0;
            shape[i] = std::stoi(file.parameter(keys[i]), &used);
            if (used != file.parameter(keys[i]).size()) throw std::invalid_argument(keys[i]);
        } catch (const std::logic_error&) {
            fail(file.source, std::string("parameter '") + keys[i] + "' is not an integer");
        }
    }
    try {
        m->setNetworkShape(shape[0], shape[1], shape[2], false);  // the file's latents below
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    const MaterialTexture latentShape{
        "latent", m->_width, m->_height, m->_latentSize / 4, 4, MaterialTexture::Half, {}};
    const MaterialTexture* const shapes[] = {&latentShape, &m->decoder};
    for (const MaterialTexture* expected : shapes) {
        MaterialTexture& got = file.texture(expected->name);  // the file is ours: taken
        if (got.width != expected->width || got.height != expected->height ||
            got.depth != expected->depth || got.channels != expected->channels ||
            got.kind != expected->kind || got.storedCount() != expected->valueCount())
            fail(file.source, "texture '" + expected->name + "' must be " +
                                  std::to_string(expected->width) + "x" +
                                  std::to_string(expected->height) + "x" +
                                  std::to_string(expected->depth) + " RGBA " +
                                  (expected->kind == MaterialTexture::Half ? "half" : "float") +
                                  " for latent " + std::to_string(shape[0]) + ", layers " +
                                  std::to_string(shape[1]) + ", units " + std::to_string(shape[2]));
        if (expected == &latentShape)
            m->latent = StoredValues::take(got, MaterialTexture::Half);
        else
            m->decoder.data = std::move(got.data);
    }
    for (float v : m->decoder.data)
        if (!std::isfinite(v))
            fail(file.source, "texture 'decoder' holds a value that is not finite");
    if (!m->latent.allFinite())
        fail(file.source, "texture 'latent' holds a value that is not finite");
    return m;
}

MaterialTexture NeuralMaterial::gpuDecoder() const {
    const int groups = _units / 4, columns = 1 + std::max(inputs(), _units);
    MaterialTexture t{"decoder", columns, _hiddenLayers * groups + 1, 1, 4, MaterialTexture::Float,
                      {}};
    t.data.assign(t.valueCount(), 0.0f);
    for (int k = 0; k <= _hiddenLayers; ++k)
        for (int j = 0; j < layerOutputs(k); ++j) {
            const float* row = &decoder.data[std::size_t(decoderRow(k, j)) * decoder.width * 4];
            float* out = &t.data[std::size_t(k * groups + j / 4) * std::size_t(columns) * 4];
            out[j % 4] = row[0];
            for (int i = 0; i < layerInputs(k); ++i) out[4 * (1 + i) + j % 4] = row[4 + i];
        }
    return t;
}

int NeuralMaterial::gpuWeightVectors() const {
    int count = 0;
    for (int k = 0; k <= _hiddenLayers; ++k)
        count += (layerOutputs(k) + 3) / 4 * (1 + layerInputs(k));
    return count;
}

std::vector<float> NeuralMaterial::gpuWeights() const {
    std::vector<float> weights(std::size_t(gpuWeightVectors()) * 4, 0.0f);
    std::size_t start = 0;  // the group's first float
    for (int k = 0; k <= _hiddenLayers; ++k) {
        const int inputs = layerInputs(k);
        for (int j = 0; j < layerOutputs(k); ++j) {
            if (j > 0 && j % 4 == 0) start += std::size_t(1 + inputs) * 4;
            const float* row = &decoder.data[std::size_t(decoderRow(k, j)) * decoder.width * 4];
            weights[start + j % 4] = row[0];
            for (int i = 0; i < inputs; ++i) weights[start + 4 * (1 + i) + j % 4] = row[4 + i];
        }
        start += std::size_t(1 + inputs) * 4;
    }
    return weights;
}

std::vector<std::string> NeuralMaterial::shaderDefines() const {
    std::vector<std::string> defines = {
        "OSGBTF_NEURAL_LATENT_GROUPS " + std::to_string(_latentSize / 4),
        "OSGBTF_NEURAL_LAYERS " + std::to_string(_hiddenLayers),
        "OSGBTF_NEURAL_UNITS " + std::to_string(_units)};
    if (usesUniformWeights())
        defines.push_back("OSGBTF_NEURAL_WEIGHTS " + std::to_string(gpuWeightVectors()));
    return defines;
}

osg::ref_ptr<osg::StateSet> NeuralMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addTexture(*stateSet, createFloatTextureArray(latentTexture()).get(), "neuralLatent", 0);
    if (usesUniformWeights()) {
        // Read once per draw, not fetched per fragment (shaderDefines).
        const std::vector<float> weights = gpuWeights();
        const int vectors = int(weights.size() / 4);
        osg::ref_ptr<osg::Uniform> uniform =
            new osg::Uniform(osg::Uniform::FLOAT_VEC4, "neuralWeights", vectors);
        for (int i = 0; i < vectors; ++i)
            uniform->setElement(i, osg::Vec4f(weights[4 * i], weights[4 * i + 1],
                                              weights[4 * i + 2], weights[4 * i + 3]));
        stateSet->addUniform(uniform.get());
    } else {
        addTexture(*stateSet, createFloatTexture(gpuDecoder()).get(), "neuralDecoder", 1);
    }
    // The shape is the program's (shaderDefines), not uniforms.
    return stateSet;
}

namespace {
const bool neuralRegistered = registerMethodClass<NeuralMaterial>([] {
    MethodInfo m;
    m.description =
        "neural BTF (Rainer et al. 2019): a latent texture (L half values per texel) decoded with "
        "the light and view directions by one small MLP per material";
    m.options = {
        OptionSpec::integer("latent", 8, 4, NeuralMaterial::kMaxLatent,
                            "latent values per texel (2 bytes each)")
            .multipleOf(4),
        OptionSpec::integer("layers", 2, 1, NeuralMaterial::kMaxHiddenLayers,
                            "hidden layers of the decoder"),
        OptionSpec::integer("units", 32, 4, NeuralMaterial::kMaxUnits, "units per hidden layer")
            .multipleOf(4),
        OptionSpec::integer("steps", 8000, 1, OptionSpec::kNoLimit,
                            "Adam steps (the last tenth trains the decoder on the latents as "
                            "stored)"),
        OptionSpec::integer("batch", 4096, 16, 65536, "(texel, view, light) samples per step"),
        OptionSpec::integer("seed", 1, 0, OptionSpec::kNoLimit,
                            "initial weights and sample order; the same seed fits the same "
                            "material on the same machine"),
        OptionSpec::integer("filtered", 25, 0, 100,
                            "percent of each batch trained on latents blended as filtered "
                            "lookups blend them (between texels and mip levels)"),
        OptionSpec::integer("threads", 1, 0, 256,
                            "training threads (torch's intra-op threads); 0: every core. More "
                            "than 1 pays only on an idle machine (README)")};
    // One decode of the latents blended over the filtered texels (TexelFilter::Inputs), not a
    // blend of four (eight) decodes: the fit trains every mip level's latents on that level's
    // box-filtered data, and the decoder on latents blended between texels and levels.
    m.blendsInputs = true;
    m.shaderCost = [](const Material& material) {
        // Features: normalize 6, rest 2. The latent blend: per tap (4, 8 between two mip levels)
        // and group of 4 latents a fetch and a multiply-add (2), per tap its texel and weight (4);
        // per level the taps' selection (ShaderCost::kBlendLevelAlu).
        const NeuralMaterial& n = static_cast<const NeuralMaterial&>(material);
        const bool mip = n.mipLayout().mipMapped();
        const int taps = mip ? 8 : 4, groups = n.latentSize() / 4;
        int alu = 8 + taps * (4 + 2 * groups), tex = taps * groups;
        const bool uniforms = n.usesUniformWeights();
        for (int k = 0; k <= n.hiddenLayers(); ++k) {
            // Four neurons at a time: per input 4 weights in one vec4 (a uniform, or a fetch from
            // gpuDecoder for a network too large for the uniforms), per group of 4 inputs 4
            // multiplies and 4 adds; the bias, the loop and the ReLU.
            const int outputGroups = (n.layerOutputs(k) + 3) / 4, inputs = n.layerInputs(k);
            alu += outputGroups * (inputs / 4 * 8 + 2);
            if (!uniforms) tex += outputGroups * (inputs + 1);
        }
        alu += 3;  // times l_z
        const std::string shape = "one decode (L " + std::to_string(n.latentSize()) + ", " +
                                  std::to_string(n.hiddenLayers()) + " x " +
                                  std::to_string(n.units()) + " units)";
        ShaderCost cost = ShaderCost::ofEvaluate(
            alu, tex,
            uniforms ? "ALU ~2 x weights / 4 (weights in uniforms), TEX " + std::to_string(taps) +
                           " taps x L/4, " + shape
                     : "ALU ~2 x weights / 4, TEX weights / 4 + neurons / 4 + " +
                           std::to_string(taps) + " taps x L/4, " + shape);
        cost.fixedAlu += (mip ? 2 : 1) * ShaderCost::kBlendLevelAlu;
        return cost;
    };
    m.order = 90;
    m.quickFitOptions = "latent=4 units=16 layers=1 steps=300 batch=512";
    // The fit holds the latents and a block of ABRDFs (at most 256 MiB) beyond the input.
    m.fitWorkingSet = 0.25;
    m.fitWorkingSetFullSizeGiB = 1;
    return m;
}());
}  // namespace

// The decoder is every texel's; only the latents are per texel (remapMaterial).
[[maybe_unused]] const bool neuralSharedTexturesDeclared =
    declareSharedTextures(NeuralMaterial::kMethod, {"decoder"});

}  // namespace osgBTF
