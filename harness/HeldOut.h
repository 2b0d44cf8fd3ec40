// osgBTF harness: how a model does on directions it was not fitted on, in the figures the RTI
// field reports (PSNR and SSIM of relit images, e.g. Ponchio et al. 2018 and Dulecha et al. 2020
// on held-out lights) next to the per-texel error of Meseth et al. 2003.
//
// A model fitted without the held-out directions of a split (harness/batch/Holdout.h) is
// evaluated at the left-out (view, light) pairs: the per-texel error, RMSE and PSNR over those
// pairs (computeError: every texel, or the caller's subsample), and the SSIM (Wang, Bovik,
// Sheikh, Simoncelli 2004) of whole relit images, over up to `maxImages` left-out images chosen
// evenly among them (SSIM needs whole images, and an image costs a model evaluation per texel).
#pragma once

#include <cstddef>
#include <vector>

#include "core/ErrorMetrics.h"
#include "harness/batch/Holdout.h"
#include "materials/Material.h"

namespace osgBTF {

/** Mean SSIM of two images of `channels` interleaved float channels (row-major, width x height):
 *  per channel, the SSIM index of Wang et al. 2004 with their constants (K1 = 0.01, K2 = 0.03,
 *  dynamic range L = 1, the 8-bit white level the loaders scale to), an 11 x 11 Gaussian window
 *  of sigma 1.5 at every position where it fits inside the image; averaged over positions, then
 *  channels. An image narrower or lower than 11 uses the largest odd window that fits (the same
 *  Gaussian, truncated and normalised). 1 for identical images. */
double structuralSimilarity(const float* a, const float* b, int width, int height, int channels);

struct HeldOutScores {
    ErrorSummary error;     ///< per-texel error, RMSE and PSNR over the left-out pairs
    double ssim = 0;        ///< mean SSIM over the scored images
    std::size_t pairs = 0;  ///< left-out (view, light) pairs
    std::size_t imagesScored = 0;
};

/** Scores `model` (fitted without the split's left-out directions) against `measured`.
 *  `texels`: the subsample the per-texel error uses (null: all). Throws Error when the split
 *  leaves nothing out or the model's size differs from the data's. */
HeldOutScores scoreHeldOut(const BtfSource& measured, const Material& model,
                           const batch::HoldoutSplit& split,
                           const std::vector<std::size_t>* texels = nullptr,
                           std::size_t maxImages = 8);

}  // namespace osgBTF
