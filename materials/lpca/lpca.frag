#version 330 compatibility
// Method "lpca" (materials/lpca/Lpca.h): clustered local PCA, the original rendering of Schneider
// 2004 section 5. Per component the Eigen-BRDF is interpolated by hand over the 3 nearest measured
// views x 3 nearest lights (the exact Delaunay weights), then weighted by the texel's alpha_i.
// LpcaMaterial::evaluate is the same arithmetic on the CPU.
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

uniform sampler2D lpcaCluster;           // 8-bit: cluster index / 255
uniform sampler2DArray lpcaWeights;      // layer i / 4, channel i % 4: alpha_i
uniform sampler2DArray lpcaEigenBrdfs;   // layer cluster, x light, y view * components + i
uniform int lpcaComponents;
uniform sampler2D lpcaViewTable;         // direction interpolation (common/directions.glsl)
uniform sampler2D lpcaLightTable;

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    int k = int(texelFetch(lpcaCluster, texel, 0).r * 255.0 + 0.5);
    ivec3 vi, li;
    vec3 vw, lw;
    btfLookupDirections(lpcaViewTable, view, vi, vw);
    btfLookupDirections(lpcaLightTable, light, li, lw);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < lpcaComponents; ++i) {
        float alpha = texelFetch(lpcaWeights, ivec3(texel, i / 4), 0)[i % 4];
        vec3 value = vec3(0.0);
        for (int a = 0; a < 3; ++a)
            for (int b = 0; b < 3; ++b)
                value += (vw[a] * lw[b]) *
                         texelFetch(lpcaEigenBrdfs, ivec3(li[b], vi[a] * lpcaComponents + i, k), 0).rgb;
        sum += alpha * value;
    }
    return sum;
}
