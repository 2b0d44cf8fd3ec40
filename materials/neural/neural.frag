#version 330 compatibility
// Method "neural" (materials/neural/Neural.h): l_z * D(z(x), f(v, l)), the decoder network run
// per fragment and light. Same operations in the same order as NeuralMaterial::decode/evaluate,
// so GPU == CPU. Not linear in the latents: btf_main.glsl blends four texels' values.
#pragma include "common/btf_main.glsl"

const int kMaxUnits = 64;                 // NeuralMaterial::kMaxUnits
const int kMaxGroups = (32 + 8) / 4;      // (kMaxLatent + kDirectionFeatures) / 4

uniform sampler2DArray neuralLatent;  // RGBA half, layer g = latents 4g..4g+3
uniform sampler2D neuralDecoder;      // RGBA float: row = neuron, texel 0 = bias, 1.. = weights
uniform int neuralLatentGroups;       // L / 4
uniform int neuralHiddenLayers;       // H
uniform int neuralUnits;              // W

// The first layer's inputs, in groups of 4: the latents, then the direction features.
vec4 neuralInput[kMaxGroups];
// Two hidden layers' outputs, in groups of 4 (GLSL 3.30 has no arrays of arrays): the layer
// being computed writes one half while it reads the other.
const int kHalf = kMaxUnits / 4;
vec4 neuralHidden[2 * kHalf];

// source < 0: the first layer's inputs; else the half of neuralHidden starting at group source.
float neuralNeuron(int row, int groups, int source) {
    float sum = texelFetch(neuralDecoder, ivec2(0, row), 0).x;
    for (int c = 0; c < groups; ++c) {
        vec4 w = texelFetch(neuralDecoder, ivec2(1 + c, row), 0);
        vec4 x = source < 0 ? neuralInput[c] : neuralHidden[source + c];
        sum += w.x * x.x + w.y * x.y + w.z * x.z + w.w * x.w;
    }
    return sum;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    for (int g = 0; g < neuralLatentGroups; ++g)
        neuralInput[g] = texelFetch(neuralLatent, ivec3(texel, g), 0);
    vec3 h = normalize(view + light);
    neuralInput[neuralLatentGroups] = vec4(view.x, view.y, light.x, light.y);
    neuralInput[neuralLatentGroups + 1] = vec4(h.x, h.y, h.z, light.z);
    int groups = neuralLatentGroups + 2, source = -1, unitGroups = neuralUnits / 4;
    for (int k = 0; k < neuralHiddenLayers; ++k) {
        int target = (k - 2 * (k / 2)) * kHalf;
        for (int j = 0; j < neuralUnits; ++j)
            neuralHidden[target + j / 4][j % 4] =
                max(neuralNeuron(k * neuralUnits + j, groups, source), 0.0);
        groups = unitGroups;
        source = target;
    }
    int outputRow = neuralHiddenLayers * neuralUnits;
    vec3 rgb = vec3(neuralNeuron(outputRow, groups, source),
                    neuralNeuron(outputRow + 1, groups, source),
                    neuralNeuron(outputRow + 2, groups, source));
    return rgb * light.z;
}
