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

// The material's shape is compiled in (PtmMaterial::shaderDefines), not read from uniforms: a
// software rasterizer runs both sides of a branch on a uniform, so the views=all path and the
// other colour model cost every pass (README.md, "Pass cost"):
//   OSGBTF_PTM_LUMINANCE  luminance PTM x colour (else one PTM per channel)
//   OSGBTF_PTM_PER_VIEW   one PTM per measured view (else slot 0 for every view)
//   OSGBTF_PTM_FILTERED   the coefficients are filtered (TexelFilter::Parameters)

// RGB. rgb: layer 6 s + k = a_k of (R, G, B); luminance: layer 2 s = (a0, a1, a2), layer 2 s + 1 =
// (a3, a4, a5); s = the view slot (0 for front, the measured view for all).
uniform sampler2DArray ptmCoefficients;
uniform sampler2DArray ptmColour;  // luminance: RGB base colour, layer = view slot
uniform sampler2D ptmViewTable;    // views=all: view interpolation (common/directions.glsl)

// One layer of the texel's data; filtered: the field is linear in the coefficients (half or
// float, filtered as the floats they are), so filtering them blends the texels' fields, and
// btfEvaluate clamps the blend (PtmMaterial::finishLinear). A filtered material reads at
// btfBilinearCoordinate whenever btf_main.glsl sets btfBilinear (always, but through a coordinate
// map, whose variant reads each tap's own texel): one fetch either way, not both sides of a
// select. Luminance materials, a product of colour and coefficients, read their texel here and
// btf_main.glsl blends four texels' values (PtmMaterial::linearInParameters).
vec3 ptmTexel(sampler2DArray s, ivec2 texel, int layer) {
#if defined(OSGBTF_PTM_FILTERED) && !defined(OSGBTF_COORDINATE_MAP)
    return textureLod(s, vec3(btfBilinearCoordinate, float(layer)), 0.0).rgb;
#else
    return texelFetch(s, ivec3(texel, layer), 0).rgb;
#endif
}

vec3 ptmField(ivec2 texel, int slot, float lx, float ly) {
    float mx = lx * lx, my = ly * ly, mxy = lx * ly;
#ifdef OSGBTF_PTM_LUMINANCE
    vec3 a = ptmTexel(ptmCoefficients, texel, 2 * slot);
    vec3 b = ptmTexel(ptmCoefficients, texel, 2 * slot + 1);
    float l = b.z;
    l += a.x * mx;
    l += a.y * my;
    l += a.z * mxy;
    l += b.x * lx;
    l += b.y * ly;
    return ptmTexel(ptmColour, texel, slot) * l;
#else
    int layer = 6 * slot;
    vec3 sum = ptmTexel(ptmCoefficients, texel, layer + 5);
    sum += ptmTexel(ptmCoefficients, texel, layer) * mx;
    sum += ptmTexel(ptmCoefficients, texel, layer + 1) * my;
    sum += ptmTexel(ptmCoefficients, texel, layer + 2) * mxy;
    sum += ptmTexel(ptmCoefficients, texel, layer + 3) * lx;
    sum += ptmTexel(ptmCoefficients, texel, layer + 4) * ly;
    return sum;
#endif
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    // Measured values are never negative: a polynomial's dip below 0 is clamped.
#ifndef OSGBTF_PTM_PER_VIEW
    return max(ptmField(texel, 0, light.x, light.y), vec3(0.0));
#else
    ivec3 index;
    vec3 weight;
    btfLookupDirections(ptmViewTable, view, index, weight);
    vec3 sum = vec3(0.0);
    for (int j = 0; j < 3; ++j) {
        if (weight[j] > 0.0) sum += weight[j] * ptmField(texel, index[j], light.x, light.y);
    }
    return max(sum, vec3(0.0));
#endif
}
