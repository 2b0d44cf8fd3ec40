// The local frame, view direction and filtered texels of a fragment, shared by btf_main.glsl
// (point lights) and environment.glsl (environment lighting) so that both shade the same
// directions and blend the same texels.
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

/** The level of detail at uv as GL computes it for a texture of `size` texels: log2 of the
 *  longer screen-space step in texels. Called in uniform control flow (derivatives). */
float btfLod(vec2 uv, vec2 size) {
    vec2 dx = dFdx(uv) * size, dy = dFdy(uv) * size;
    return 0.5 * log2(max(dot(dx, dx), dot(dy, dy)));
}

/** btfLod for the material's base level. */
float btfMipLod(vec2 uv) {
    return btfLod(uv, vec2(osgBTF_mipLevel[0].zw));
}

// The texels a fragment evaluates and their shares of its value (at most four per level, two
// levels), in the order the CPU references add them up (materials/BilinearTaps.h: FilterTaps,
// mipFilterTaps). Texels of weight 0 are left out: they cost no evaluation.
// Eight named variables, not arrays: an array indexed per fragment lives in memory on a software
// rasteriser, and llvmpipe then spent ~2.5 ms per 256 x 256 pass on it in every program, also
// where a fragment reads one texel (lambert's whole shading took 0.4 ms without it). Reads and
// writes pick a variable by comparisons, which stay in registers.
const int btfMaxTaps = 8;
ivec2 btfTap0, btfTap1, btfTap2, btfTap3, btfTap4, btfTap5, btfTap6, btfTap7;
float btfWeight0, btfWeight1, btfWeight2, btfWeight3, btfWeight4, btfWeight5, btfWeight6,
    btfWeight7;
int btfTapCount = 0;

void btfAddTap(ivec2 texel, float weight) {
    if (weight > 0.0) {
        int k = btfTapCount;
        if (k == 0) {
            btfTap0 = texel;
            btfWeight0 = weight;
        } else if (k == 1) {
            btfTap1 = texel;
            btfWeight1 = weight;
        } else if (k == 2) {
            btfTap2 = texel;
            btfWeight2 = weight;
        } else if (k == 3) {
            btfTap3 = texel;
            btfWeight3 = weight;
        } else if (k == 4) {
            btfTap4 = texel;
            btfWeight4 = weight;
        } else if (k == 5) {
            btfTap5 = texel;
            btfWeight5 = weight;
        } else if (k == 6) {
            btfTap6 = texel;
            btfWeight6 = weight;
        } else {
            btfTap7 = texel;
            btfWeight7 = weight;
        }
        ++btfTapCount;
    }
}

/** Tap k's texel (k < btfTapCount). */
ivec2 btfTapTexel(int k) {
    return k < 4 ? (k < 2 ? (k == 0 ? btfTap0 : btfTap1) : (k == 2 ? btfTap2 : btfTap3))
                 : (k < 6 ? (k == 4 ? btfTap4 : btfTap5) : (k == 6 ? btfTap6 : btfTap7));
}

/** Tap k's share of the fragment's value (k < btfTapCount). */
float btfTapWeight(int k) {
    return k < 4 ? (k < 2 ? (k == 0 ? btfWeight0 : btfWeight1)
                          : (k == 2 ? btfWeight2 : btfWeight3))
                 : (k < 6 ? (k == 4 ? btfWeight4 : btfWeight5)
                          : (k == 6 ? btfWeight6 : btfWeight7));
}

/** The four texels of `level` around uv, wrapped inside the level's rectangle of the atlas (the
 *  hardware's GL_REPEAT would wrap at the atlas's edge), with GL_LINEAR's weights; times
 *  `share`. */
void btfAddBilinearTaps(vec2 uv, int level, float share) {
    ivec4 r = osgBTF_mipLevel[level];
    ivec2 i0, i1;
    vec2 w;
    btfBilinearNeighbours(uv, r.zw, i0, i1, w);
    btfAddTap(r.xy + i0, share * (1.0 - w.x) * (1.0 - w.y));
    btfAddTap(r.xy + ivec2(i1.x, i0.y), share * w.x * (1.0 - w.y));
    btfAddTap(r.xy + ivec2(i0.x, i1.y), share * (1.0 - w.x) * w.y);
    btfAddTap(r.xy + i1, share * w.x * w.y);
}

/** The taps at uv of a mip-mapped material as GL_LINEAR_MIPMAP_LINEAR (`bilinear`) or
 *  GL_NEAREST_MIPMAP_LINEAR picks them: levels floor(lod) and the next, the coarser one's share
 *  lod - floor(lod); magnified fragments, and a material without levels, read level 0 alone.
 *  One definition for point lights (btf_main.glsl) and environment lighting (environment.glsl),
 *  so that both filter a minified material alike. Calls btfMipLod: uniform control flow. */
void btfAddMipTaps(vec2 uv, bool bilinear) {
    float lod = btfMipLod(uv);
    int level = 0;
    float coarserWeight = 0.0;
    if (osgBTF_mipLevels > 1) {
        // NaN (no derivative) or negative: level 0.
        lod = lod > 0.0 ? min(lod, float(osgBTF_mipLevels - 1)) : 0.0;
        level = int(floor(lod));
        coarserWeight = lod - float(level);
    }
    int coarser = min(level + 1, osgBTF_mipLevels - 1);
    if (bilinear) {
        btfAddBilinearTaps(uv, level, 1.0 - coarserWeight);
        if (coarserWeight > 0.0) btfAddBilinearTaps(uv, coarser, coarserWeight);
    } else {
        btfAddTap(btfLevelTexel(uv, level), 1.0 - coarserWeight);
        if (coarserWeight > 0.0) btfAddTap(btfLevelTexel(uv, coarser), coarserWeight);
    }
}
