// The local frame, view direction and texel of a fragment, shared by btf_main.glsl (point
// lights) and environment.glsl (environment lighting) so that both shade the same directions.
// Included by them after they declare btfTexCoord, btfEyePosition, btfEyeNormal, btfEyeTangent,
// osgBTF_size and osgBTF_fixedView.

/** The orthonormal tangent frame (t, b, n) in eye space. */
void btfSurfaceFrame(out vec3 t, out vec3 b, out vec3 n) {
    n = normalize(btfEyeNormal);
    t = btfEyeTangent.xyz - n * dot(n, btfEyeTangent.xyz);
    if (dot(t, t) < 1e-12) {
        // No tangent attribute: any frame around the normal (anisotropy is then arbitrary).
        t = abs(n.x) < 0.9 ? cross(vec3(1.0, 0.0, 0.0), n) : cross(vec3(0.0, 1.0, 0.0), n);
    }
    t = normalize(t);
    b = cross(n, t) * (btfEyeTangent.w < 0.0 ? -1.0 : 1.0);
}

/** The direction toward the eye in the frame (t, b, n), or osgBTF_fixedView when it is set. */
vec3 btfLocalView(vec3 t, vec3 b, vec3 n) {
    // The centre of projection in homogeneous eye coordinates, P^-1 (0, 0, -1, 0): the eye point
    // (w > 0) of a perspective projection, the direction toward the eye (w = 0) of an
    // orthographic one. No test of a matrix entry against an exact value: a projection is only
    // defined up to a positive factor, and products or inverses of matrices round.
    vec4 centre = -gl_ProjectionMatrixInverse[2];
    vec3 toEye = normalize(centre.xyz - centre.w * btfEyePosition);
    vec3 view = vec3(dot(toEye, t), dot(toEye, b), dot(toEye, n));
    if (osgBTF_fixedView.w > 0.5) view = normalize(osgBTF_fixedView.xyz);
    return view;
}

/** The nearest texel with wrap-around tiling; texelFetch keeps the GPU equal to the CPU
 *  reference. */
ivec2 btfNearestTexel(vec2 uv) {
    vec2 f = fract(uv);
    return clamp(ivec2(floor(f * vec2(osgBTF_size))), ivec2(0), osgBTF_size - ivec2(1));
}
