#version 330 compatibility
// Method "rf" (materials/rf/Rf.h): reflectance fields, one per measured view,
//   RF_v(x, l) = rho_d(x) + rho_v(x, v) * sum_i max(0, (a, b, c)_vi(x) . l)^n_vi(x),
// blended over the 3 measured views around the view direction with the exact Delaunay weights.
// Boßerhoff and Nicoll 2003's variants: without rho_d (rfDiffuse = 0) and with k lobes per colour
// channel (rfLobeChannels = 3), rho_v then scaling each channel's own lobe sum. Same float math and
// order as RfMaterial::evaluate, so GPU == CPU.
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

uniform sampler2D rfRhoD;         // RGB, 8-bit (a black 1x1 texture when rfDiffuse = 0)
uniform sampler2DArray rfRhoV;    // RGB half, layer = view
uniform sampler2DArray rfLobes;   // (a, b, c, n) half,
                                  // layer = (view * rfLobeChannels + channel) * rfLobeCount + lobe
uniform sampler2D rfViewTable;    // view interpolation (common/directions.glsl)
uniform int rfLobeCount;          // lobes per view, or per view and channel
uniform int rfLobeChannels;       // 1: luminance lobes; 3: lobes per colour channel
uniform int rfDiffuse;            // 1: rho_d; 0: none

float rfLobeSum(ivec2 texel, int firstLayer, vec3 light) {
    float sum = 0.0;
    for (int i = 0; i < rfLobeCount; ++i) {
        vec4 p = texelFetch(rfLobes, ivec3(texel, firstLayer + i), 0);
        float base = p.x * light.x + p.y * light.y + p.z * light.z;
        // pow(0, n) is undefined in GLSL: test the base as the CPU does.
        sum += base > 0.0 ? pow(base, p.w) : 0.0;
    }
    return sum;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    ivec3 index;
    vec3 weight;
    btfLookupDirections(rfViewTable, view, index, weight);
    vec3 color = texelFetch(rfRhoD, rfDiffuse != 0 ? texel : ivec2(0), 0).rgb;
    for (int j = 0; j < 3; ++j) {
        if (weight[j] > 0.0) {
            vec3 rho = texelFetch(rfRhoV, ivec3(texel, index[j]), 0).rgb;
            int first = index[j] * rfLobeChannels * rfLobeCount;
            vec3 sum = rfLobeChannels == 3
                           ? vec3(rfLobeSum(texel, first, light),
                                  rfLobeSum(texel, first + rfLobeCount, light),
                                  rfLobeSum(texel, first + 2 * rfLobeCount, light))
                           : vec3(rfLobeSum(texel, first, light));
            color += weight[j] * (rho * sum);
        }
    }
    return color;
}
