#version 330 compatibility
// Method "lambert" (materials/lambert/Lambert.h): rho(x) * l_z.
#pragma include "common/btf_main.glsl"

uniform sampler2D lambertAlbedo;

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    return texelFetch(lambertAlbedo, texel, 0).rgb * light.z;
}
