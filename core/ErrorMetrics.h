// osgBTF: how far a model is from the measured data.
//
// Per-texel error (Meseth et al. 2003 section 4.1): for texel x, the mean over all measured (view,
// light) pairs of the length of the RGB difference |BTF(x, v, l) - M(x, v, l)|, with 8-bit data
// scaled to [0, 1] (the loaders already do). Reported as average, minimum and maximum over texels.
// RMSE is over every channel value; PSNR uses a peak of 1 (the 8-bit white level), so it stays
// comparable between materials; for HDR data it is still defined but values above 1 make it
// pessimistic.
#pragma once

#include <functional>
#include <vector>

#include "core/MeasuredBtf.h"

namespace osgBTF {

struct ErrorSummary {
    double average = 0, minimum = 0, maximum = 0;  ///< of the per-texel error
    double rmse = 0;
    double psnr = 0;                  ///< dB, +infinity for identical data
    std::vector<float> perTexel;      ///< width*height, rows bottom-up (for error maps); NaN
                                      ///< for texels left out of a subsample
    std::size_t nonFiniteValues = 0;  ///< NaN/Inf produced by the model; counted as errors
    std::size_t texelsCompared = 0;   ///< all texels, or the subsample's size
};

/** Fills a texel's ABRDF ([view][light][rgb], the layout of MeasuredBtf::abrdf). */
using AbrdfEvaluator = std::function<void(std::size_t texel, float* abrdfOut)>;

/** Compares a model, evaluated texel by texel (in parallel), with the measured data. The model
 *  must be evaluated at the measured directions of `measured`. With `texels` (ascending, e.g.
 *  randomTexels()), only those texels are compared, at all their (view, light) pairs: the
 *  statistics are then those of the subsample. With `pairs` (image indices, view * lights +
 *  light), only those (view, light) pairs are compared: the model need not fill the others. */
ErrorSummary computeError(const BtfSource& measured, const AbrdfEvaluator& model,
                          const std::vector<std::size_t>* texels = nullptr,
                          const std::vector<std::size_t>* pairs = nullptr);
/** Compares two BTFs of the same size and direction sets; throws Error otherwise. */
ErrorSummary computeError(const MeasuredBtf& measured, const MeasuredBtf& model);

}  // namespace osgBTF
