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

// Mip-mapped materials (core/MipPyramid.h): level l is the rectangle osgBTF_mipLevel[l] = (x, y,
// width, height) of the material's texels; osgBTF_mipLevels = 1 for a material without levels
// (its one rectangle is the whole material).
const int osgBTF_maxMipLevels = 16;
uniform int osgBTF_mipLevels;
uniform ivec4 osgBTF_mipLevel[osgBTF_maxMipLevels];

/** The texel of level `level` at uv, with wrap-around tiling; texelFetch keeps the GPU equal to
 *  the CPU reference (MipLayout::texelAt). */
ivec2 btfLevelTexel(vec2 uv, int level) {
    ivec4 r = osgBTF_mipLevel[level];
    vec2 f = fract(uv);
    return r.xy + clamp(ivec2(floor(f * vec2(r.zw))), ivec2(0), r.zw - ivec2(1));
}

/** GL_LINEAR's neighbours of uv in a grid of `size` texels that repeats (GL_REPEAT): along each
 *  axis the texels i0 and i1 (the next, wrapping) and i1's weight w, texel centres at
 *  (i + 0.5) / size, w = frac(uv size - 0.5). Left of (below) the first centre, i0 is the last
 *  texel. Texels relative to the grid: the caller places them (a mip level's rectangle, a
 *  coordinate map's entries). materials/BilinearTaps.h is the CPU side. */
void btfBilinearNeighbours(vec2 uv, ivec2 size, out ivec2 i0, out ivec2 i1, out vec2 w) {
    vec2 s = fract(uv) * vec2(size) - 0.5;
    vec2 first = floor(s);
    w = s - first;
    i0 = min(ivec2(first), size - ivec2(1));
    i0 = ivec2(i0.x < 0 ? size.x - 1 : i0.x, i0.y < 0 ? size.y - 1 : i0.y);
    i1 = ivec2(i0.x + 1 == size.x ? 0 : i0.x + 1, i0.y + 1 == size.y ? 0 : i0.y + 1);
}

/** The nearest base texel. */
ivec2 btfNearestTexel(vec2 uv) {
    return btfLevelTexel(uv, 0);
}

/** The level of detail at uv as GL computes it for a texture of the base's size: log2 of the
 *  longer screen-space step in base texels. Called in uniform control flow (derivatives). */
float btfMipLod(vec2 uv) {
    vec2 base = vec2(osgBTF_mipLevel[0].zw);
    vec2 dx = dFdx(uv) * base, dy = dFdy(uv) * base;
    return 0.5 * log2(max(dot(dx, dx), dot(dy, dy)));
}
