#version 330 compatibility
// Method "hsh" (materials/hsh/Hsh.h): hemispherical harmonics (Gautron et al. 2004) in the RTI
// tools' order and normalisation, 4, 9 or 16 coefficients per channel; one fit for every view
// (front) or one per measured view blended over the 3 views around the view direction with the
// exact Delaunay weights (all). Same float operations and order as HshMaterial::basis/field/
// evaluate, so GPU == CPU.
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

// The material's shape is compiled in (HshMaterial::shaderDefines), not read from uniforms: a
// software rasterizer runs the views=all path whatever a uniform says, and a loop to a uniform
// count keeps the basis in memory indexed per lane (README.md, "Pass cost"):
//   OSGBTF_HSH_TERMS     4, 9 or 16
//   OSGBTF_HSH_PER_VIEW  one fit per measured view (else slot 0 for every view)
//   OSGBTF_HSH_FILTERED  the coefficients are filtered (TexelFilter::Parameters)
#ifndef OSGBTF_HSH_TERMS
#error "hsh.frag is compiled with OSGBTF_HSH_TERMS (HshMaterial::shaderDefines)"
#endif

// RGB; layer OSGBTF_HSH_TERMS * s + k = c_k of (R, G, B), s = the view slot (0 for front).
uniform sampler2DArray hshCoefficients;
uniform sampler2D hshViewTable;  // views=all: view interpolation (common/directions.glsl)

// The basis of Hsh.h; the constants are its normalisations rounded to float (the literals
// HshMaterial::basis rounds to).
void hshBasis(vec3 light, out float h[16]) {
    float x = light.x, y = light.y;
    float t = clamp(light.z, 0.0, 1.0);
    float r = sqrt(x * x + y * y);
    float cp = r > 0.0 ? x / r : 1.0;
    float sp = r > 0.0 ? y / r : 0.0;
    float t2 = t * t;
    float w = t2 - t;
    float s = sqrt(-w);
    float a = 2.0 * t - 1.0;
    float c2 = cp * cp - sp * sp, s2 = 2.0 * sp * cp;
    float c3 = cp * (4.0 * cp * cp - 3.0), s3 = sp * (3.0 - 4.0 * sp * sp);
    float q = 1.0 - 5.0 * t + 5.0 * t2;
    float s3t = -w * s;
    h[0] = 0.398942292;
    h[1] = 1.3819766 * cp * s;
    h[2] = 0.690988302 * a;
    h[3] = 1.3819766 * sp * s;
    h[4] = 3.09019351 * c2 * w;
    h[5] = 3.09019351 * cp * a * s;
    h[6] = 0.892062068 * (1.0 - 6.0 * t + 6.0 * t2);
    h[7] = 3.09019351 * sp * a * s;
    h[8] = 3.09019351 * s2 * w;
    h[9] = 6.67558098 * c3 * s3t;
    h[10] = 8.17588425 * c2 * a * w;
    h[11] = 5.17088318 * cp * s * q;
    h[12] = 1.05550206 * (-1.0 + 12.0 * t - 30.0 * t2 + 20.0 * t2 * t);
    h[13] = 5.17088318 * sp * s * q;
    h[14] = 8.17588425 * s2 * a * w;
    h[15] = 6.67558098 * s3 * s3t;
}

// Filtered: the field is linear in the coefficients, so filtering them blends the texels'
// fields, and btfEvaluate clamps the blend (HshMaterial::finishLinear). A filtered material
// reads at btfBilinearCoordinate whenever btf_main.glsl sets btfBilinear (always, but through a
// coordinate map, whose variant reads each tap's own texel): one fetch, not both sides of a
// select.
vec3 hshTexel(ivec2 texel, int layer) {
#if defined(OSGBTF_HSH_FILTERED) && !defined(OSGBTF_COORDINATE_MAP)
    return textureLod(hshCoefficients, vec3(btfBilinearCoordinate, float(layer)), 0.0).rgb;
#else
    return texelFetch(hshCoefficients, ivec3(texel, layer), 0).rgb;
#endif
}

vec3 hshField(ivec2 texel, int slot, float h[16]) {
    vec3 sum = vec3(0.0);
    for (int k = 0; k < OSGBTF_HSH_TERMS; ++k)
        sum += hshTexel(texel, slot * OSGBTF_HSH_TERMS + k) * h[k];
    return sum;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    float h[16];
    hshBasis(light, h);
    // Measured values are never negative: a dip of the harmonics below 0 is clamped.
#ifndef OSGBTF_HSH_PER_VIEW
    return max(hshField(texel, 0, h), vec3(0.0));
#else
    ivec3 index;
    vec3 weight;
    btfLookupDirections(hshViewTable, view, index, weight);
    vec3 sum = vec3(0.0);
    for (int j = 0; j < 3; ++j) {
        if (weight[j] > 0.0) sum += weight[j] * hshField(texel, index[j], h);
    }
    return max(sum, vec3(0.0));
#endif
}
