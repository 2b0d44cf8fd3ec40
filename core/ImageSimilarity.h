// osgBTF: the structural similarity index (SSIM; Wang, Bovik, Sheikh, Simoncelli 2004), which
// Schwartz et al. 2013 report for streamed renders ("95.4 % to the converged image after 25 MB").
#pragma once

#include <vector>

namespace osgBTF {

/** Mean SSIM of two images of width x height x channels floats (any row order, the same for
 *  both), per channel with the paper's 11 x 11 Gaussian window (sigma 1.5, windows fully inside
 *  the image; an image smaller than the window uses one window over all of it), K1 = 0.01,
 *  K2 = 0.03 and dynamic range `range` (1 for [0, 1] data; the reference's peak for HDR),
 *  averaged over windows and channels. Throws Error for sizes that do not match or range <= 0. */
double structuralSimilarity(const std::vector<float>& a, const std::vector<float>& b, int width,
                            int height, int channels, double range);

}  // namespace osgBTF
