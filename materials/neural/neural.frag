#version 330 compatibility
// Method "neural" (materials/neural/Neural.h): l_z * D(z(x), f(v, l)), the decoder network run
// once per fragment and light. Same operations in the same order as NeuralMaterial::decode and
// evaluateTaps, so GPU == CPU. Decodes once (TexelFilter::Inputs): with btfBlendInputs, the
// latents of the taps btf_main.glsl selected (four texels, eight between two mip levels) are
// blended by their weights and the blend decoded.
#pragma include "common/btf_main.glsl"

// The network's shape is compiled in (NeuralMaterial::shaderDefines), not read from uniforms:
// with constant loop bounds the compiler unrolls the decoder, every weight's index becomes a
// constant, and the weights can be uniforms, which a software rasterizer reads once per draw
// rather than fetching per fragment (README.md, "Pass cost"):
//   OSGBTF_NEURAL_LATENT_GROUPS  L / 4
//   OSGBTF_NEURAL_LAYERS         H, the hidden layers
//   OSGBTF_NEURAL_UNITS          W, the units per hidden layer
//   OSGBTF_NEURAL_WEIGHTS        n: the decoder in the uniform array neuralWeights[n]; absent for
//                                a network too large for the uniforms (the texture below)
#if !defined(OSGBTF_NEURAL_LATENT_GROUPS) || !defined(OSGBTF_NEURAL_LAYERS) || \
    !defined(OSGBTF_NEURAL_UNITS)
#error "neural.frag is compiled with the network's shape (NeuralMaterial::shaderDefines)"
#endif

const int kLatentGroups = OSGBTF_NEURAL_LATENT_GROUPS;
const int kUnitGroups = OSGBTF_NEURAL_UNITS / 4;
const int kInputGroups = kLatentGroups + 2;  // the latents, then the 8 direction features
const int kHalf = max(kInputGroups, kUnitGroups);

uniform sampler2DArray neuralLatent;  // RGBA half, layer g = latents 4g..4g+3

// Four neurons a group: the group's 4 biases, then per input i its 4 weights. Uniforms
// (NeuralMaterial::gpuWeights): the groups one after the other, those of layer 0, then of each
// further layer, the output layer's one group last; `start` is a group's first vec4. Texture
// (NeuralMaterial::gpuDecoder): one group a row, `group` the row.
#ifdef OSGBTF_NEURAL_WEIGHTS
uniform vec4 neuralWeights[OSGBTF_NEURAL_WEIGHTS];
vec4 neuralWeight(int group, int start, int index) { return neuralWeights[start + index]; }
#else
uniform sampler2D neuralDecoder;
vec4 neuralWeight(int group, int start, int index) {
    return texelFetch(neuralDecoder, ivec2(index, group), 0);
}
#endif

// Two halves of groups of 4 values (GLSL 3.30 has no arrays of arrays): the first layer's
// inputs (the latents, then the direction features) in the first, then each layer reads one half
// and writes the other.
vec4 neuralBuffer[2 * kHalf];

// Four neurons, group `group` of the decoder (its weights at `start`), on `groups` groups of
// inputs at neuralBuffer[source]: per group c and neuron k, sum[k] += w0[k] x.x + w1[k] x.y +
// w2[k] x.z + w3[k] x.w (the CPU's order).
vec4 neuralNeurons(int group, int start, int groups, int source) {
    vec4 sum = neuralWeight(group, start, 0);
    for (int c = 0; c < groups; ++c) {
        vec4 x = neuralBuffer[source + c];
        int column = 1 + 4 * c;
        vec4 w0 = neuralWeight(group, start, column);
        vec4 w1 = neuralWeight(group, start, column + 1);
        vec4 w2 = neuralWeight(group, start, column + 2);
        vec4 w3 = neuralWeight(group, start, column + 3);
        sum += w0 * x.x + w1 * x.y + w2 * x.z + w3 * x.w;
    }
    return sum;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    if (btfBlendInputs) {
        for (int g = 0; g < kLatentGroups; ++g) neuralBuffer[g] = vec4(0.0);
        for (int k = 0; k < btfTapCount; ++k) {
            ivec2 tap = btfTapTexel(k);
            float w = btfTapWeight(k);
            for (int g = 0; g < kLatentGroups; ++g)
                neuralBuffer[g] += w * texelFetch(neuralLatent, ivec3(tap, g), 0);
        }
    } else {
        for (int g = 0; g < kLatentGroups; ++g)
            neuralBuffer[g] = texelFetch(neuralLatent, ivec3(texel, g), 0);
    }
    vec3 h = normalize(view + light);
    neuralBuffer[kLatentGroups] = vec4(view.x, view.y, light.x, light.y);
    neuralBuffer[kLatentGroups + 1] = vec4(h.x, h.y, h.z, light.z);
    // Layer 0 on the inputs (first half), written to the second half.
    const int firstStride = 4 * kInputGroups + 1, stride = OSGBTF_NEURAL_UNITS + 1;
    for (int j = 0; j < kUnitGroups; ++j)
        neuralBuffer[kHalf + j] =
            max(neuralNeurons(j, j * firstStride, kInputGroups, 0), vec4(0.0));
    // Hidden layers 1..H-1, alternating halves; then the output layer.
    int start = kUnitGroups * firstStride, source = kHalf;
    for (int k = 1; k < OSGBTF_NEURAL_LAYERS; ++k) {
        int target = kHalf - source;
        for (int j = 0; j < kUnitGroups; ++j)
            neuralBuffer[target + j] = max(
                neuralNeurons(k * kUnitGroups + j, start + j * stride, kUnitGroups, source),
                vec4(0.0));
        start += kUnitGroups * stride;
        source = target;
    }
    return neuralNeurons(OSGBTF_NEURAL_LAYERS * kUnitGroups, start, kUnitGroups, source).rgb *
           light.z;
}
