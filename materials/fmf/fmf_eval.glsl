// The evaluation of materials/fmf/fmf.frag and streaming/bsvtf.frag (materials/fmf/Fmf.h): the
// same loops as FmfMaterial::evaluate/factorSums on the CPU. The U rows of the 9 (view, light)
// combinations are blended per group of 4 components, dotted with the texel's Eigen-Texture
// values, then decoded once (colour model or exp), then divided by the light's cosine when the
// data include it. The includer defines where the Eigen-Textures come from (a texture array, or
// BSVTF's tile cache through a lookup table):
vec4 fmfEigenTexture(ivec2 texel, int layer);

// Layer = measured view; texel (group g, light * 3 + channel) = components 4g..4g+3 of the row.
uniform sampler2DArray fmfU;
uniform sampler2D fmfViewTable;
uniform sampler2D fmfLightTable;
uniform int fmfShared;  // 1: fmf, one SxV for the three channels; 0: dfmf, one per channel
uniform ivec3 fmfGroups;
uniform ivec3 fmfLayerOffset;
uniform int fmfColorModel;  // dfmf: btflib's 0 RGB, 1 YUV, 3 PCA, 4 YCoCg, 11 exp-YUV
uniform vec3 fmfColorRows[3];
uniform vec3 fmfColorMean;
uniform int fmfDrr;  // fmf: values are log(rgb + eps)
uniform float fmfEps;
uniform int fmfCosine;  // values include cos(theta_light)

vec3 fmfYuv(float y, float u, float v) {
    return vec3(y + 1.13983 * v, y - 0.39465 * u - 0.5806 * v, y + 2.03211 * u);
}

vec3 fmfDecode(vec3 s) {
    if (fmfShared != 0) return fmfDrr != 0 ? exp(s) - vec3(fmfEps) : s;
    if (fmfColorModel == 1) return fmfYuv(s.x, s.y, s.z);
    if (fmfColorModel == 3)
        return s.x * fmfColorRows[0] + s.y * fmfColorRows[1] + s.z * fmfColorRows[2] +
               fmfColorMean;
    if (fmfColorModel == 4) return vec3(s.x + s.y - s.z, s.x + s.z, s.x - s.y - s.z);
    if (fmfColorModel == 11) {
        float y = exp(s.x) - fmfEps;
        return fmfYuv(y, s.y * (y + fmfEps), s.z * (y + fmfEps));
    }
    return s;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    ivec3 vi, li;
    vec3 vw, lw;
    btfLookupDirections(fmfViewTable, view, vi, vw);
    btfLookupDirections(fmfLightTable, light, li, lw);
    // The combinations with weight > 0: U row (light * 3) and layer (view).
    float cw[9];
    ivec2 cr[9];
    int n = 0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            float w = vw[i] * lw[j];
            if (!(w > 0.0)) continue;
            cw[n] = w;
            cr[n] = ivec2(li[j] * 3, vi[i]);
            ++n;
        }
    vec3 sums = vec3(0.0);
    if (fmfShared != 0) {
        for (int g = 0; g < fmfGroups.x; ++g) {
            vec4 s = fmfEigenTexture(texel, g);
            for (int c = 0; c < 3; ++c) {
                vec4 u = vec4(0.0);
                for (int k = 0; k < n; ++k)
                    u += cw[k] * texelFetch(fmfU, ivec3(g, cr[k].x + c, cr[k].y), 0);
                sums[c] += dot(u, s);
            }
        }
    } else {
        for (int c = 0; c < 3; ++c)
            for (int g = 0; g < fmfGroups[c]; ++g) {
                vec4 u = vec4(0.0);
                for (int k = 0; k < n; ++k)
                    u += cw[k] * texelFetch(fmfU, ivec3(g, cr[k].x + c, cr[k].y), 0);
                sums[c] += dot(u, fmfEigenTexture(texel, fmfLayerOffset[c] + g));
            }
    }
    vec3 rgb = fmfDecode(sums);
    if (fmfCosine != 0 && light.z > 1e-3) rgb *= 1.0 / light.z;
    return rgb;
}
