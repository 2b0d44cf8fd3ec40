// Direction interpolation on the GPU: the same baked table and nearest-cell lookup as
// DirectionInterpolator::lookupBaked on the CPU (core/DirectionInterpolation.h).

vec2 btfDirectionToDisc(vec3 d) {
    d.z = max(d.z, 0.0);
    d = normalize(d);
    return d.xy / (1.0 + d.z);
}

/** Up to 3 measured direction indices and weights (sum 1) for direction d. */
void btfLookupDirections(sampler2D indices, sampler2D weights, vec3 d, out ivec3 index,
                         out vec3 weight) {
    int r = textureSize(indices, 0).x;
    vec2 p = btfDirectionToDisc(d);
    ivec2 cell = clamp(ivec2(floor((p + 1.0) * 0.5 * float(r))), ivec2(0), ivec2(r - 1));
    index = ivec3(texelFetch(indices, cell, 0).rgb + 0.5);
    weight = texelFetch(weights, cell, 0).rgb;
}
