#version 330 compatibility
// Method "laf" (materials/laf/Laf.h):
//   (rho_d + rho_s * sum_i max(dot(C_i, v * l), 0)^n_i) * (lafCosine != 0 ? l_z : 1).
#pragma include "common/btf_main.glsl"

uniform sampler2D lafRhoD;   // RGB, 8-bit
uniform sampler2D lafRhoS;   // RGB, 8-bit
uniform sampler2D lafLobes;  // (Cx, Cy, Cz, n), lobe i in rows [i * height, (i + 1) * height)
uniform int lafLobeCount;
uniform int lafCosine;  // the model's own l_z factor (a BRDF model fitted to cosine-weighted data)

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    vec3 vl = view * light;
    float sum = 0.0;
    for (int i = 0; i < lafLobeCount; ++i) {
        vec4 lobe = texelFetch(lafLobes, ivec2(texel.x, texel.y + i * osgBTF_size.y), 0);
        float base = dot(lobe.xyz, vl);
        // pow is undefined for a negative base: the lobe is clamped at 0, as on the CPU.
        if (base > 0.0) sum += pow(base, lobe.w);
    }
    vec3 bracket = texelFetch(lafRhoD, texel, 0).rgb + texelFetch(lafRhoS, texel, 0).rgb * sum;
    return bracket * (lafCosine != 0 ? light.z : 1.0);
}
