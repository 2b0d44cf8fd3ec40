#version 330 compatibility
// Method "rbf" (materials/rbf/Rbf.h): relight's rbf model, per texel N PCA coefficients, the
// basis interpolated between the measured lights with normalised Gaussian weights (or, for
// relight's bilinear type, bilinearly over an octahedral grid). The same float operations and
// order as RbfMaterial::lightWeights and RbfMaterial::combine, so GPU == CPU. The weights depend
// on the light only; they are computed per fragment (the light loop of btf_main.glsl).
#pragma include "common/btf_main.glsl"

// RGB layers: plane p = layer p / 3, channel p % 3.
uniform sampler2DArray rbfCoefficients;
// Texel (p, i): E_p of node i, RGB (p = 0: the mean profile).
uniform sampler2D rbfBasis;
// Texel (i, 0): node i's light direction (rbf).
uniform sampler2D rbfNodes;
uniform int rbfPlanes;
uniform int rbfNodeCount;
uniform int rbfResolution;  // 0: Gaussian weights over the nodes; R: R x R octahedral grid
uniform float rbfInverseSigma2;

const float kRbfThreshold = 0.001;
const int kRbfMaxLayers = 16;

vec3 rbfCoefficient[kRbfMaxLayers];

// The profile of node i at this texel: E_0(i) + sum_p a_p E_p(i).
vec3 rbfProfile(int i) {
    vec3 s = texelFetch(rbfBasis, ivec2(0, i), 0).rgb;
    for (int p = 0; p < rbfPlanes; ++p)
        s += rbfCoefficient[p / 3][p % 3] * texelFetch(rbfBasis, ivec2(p + 1, i), 0).rgb;
    return s;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    // Filtered (btfBilinear): the value is linear in the coefficients (half or float, filtered as
    // the floats they are), so filtering them blends the texels' values.
    int layers = (rbfPlanes + 2) / 3;
    for (int j = 0; j < layers; ++j)
        rbfCoefficient[j] =
            btfBilinear ? textureLod(rbfCoefficients, vec3(btfBilinearCoordinate, float(j)), 0.0).rgb
                        : texelFetch(rbfCoefficients, ivec3(texel, j), 0).rgb;
    float lx = light.x, ly = light.y;
    float lz = sqrt(max(0.0, 1.0 - lx * lx - ly * ly));
    if (rbfResolution > 0) {
        float r = float(rbfResolution) - 1.0;
        float s = abs(lx) + abs(ly) + lz;
        float u = ((lx + ly) / s + 1.0) * 0.5 * r;
        float v = ((ly - lx) / s + 1.0) * 0.5 * r;
        float su = min(r - 1.0, max(0.0, floor(u)));
        float sv = min(r - 1.0, max(0.0, floor(v)));
        float du = u - su, dv = v - sv;
        int i00 = int(su) + int(sv) * rbfResolution;
        vec3 sum = vec3(0.0);
        sum += ((1.0 - du) * (1.0 - dv)) * rbfProfile(i00);
        sum += (du * (1.0 - dv)) * rbfProfile(i00 + 1);
        sum += ((1.0 - du) * dv) * rbfProfile(i00 + rbfResolution);
        sum += (du * dv) * rbfProfile(i00 + rbfResolution + 1);
        return sum;
    }
    vec3 l = vec3(lx, ly, lz);
    float nearest = 3.4e38;
    for (int i = 0; i < rbfNodeCount; ++i) {
        vec3 d = l - texelFetch(rbfNodes, ivec2(i, 0), 0).rgb;
        nearest = min(nearest, d.x * d.x + d.y * d.y + d.z * d.z);
    }
    float total = 0.0;
    for (int i = 0; i < rbfNodeCount; ++i) {
        vec3 d = l - texelFetch(rbfNodes, ivec2(i, 0), 0).rgb;
        total += exp(-(d.x * d.x + d.y * d.y + d.z * d.z - nearest) * rbfInverseSigma2);
    }
    float kept = 0.0;
    vec3 sum = vec3(0.0);
    for (int i = 0; i < rbfNodeCount; ++i) {
        vec3 d = l - texelFetch(rbfNodes, ivec2(i, 0), 0).rgb;
        float w = exp(-(d.x * d.x + d.y * d.y + d.z * d.z - nearest) * rbfInverseSigma2) / total;
        if (w > kRbfThreshold) {
            sum += w * rbfProfile(i);
            kept += w;
        }
    }
    return sum / kept;
}
