#version 330 compatibility
// Method "lambert" (materials/lambert/Lambert.h): rho(x) * l_z.
#pragma include "common/btf_main.glsl"

uniform sampler2D lambertAlbedo;

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    // The value is linear in the albedo (half floats: filtered as the floats they are), so the
    // filtered albedo gives the bilinear blend of the texels' values.
    vec3 albedo = btfBilinear ? textureLod(lambertAlbedo, btfBilinearCoordinate, 0.0).rgb
                              : texelFetch(lambertAlbedo, texel, 0).rgb;
    return albedo * light.z;
}
