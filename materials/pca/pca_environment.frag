#version 330 compatibility
// Environment lighting of method "pca" (Sattler et al. 2003 section 5.2): per measured view j the
// folded weights gamma*_kj = sum_i g_i alpha_k(j, i) replace the light interpolation, so a fragment
// costs what one point light costs. Slots per view: the components, then the unorm8 bias. The same
// loops as evaluateFoldedPca (materials/EnvironmentLighting.h).
#pragma include "common/environment.glsl"
#pragma include "common/directions.glsl"

uniform sampler2DArray pcaEigenTextures;
uniform sampler2D pcaViewTable;
uniform int pcaComponents;
uniform int pcaTileColumns;

vec3 btfEnvironmentEvaluate(ivec2 texel, vec3 view) {
    ivec3 vi;
    vec3 vw;
    btfLookupDirections(pcaViewTable, view, vi, vw);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < 3; ++i) {
        if (!(vw[i] > 0.0)) continue;
        int base = vi[i] * (pcaComponents + 1);
        vec3 value = btfEnvData(base + pcaComponents);
        for (int k = 0; k < pcaComponents; ++k) {
            ivec2 tile = ivec2(k % pcaTileColumns, k / pcaTileColumns) * osgBTF_size;
            value += btfEnvData(base + k) *
                     texelFetch(pcaEigenTextures, ivec3(tile + texel, vi[i]), 0).rgb;
        }
        sum += vw[i] * value;
    }
    return sum;
}
