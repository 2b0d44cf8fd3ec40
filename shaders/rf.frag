#version 330 compatibility
// Method "rf" (materials/rf/Rf.h): reflectance fields, one per measured view,
//   RF_v(x, l) = rho_d(x) + rho_v(x, v) * sum_i max(0, (a, b, c)_vi(x) . l)^n_vi(x),
// blended over the 3 measured views around the view direction with the exact Delaunay weights.
// Same float math and order as RfMaterial::evaluate, so GPU == CPU.
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

uniform sampler2D rfRhoD;         // RGB, 8-bit
uniform sampler2DArray rfRhoV;    // RGB half, layer = view
uniform sampler2DArray rfLobes;   // (a, b, c, n) half, layer = view * rfLobeCount + lobe
uniform sampler2D rfViewTable;    // view interpolation (common/directions.glsl)
uniform int rfLobeCount;

float rfLobeSum(ivec2 texel, int view, vec3 light) {
    float sum = 0.0;
    for (int i = 0; i < rfLobeCount; ++i) {
        vec4 p = texelFetch(rfLobes, ivec3(texel, view * rfLobeCount + i), 0);
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
    vec3 color = texelFetch(rfRhoD, texel, 0).rgb;
    for (int j = 0; j < 3; ++j) {
        if (weight[j] > 0.0) {
            vec3 rho = texelFetch(rfRhoV, ivec3(texel, index[j]), 0).rgb;
            color += weight[j] * (rho * rfLobeSum(texel, index[j], light));
        }
    }
    return color;
}
