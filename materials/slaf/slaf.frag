#version 330 compatibility
// Method "slaf" (materials/slaf/Slaf.h): T(v) * (rho_d + rho_s * sum_i max(dot(C_i, v * l), 0)^n_i) * l_z,
// T blended between measured views with the exact Delaunay weights (common/directions.glsl).
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

uniform sampler2D slafRhoD;        // RGB, 8-bit
uniform sampler2D slafRhoS;        // RGB, 8-bit
uniform sampler2D slafLobes;       // (Cx, Cy, Cz, n), lobe i in rows [i * height, (i + 1) * height)
uniform sampler2DArray slafScale;  // T, one layer per measured view
uniform sampler2D slafViewTable;
uniform int slafLobeCount;
uniform int slafCosine;  // the model's own l_z factor (see laf.frag)

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    ivec3 index;
    vec3 weight;
    btfLookupDirections(slafViewTable, view, index, weight);
    vec3 T = vec3(0.0);
    T += weight.x * texelFetch(slafScale, ivec3(texel, index.x), 0).rgb;
    T += weight.y * texelFetch(slafScale, ivec3(texel, index.y), 0).rgb;
    T += weight.z * texelFetch(slafScale, ivec3(texel, index.z), 0).rgb;
    vec3 vl = view * light;
    float sum = 0.0;
    for (int i = 0; i < slafLobeCount; ++i) {
        vec4 lobe = texelFetch(slafLobes, ivec2(texel.x, texel.y + i * osgBTF_size.y), 0);
        float base = dot(lobe.xyz, vl);
        // pow is undefined for a negative base: the lobe is clamped at 0, as on the CPU.
        if (base > 0.0) sum += pow(base, lobe.w);
    }
    vec3 bracket = texelFetch(slafRhoD, texel, 0).rgb + texelFetch(slafRhoS, texel, 0).rgb * sum;
    return T * (bracket * (slafCosine != 0 ? light.z : 1.0));
}
