#include "harness/FitScore.h"

#include <chrono>
#include <limits>

#include "harness/batch/Holdout.h"

namespace osgBTF {

namespace {

double elapsedSeconds(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

}  // namespace

std::vector<std::size_t> errorSubsample(const BtfSource& measured, long long requested) {
    const std::size_t count = errorTexelCount(measured, requested);
    if (count < measured.texelCount()) return randomTexels(measured, count);
    return {};
}

ErrorSummary fitError(const BtfSource& measured, const Material& material,
                      const std::vector<std::size_t>& texels) {
    return computeError(
        measured, [&](std::size_t texel, float* out) { material.evaluateMeasured(texel, out); },
        texels.empty() ? nullptr : &texels);
}

FitScore scoreFit(const BtfSource& measured, const Material& material,
                  const std::vector<std::size_t>& texels) {
    FitScore score;
    score.error = fitError(measured, material, texels);
    score.memory = material.memory();
    score.compressionRatio = score.memory.bytesPerTexel > 0
                                 ? double(measured.imageCount() * 3) / score.memory.bytesPerTexel
                                 : std::numeric_limits<double>::quiet_NaN();
    return score;
}

MethodScore fitAndScore(const BtfSource& measured, const MethodInfo& method,
                        const FitOptions& options, long long errorTexels, double holdoutFraction,
                        const std::function<void(Material&)>& keep) {
    MethodScore score;
    const std::vector<std::size_t> texels = errorSubsample(measured, errorTexels);
    {
        const auto start = std::chrono::steady_clock::now();
        osg::ref_ptr<Material> fitted = method.fit(measured, options);
        score.fitSeconds = elapsedSeconds(start);
        score.fit = scoreFit(measured, *fitted, texels);
        if (keep) keep(*fitted);
    }  // the fitted material goes before the second fit
    if (holdoutFraction > 0) {
        const batch::HoldoutSplit split =
            batch::holdoutSplit(measured.viewCount(), measured.lightCount(), holdoutFraction);
        const batch::DirectionSubsetSource kept(measured, split);
        const auto start = std::chrono::steady_clock::now();
        const osg::ref_ptr<Material> withoutThem = method.fit(kept, options);
        score.heldOutFitSeconds = elapsedSeconds(start);
        score.heldOut =
            scoreHeldOut(measured, *withoutThem, split, texels.empty() ? nullptr : &texels);
    }
    return score;
}

}  // namespace osgBTF
