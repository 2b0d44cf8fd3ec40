#version 330 compatibility
// Environment lighting of method "fmf" (Schwartz et al. 2013's B = U SxV^T, Sattler et al. 2003
// section 5.2): per measured view j the environment is folded into U, u*_jq = sum_i g_i U[(j, i,
// c), q] per channel c, so a fragment dots the blended u* of its nearest views with its texel's SxV
// row: 3 vertices x 3 views x K fetches. The same loops as evaluateFoldedFmf
// (materials/EnvironmentLighting.h); only plain fmf (no log values, no dfmf) is folded.
#pragma include "common/environment.glsl"
#pragma include "common/directions.glsl"

uniform sampler2DArray fmfSxV;  // layer = group of 4 components
uniform sampler2D fmfViewTable;
uniform int fmfComponents;      // K, slots per view of the folded data

vec3 btfEnvironmentEvaluate(ivec2 texel, vec3 view) {
    ivec3 vi;
    vec3 vw;
    btfLookupDirections(fmfViewTable, view, vi, vw);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < 3; ++i) {
        if (!(vw[i] > 0.0)) continue;
        int base = vi[i] * fmfComponents;
        vec3 value = vec3(0.0);
        for (int q = 0; q < fmfComponents; ++q)
            value += btfEnvData(base + q) * texelFetch(fmfSxV, ivec3(texel, q / 4), 0)[q % 4];
        sum += vw[i] * value;
    }
    return sum;
}
