#version 330 compatibility
// Method "neural" (materials/neural/Neural.h): l_z * D(z(x), f(v, l)), the decoder network run
// once per fragment and light. Same operations in the same order as NeuralMaterial::decode and
// evaluateTaps, so GPU == CPU. Decodes once (TexelFilter::Inputs): with btfBlendInputs, the
// latents of the taps btf_main.glsl selected (four texels, eight between two mip levels) are
// blended by their weights and the blend decoded.
#pragma include "common/btf_main.glsl"

const int kHalf = 64 / 4;  // NeuralMaterial::kMaxUnits / 4 >= (kMaxLatent + 8) / 4 groups

uniform sampler2DArray neuralLatent;  // RGBA half, layer g = latents 4g..4g+3
// RGBA float, four neurons a row (NeuralMaterial::gpuDecoder): texel 0 their 4 biases, texel
// 1 + i their 4 weights of input i.
uniform sampler2D neuralDecoder;
uniform int neuralLatentGroups;  // L / 4
uniform int neuralHiddenLayers;  // H
uniform int neuralUnits;         // W

// Two halves of groups of 4 values (GLSL 3.30 has no arrays of arrays): the first layer's
// inputs (the latents, then the direction features) in the first, then each layer reads one half
// and writes the other.
vec4 neuralBuffer[2 * kHalf];

// Four neurons of decoder row `row` on `groups` groups of inputs at neuralBuffer[source]: per
// group c and neuron k, sum[k] += w0[k] x.x + w1[k] x.y + w2[k] x.z + w3[k] x.w (the CPU's order).
vec4 neuralNeurons(int row, int groups, int source) {
    vec4 sum = texelFetch(neuralDecoder, ivec2(0, row), 0);
    for (int c = 0; c < groups; ++c) {
        vec4 x = neuralBuffer[source + c];
        int column = 1 + 4 * c;
        vec4 w0 = texelFetch(neuralDecoder, ivec2(column, row), 0);
        vec4 w1 = texelFetch(neuralDecoder, ivec2(column + 1, row), 0);
        vec4 w2 = texelFetch(neuralDecoder, ivec2(column + 2, row), 0);
        vec4 w3 = texelFetch(neuralDecoder, ivec2(column + 3, row), 0);
        sum += w0 * x.x + w1 * x.y + w2 * x.z + w3 * x.w;
    }
    return sum;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    if (btfBlendInputs) {
        for (int g = 0; g < neuralLatentGroups; ++g) neuralBuffer[g] = vec4(0.0);
        for (int k = 0; k < btfTapCount; ++k) {
            ivec2 tap = btfTapTexel(k);
            float w = btfTapWeight(k);
            for (int g = 0; g < neuralLatentGroups; ++g)
                neuralBuffer[g] += w * texelFetch(neuralLatent, ivec3(tap, g), 0);
        }
    } else {
        for (int g = 0; g < neuralLatentGroups; ++g)
            neuralBuffer[g] = texelFetch(neuralLatent, ivec3(texel, g), 0);
    }
    vec3 h = normalize(view + light);
    neuralBuffer[neuralLatentGroups] = vec4(view.x, view.y, light.x, light.y);
    neuralBuffer[neuralLatentGroups + 1] = vec4(h.x, h.y, h.z, light.z);
    int groups = neuralLatentGroups + 2, source = 0, unitGroups = neuralUnits / 4;
    for (int k = 0; k < neuralHiddenLayers; ++k) {
        int target = kHalf - source;
        for (int j = 0; j < unitGroups; ++j)
            neuralBuffer[target + j] =
                max(neuralNeurons(k * unitGroups + j, groups, source), vec4(0.0));
        groups = unitGroups;
        source = target;
    }
    return neuralNeurons(neuralHiddenLayers * unitGroups, groups, source).rgb * light.z;
}
