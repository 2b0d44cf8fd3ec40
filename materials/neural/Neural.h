// osgBTF method "neural": a latent texture and one small decoder network per material, after
// Rainer, Jakob, Ghosh, Weyrich 2019 ("Neural BTF Compression and Interpolation") and the
// real-time neural materials of Zeltner et al. 2024 (latents decoded by a small MLP in the shader).
//
//   BTF(x, v, l) ~ l_z * D(z(x), f(v, l))
//
// z(x): L latent values per texel (L a multiple of 4, stored half); f: 8 features of the local view
// and light directions (NeuralMaterial::directionFeatures); D: H hidden layers of W ReLU units and
// a linear RGB output, one network for the whole material. The fit (NeuralFit.cpp; the training
// in NeuralTraining.cpp, with libtorch) trains z and D together by Adam on the measured values
// (an "auto-decoder": no encoder, the latents are free parameters). Memory per texel: L values,
// 2L bytes; the decoder's float weights are shared by all texels.
#pragma once

#include <vector>

#include "materials/MethodMaterial.h"
#include "materials/MethodOptions.h"
#include "materials/StoredValues.h"

namespace osgBTF {

/** NeuralMaterial's members (materials/MethodMaterial.h). */
struct NeuralData {
    /** Latent codes, half, as the file stores them (materials/StoredValues.h): L/4 layers of
     *  RGBA, latent k of a texel in layer k / 4, channel k % 4 (rows bottom-up; latentIndex). */
    StoredValues latent;
    /** The decoder, one row per neuron (the hidden layers' W each, then the 3 outputs), RGBA float:
     *  texel 0 of a row is (bias, 0, 0, 0), texels 1.. the neuron's input weights in groups of 4.
     */
    MaterialTexture decoder;

protected:
    int _latentSize = 0;    ///< L
    int _hiddenLayers = 0;  ///< H
    int _units = 0;         ///< W
};

class NeuralMaterial : public MethodMaterial<NeuralMaterial, NeuralData> {
public:
    static constexpr const char* kMethod = "neural";
    /** fromFile takes the file's half latents as they are stored. */
    static constexpr bool kLoadsHalves = true;
    /** Direction features the decoder reads after the latents (directionFeatures). */
    static constexpr int kDirectionFeatures = 8;
    static constexpr int kMaxLatent = 32, kMaxUnits = 64, kMaxHiddenLayers = 4;

    NeuralMaterial() = default;
    NeuralMaterial(const NeuralMaterial& other,
                   const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop) {}
    META_Object(osgBTF, NeuralMaterial)

        /** Options: latent, layers, units, steps, batch, seed (the README's table). Throws Error
         * for an empty BTF, unknown or out-of-range options, latent or units not a multiple of 4,
         * and a build without libtorch. */
        static osg::ref_ptr<NeuralMaterial> fit(const BtfSource& btf, const FitOptions& options);
    static osg::ref_ptr<NeuralMaterial> fromFile(FittedMaterial file);

    /** Sets the texel size and directions, then setNetworkShape. */
    void setShape(int width, int height, const DirectionSet& views, const DirectionSet& lights,
                  int latentSize, int hiddenLayers, int units);
    /** Sets the network's shape and sizes both textures (zero-filled) for the material's texels;
     *  without `allocateLatent` the latents stay empty (a file brings them). Throws Error for a
     *  shape outside the limits above. */
    void setNetworkShape(int latentSize, int hiddenLayers, int units, bool allocateLatent = true);
    /** The latent texture as the file and the GPU hold it (`latent` copied into its shape). */
    MaterialTexture latentTexture() const {
        return latent.texture("latent", _width, _height, _latentSize / 4, 4);
    }

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    /** Decode once (TexelFilter::Inputs): the taps' latents blended by their weights, in the
     *  taps' order (neural.frag's btfBlendInputs branch), then one decode of the blend. */
    glm::vec3 evaluateTaps(const FilterTaps& taps, const glm::vec3& view,
                           const glm::vec3& light) const override;
    MemoryFootprint memory() const override;
    FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

    int latentSize() const { return _latentSize; }
    int hiddenLayers() const { return _hiddenLayers; }
    int units() const { return _units; }
    /** Inputs of the first layer: the latents, then the direction features. */
    int inputs() const { return _latentSize + kDirectionFeatures; }
    /** Inputs of layer k (0 .. hiddenLayers(); the last is the output layer). */
    int layerInputs(int k) const { return k == 0 ? inputs() : _units; }
    /** Outputs of layer k: units(), 3 for the output layer. */
    int layerOutputs(int k) const { return k == _hiddenLayers ? 3 : _units; }
    /** The decoder row of neuron j of layer k. */
    int decoderRow(int k, int j) const { return k * _units + j; }
    /** Latent i of texel (x, y) in latent. */
    std::size_t latentIndex(int x, int y, int i) const {
        return ((std::size_t(i / 4) * _height + y) * _width + x) * 4 + std::size_t(i % 4);
    }

    /** The decoder as the shader reads it (neural.frag): four neurons a row, row k W/4 + j/4 for
     *  neuron j of layer k (the output layer's 3 in the last row, the fourth channel 0); texel 0
     *  their biases, texel 1 + i their weights of input i. One fetch gives an input's weights of
     *  four neurons, which the shader accumulates in one vec4. */
    MaterialTexture gpuDecoder() const;
    /** The decoder as neural.frag's uniform array neuralWeights holds it: gpuDecoder's groups
     *  without the padding, one after the other (each: 4 biases, then 4 weights per input of its
     *  layer), 4 floats per vec4. */
    std::vector<float> gpuWeights() const;
    /** The most vec4 the decoder may take as uniforms (gpuWeights, usesUniformWeights): 1024 is
     *  what GL 3.3 guarantees a fragment shader (GL_MAX_FRAGMENT_UNIFORM_COMPONENTS >= 1024
     *  floats is the floor, real drivers give 4096 to 16384 floats); a margin is left for
     *  btf_main.glsl's own uniforms. */
    static constexpr int kMaxUniformWeights = 768;
    /** Whether the shader reads the decoder from uniforms (gpuWeights; the network's default
     *  shapes) or, for a network whose weights exceed kMaxUniformWeights vec4, from the texture
     *  (gpuDecoder). */
    bool usesUniformWeights() const { return gpuWeightVectors() <= kMaxUniformWeights; }
    /** gpuWeights' size in vec4: per group of 4 neurons of layer k, 1 + layerInputs(k). */
    int gpuWeightVectors() const;
    /** The network's shape as neural.frag's defines (the loops' bounds are constants, so the
     *  decoder unrolls and the weights' indices are constants), and the uniforms' size. */
    std::vector<std::string> shaderDefines() const override;

    /** f(v, l) = (v.x, v.y, l.x, l.y, h.x, h.y, h.z, l.z), h = normalize(v + l): the projected
     *  directions (what Rainer et al. 2019 feed their decoder) plus the half vector and the
     *  light's cosine, on which specular lobes and shading depend most directly, so that a small
     *  ReLU network needs fewer units to bend along them. */
    static void directionFeatures(const glm::vec3& view, const glm::vec3& light, float* out);
    /** D(inputs): the network on one input vector (inputs() values), in the shader's order of
     *  operations. */
    glm::vec3 decode(const float* inputs) const;

protected:
    ~NeuralMaterial() override = default;
};

}  // namespace osgBTF
