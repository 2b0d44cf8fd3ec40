#version 330 compatibility
// Method "lpca-revised" (materials/lpca-revised/LpcaRevised.h): Schneider 2004 section 6. The
// Eigen-BRDFs are resampled over the elevated concentric map into one LINEAR-filtered 3D texture
// (x = cluster * n + s_v, y = component * n + t_v, z = t_l * n + s_l, texel units); per component
// two fetches and one lerp over t_l. The direction -> (s, t) maps are computed here instead of the
// paper's cube maps (exact, and the CPU evaluator does the same: LpcaRevisedMaterial::evaluate).
#pragma include "common/btf_main.glsl"

uniform sampler2D lpcaRevisedCluster;       // 8-bit: cluster index / 255
uniform sampler2DArray lpcaRevisedWeights;  // layer i / 4, channel i % 4
uniform sampler3D lpcaRevisedGrid;
uniform int lpcaRevisedComponents;
uniform int lpcaRevisedResolution;
uniform int lpcaRevisedOffset;  // 1: unorm8 grid, weight slot c holds the folded offset

const float lpcaRevisedQuarterPi = 0.78539816339744830962;

/** Omega^-1: direction -> square [0, 1]^2 (ConcentricMap.cpp). */
vec2 lpcaRevisedInverse(vec3 d) {
    d.z = max(d.z, 0.0);
    d = normalize(d);
    vec2 disc = d.xy / sqrt(1.0 + d.z);
    float rho = length(disc);
    float phi = atan(disc.y, disc.x);
    if (phi < -lpcaRevisedQuarterPi) phi += 8.0 * lpcaRevisedQuarterPi;
    float f = phi / lpcaRevisedQuarterPi;
    float a, b;
    if (f < 1.0) {
        a = rho;
        b = a * f;
    } else if (f < 3.0) {
        b = rho;
        a = b * (2.0 - f);
    } else if (f < 5.0) {
        a = -rho;
        b = a * (f - 4.0);
    } else {
        b = -rho;
        a = b * (6.0 - f);
    }
    return (vec2(a, b) + 1.0) * 0.5;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    float n = float(lpcaRevisedResolution);
    vec3 size = vec3(textureSize(lpcaRevisedGrid, 0));
    int k = int(texelFetch(lpcaRevisedCluster, texel, 0).r * 255.0 + 0.5);
    vec2 sv = lpcaRevisedInverse(view), sl = lpcaRevisedInverse(light);
    float x = float(k) * n + clamp(sv.x * n, 0.5, n - 0.5);
    float yInBlock = clamp(sv.y * n, 0.5, n - 0.5);
    float u = clamp(sl.y * n - 0.5, 0.0, n - 1.0);
    int slab = min(int(floor(u)), lpcaRevisedResolution - 2);
    float w = u - float(slab);
    float z1 = float(slab) * n + clamp(sl.x * n, 0.5, n - 0.5);
    float z2 = z1 + n;
    vec3 sum = vec3(0.0);
    for (int i = 0; i < lpcaRevisedComponents; ++i) {
        float y = float(i) * n + yInBlock;
        vec3 a = texture(lpcaRevisedGrid, vec3(x, y, z1) / size).rgb;
        vec3 b = texture(lpcaRevisedGrid, vec3(x, y, z2) / size).rgb;
        sum += texelFetch(lpcaRevisedWeights, ivec3(texel, i / 4), 0)[i % 4] * mix(a, b, w);
    }
    if (lpcaRevisedOffset != 0) {
        int i = lpcaRevisedComponents;
        sum += vec3(texelFetch(lpcaRevisedWeights, ivec3(texel, i / 4), 0)[i % 4]);
    }
    return sum;
}
