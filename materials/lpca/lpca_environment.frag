#version 330 compatibility
// Environment lighting of method "lpca" (Sattler et al. 2003 section 5.2 for clustered PCA): the
// per-vertex data are the projected environment g itself (one RGB value per measured light),
// because folding it into every cluster's Eigen-BRDFs per vertex would be clusters x components x
// views values and a triangle spans texels of many clusters. The fragment blends g across the
// triangle (equal to blending folded data: folding is linear) and folds it into its own cluster's
// Eigen-BRDFs for its nearest views: lights x (3 + 3 x components) fetches. Same sums as
// evaluateFoldedLpca (materials/EnvironmentLighting.h), in light-outer order.
#pragma include "common/environment.glsl"
#pragma include "common/directions.glsl"

uniform sampler2D lpcaCluster;          // 8-bit: cluster index / 255
uniform sampler2DArray lpcaWeights;     // layer i / 4, channel i % 4: alpha_i
uniform sampler2DArray lpcaEigenBrdfs;  // layer cluster, x light, y view * components + i
uniform int lpcaComponents;
uniform sampler2D lpcaViewTable;
uniform int lpcaLights;

vec3 btfEnvironmentEvaluate(ivec2 texel, vec3 view) {
    int k = int(texelFetch(lpcaCluster, texel, 0).r * 255.0 + 0.5);
    ivec3 vi;
    vec3 vw;
    btfLookupDirections(lpcaViewTable, view, vi, vw);
    vec3 sum = vec3(0.0);
    for (int l = 0; l < lpcaLights; ++l) {
        vec3 g = btfEnvData(l);
        if (g == vec3(0.0)) continue;
        vec3 value = vec3(0.0);
        for (int a = 0; a < 3; ++a) {
            if (!(vw[a] > 0.0)) continue;
            vec3 viewSum = vec3(0.0);
            for (int i = 0; i < lpcaComponents; ++i) {
                float alpha = texelFetch(lpcaWeights, ivec3(texel, i / 4), 0)[i % 4];
                viewSum += alpha * texelFetch(lpcaEigenBrdfs,
                                              ivec3(l, vi[a] * lpcaComponents + i, k), 0).rgb;
            }
            value += vw[a] * viewSum;
        }
        sum += g * value;
    }
    return sum;
}
