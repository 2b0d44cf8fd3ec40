// osgBTF: numeric helpers that several methods' fitters and models share and that belong to no one
// model: the storage roundings (half float, 8-bit fixed point), Meseth et al. 2003's per-texel
// error, the memory count of a fitted file and a two-variable non-negative least squares.
#pragma once

#include <cmath>
#include <cstddef>
#include <vector>

#include "materials/Material.h"

namespace osgBTF {

/** Rounds to the nearest half float (clamped to its finite range). */
float roundHalf(double x);

/** Rounds to the 8-bit fixed point the file and the GPU hold: k / 255, k = 0..255. */
inline float quantizeUNorm8(double x) {
    const double c = x > 1.0 ? 1.0 : (x > 0.0 ? x : 0.0);
    return float(std::round(c * 255.0)) / 255.0f;
}

/** Meseth et al. 2003's per-texel error: mean over pairs of |measured - model| (RGB length). */
double texelError(const std::vector<double>& rgb, const std::vector<float>& model);

/** Bytes one value of a texture of this kind takes in the file and on the GPU. */
inline double bytesPerValue(MaterialTexture::PixelKind kind) {
    return kind == MaterialTexture::UNorm8 ? 1.0 : kind == MaterialTexture::Half ? 2.0 : 4.0;
}

/** The GPU limits the methods lay their textures out for: 2D texture size (GL_MAX_TEXTURE_SIZE)
 *  and array layers (GL_MAX_ARRAY_TEXTURE_LAYERS), what current desktop GPUs offer. */
constexpr int kMaxTextureSize = 16384;
constexpr int kMaxArrayLayers = 2048;

/** Values and bytes per texel of a fitted material's textures, by their storage kinds. */
MemoryFootprint footprintOf(const FittedMaterial& file, std::size_t texels);

/** Least squares y ~ alpha f + beta g with alpha, beta >= 0 (the two-variable NNLS, solved by
 *  checking the unconstrained optimum and both faces). Strided access: element j at [j * stride].
 */
void nonNegativeLeastSquares2(const double* f, const double* g, const double* y, std::size_t n,
                              std::size_t strideY, double& alpha, double& beta);

}  // namespace osgBTF
