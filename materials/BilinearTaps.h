// osgBTF: the texels and weights of GL_LINEAR with GL_REPEAT (and of GL_LINEAR_MIPMAP_LINEAR
// between two levels), on the CPU. One definition for every CPU reference of a filtered lookup
// (Material::evaluateFiltered, the coordinate-map render's evaluateThroughMap, the environment
// render's evaluateFoldedFiltered), in the float arithmetic of the shaders' btfBilinearNeighbours
// (shaders/common/surface_frame.glsl), so that a reference picks the texels and weights a fragment
// picks.
#pragma once

#include <algorithm>
#include <cmath>

#include "core/MipPyramid.h"

namespace osgBTF {

/** One axis of a grid of `size` texels that repeats: the texels i0 and i1 (the next one,
 *  wrapping) around texture coordinate t and i1's weight w, as GL_LINEAR with GL_REPEAT picks
 *  them: texel centres at (i + 0.5) / size, w = frac(t size - 0.5). Left of the first centre, i0
 *  is the last texel and i1 the first. A t that is not finite reads as 0 (fract would be NaN). */
inline void bilinearAxis(float t, int size, int& i0, int& i1, float& w) {
    float f = t - std::floor(t);  // fract: the texture repeats
    if (!std::isfinite(f)) f = 0.0f;
    const float s = f * float(size) - 0.5f;
    const float first = std::floor(s);
    w = s - first;
    i0 = std::min(int(first), size - 1);
    if (i0 < 0) i0 = size - 1;  // left of the first centre: blends with the last texel
    i1 = i0 + 1 == size ? 0 : i0 + 1;
}

/** The four texels of a width x height grid that repeats around texture coordinate (u, v), and
 *  their GL_LINEAR weights, in the order the shaders add them up: (x0, y0), (x1, y0), (x0, y1),
 *  (x1, y1). The weights sum to 1; some may be 0. */
struct BilinearTaps {
    int x[4], y[4];
    float weight[4];

    BilinearTaps(float u, float v, int width, int height) {
        int x0, x1, y0, y1;
        float a, b;
        bilinearAxis(u, width, x0, x1, a);
        bilinearAxis(v, height, y0, y1, b);
        const int xs[4] = {x0, x1, x0, x1}, ys[4] = {y0, y0, y1, y1};
        const float ws[4] = {(1.0f - a) * (1.0f - b), a * (1.0f - b), (1.0f - a) * b, a * b};
        for (int k = 0; k < 4; ++k) {
            x[k] = xs[k];
            y[k] = ys[k];
            weight[k] = ws[k];
        }
    }
};

/** One texel of a filtered lookup and its share of the value. */
struct FilterTap {
    int x, y;
    float weight;
};

/** The texels a filtered lookup blends (four per level, two levels), in the order the shaders
 *  add them up (surface_frame.glsl's btfTapTexel(k), btfTapWeight(k)). */
struct FilterTaps {
    FilterTap taps[8];
    int count = 0;
    void add(int x, int y, float weight) {
        // A texel whose weight is 0 is not evaluated, on the GPU neither.
        if (weight > 0.0f) taps[count++] = {x, y, weight};
    }
};

/** surface_frame.glsl's btfAddBilinearTaps: the four texels of `level` around uv, wrapped inside
 *  the level's rectangle, with GL_LINEAR's weights (frac(uv size - 0.5) along each axis) times
 *  `share`, in the shader's float arithmetic. */
inline void addBilinearTaps(FilterTaps& taps, float u, float v, const MipLevel& level,
                            float share) {
    int x0, x1, y0, y1;
    float a, b;
    bilinearAxis(u, level.width, x0, x1, a);
    bilinearAxis(v, level.height, y0, y1, b);
    taps.add(level.x + x0, level.y + y0, share * (1.0f - a) * (1.0f - b));
    taps.add(level.x + x1, level.y + y0, share * a * (1.0f - b));
    taps.add(level.x + x0, level.y + y1, share * (1.0f - a) * b);
    taps.add(level.x + x1, level.y + y1, share * a * b);
}

/** surface_frame.glsl's btfAddMipTaps with bilinear taps: for a mip-mapped `layout`, the four
 *  texels around (u, v) in level floor(lod) and in the next, the coarser level's share
 *  lod - floor(lod) (lod clamped to the levels; NaN or negative, magnification: level 0 alone);
 *  without levels, the four texels of the whole width x height material at any lod. One
 *  definition for the CPU references of point lights (Material::evaluateFiltered) and of
 *  environment lighting (evaluateFoldedFiltered), as the shaders share theirs. */
inline FilterTaps mipFilterTaps(const MipLayout& layout, int width, int height, float u, float v,
                                float lod) {
    FilterTaps taps;
    if (!layout.mipMapped()) {
        addBilinearTaps(taps, u, v, MipLevel{0, 0, width, height}, 1.0f);
        return taps;
    }
    const int last = layout.levelCount() - 1;
    // As the shader: NaN or negative (magnification) clamps to level 0.
    const float clamped = std::clamp(std::isnan(lod) ? 0.0f : lod, 0.0f, float(last));
    const int a = int(std::floor(clamped)), b = std::min(a + 1, last);
    const float coarser = clamped - float(a);
    addBilinearTaps(taps, u, v, layout.levels()[std::size_t(a)], 1.0f - coarser);
    if (coarser > 0.0f) addBilinearTaps(taps, u, v, layout.levels()[std::size_t(b)], coarser);
    return taps;
}

}  // namespace osgBTF
