// osgBTF harness: how a fit is scored, in one place. `btf fit` (and so `btf compare`, which runs
// it for every method and scores the fitted files again for its tables), `btf batch`'s jobs and
// the Python module's error(), error_of() and compare() all score with these: Meseth et al.
// 2003's per-texel error (core/ErrorMetrics.h) over the same random texels for every method of a
// material, the memory as stored for rendering, the compression against the measured data as the
// Bonn files store it (8-bit RGB per (view, light) pair), and, for a fit made without some
// directions, the scores on those (harness/HeldOut.h).
#pragma once

#include <cstddef>
#include <functional>
#include <optional>
#include <vector>

#include "core/BtfSource.h"
#include "core/ErrorMetrics.h"
#include "harness/HeldOut.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

/** The texels a fit's error is computed on: a random subsample of errorTexelCount(measured,
 *  requested) texels (randomTexels' fixed seed, so the same texels for every method of a
 *  material), or empty for all of them. */
std::vector<std::size_t> errorSubsample(const BtfSource& measured, long long requested);

/** Meseth et al. 2003's error of `material`, fitted to `measured` (evaluated at its measured
 *  directions, Material::evaluateMeasured), over `texels` (empty: all). */
ErrorSummary fitError(const BtfSource& measured, const Material& material,
                      const std::vector<std::size_t>& texels);

/** What a fitted material scores against the data it was fitted to. */
struct FitScore {
    ErrorSummary error;      ///< fitError over the texels given
    MemoryFootprint memory;  ///< Material::memory(): as stored for rendering
    /** 8-bit RGB per measured (view, light) pair, over memory.bytesPerTexel (NaN for none). */
    double compressionRatio = 0;
};
FitScore scoreFit(const BtfSource& measured, const Material& material,
                  const std::vector<std::size_t>& texels);

/** A method fitted and scored (fitAndScore). */
struct MethodScore {
    double fitSeconds = 0;
    FitScore fit;  ///< over errorSubsample(measured, errorTexels)
    /** With a held-out fraction: the second fit's time and its scores on the left-out pairs. */
    std::optional<HeldOutScores> heldOut;
    double heldOutFitSeconds = 0;
};

/** Fits `method` to `measured` with `options` and scores the fit (scoreFit over
 *  errorSubsample(measured, errorTexels)); `keep`, when given, then gets the fitted material (to
 *  save it: it may release the material's arrays), which is dropped before, with
 *  holdoutFraction > 0, the method is fitted again without a held-out split of the directions
 *  (batch::holdoutSplit) and scored on them (scoreHeldOut, over the same texels). `btf batch`'s
 *  job and the Python module's compare(). Throws what the fits and the split throw. */
MethodScore fitAndScore(const BtfSource& measured, const MethodInfo& method,
                        const FitOptions& options, long long errorTexels, double holdoutFraction,
                        const std::function<void(Material&)>& keep = {});

}  // namespace osgBTF
