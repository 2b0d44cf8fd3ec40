#version 330 compatibility
// Method "ptm" (materials/ptm/Ptm.h): polynomial texture maps, Boßerhoff and Nicoll 2003 section
// 3.1,
//   P(x, l) = a0 lx^2 + a1 ly^2 + a2 lx ly + a3 lx + a4 ly + a5,
// per channel (rgb) or on the luminance times a base colour; one PTM for every view (front) or
// one per measured view blended over the 3 views around the view direction with the exact
// Delaunay weights (all). Same float operations and order as PtmMaterial::field/evaluate, so
// GPU == CPU.
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

// RGB. rgb: layer 6 s + k = a_k of (R, G, B); luminance: layer 2 s = (a0, a1, a2), layer 2 s + 1 =
// (a3, a4, a5); s = the view slot (0 for front, the measured view for all).
uniform sampler2DArray ptmCoefficients;
uniform sampler2DArray ptmColour;  // luminance: RGB base colour, layer = view slot
uniform sampler2D ptmViewTable;    // views=all: view interpolation (common/directions.glsl)
uniform int ptmLuminance;          // 1: luminance PTM x colour, 0: one PTM per channel
uniform int ptmPerView;            // 1: one PTM per measured view, 0: slot 0 for every view

// One layer of the texel's data; filtered (btfBilinear): the field is linear in the coefficients
// (half or float, filtered as the floats they are), so filtering them blends the texels' fields,
// and btfEvaluate clamps the blend (PtmMaterial::finishLinear). Luminance materials, a product of
// colour and coefficients, read their texel here and btf_main.glsl blends four texels' values
// (PtmMaterial::linearInParameters).
vec3 ptmTexel(sampler2DArray s, ivec2 texel, int layer) {
    return btfBilinear ? textureLod(s, vec3(btfBilinearCoordinate, float(layer)), 0.0).rgb
                       : texelFetch(s, ivec3(texel, layer), 0).rgb;
}

vec3 ptmField(ivec2 texel, int slot, float lx, float ly) {
    float mx = lx * lx, my = ly * ly, mxy = lx * ly;
    if (ptmLuminance != 0) {
        vec3 a = ptmTexel(ptmCoefficients, texel, 2 * slot);
        vec3 b = ptmTexel(ptmCoefficients, texel, 2 * slot + 1);
        float l = b.z;
        l += a.x * mx;
        l += a.y * my;
        l += a.z * mxy;
        l += b.x * lx;
        l += b.y * ly;
        return ptmTexel(ptmColour, texel, slot) * l;
    }
    int layer = 6 * slot;
    vec3 sum = ptmTexel(ptmCoefficients, texel, layer + 5);
    sum += ptmTexel(ptmCoefficients, texel, layer) * mx;
    sum += ptmTexel(ptmCoefficients, texel, layer + 1) * my;
    sum += ptmTexel(ptmCoefficients, texel, layer + 2) * mxy;
    sum += ptmTexel(ptmCoefficients, texel, layer + 3) * lx;
    sum += ptmTexel(ptmCoefficients, texel, layer + 4) * ly;
    return sum;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    // Measured values are never negative: a polynomial's dip below 0 is clamped.
    if (ptmPerView == 0) return max(ptmField(texel, 0, light.x, light.y), vec3(0.0));
    ivec3 index;
    vec3 weight;
    btfLookupDirections(ptmViewTable, view, index, weight);
    vec3 sum = vec3(0.0);
    for (int j = 0; j < 3; ++j) {
        if (weight[j] > 0.0) sum += weight[j] * ptmField(texel, index[j], light.x, light.y);
    }
    return max(sum, vec3(0.0));
}
