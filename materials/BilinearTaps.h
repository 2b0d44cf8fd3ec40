// osgBTF: the texels and weights of GL_LINEAR with GL_REPEAT, on the CPU. One definition for
// every CPU reference of a filtered lookup (Material::evaluateFiltered, the coordinate-map render's
// evaluateThroughMap, the environment render's evaluateFoldedFiltered), in the float arithmetic of
// the shaders' btfBilinearNeighbours (shaders/common/surface_frame.glsl), so that a reference
// picks the texels and weights a fragment picks.
#pragma once

#include <algorithm>
#include <cmath>

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

}  // namespace osgBTF
