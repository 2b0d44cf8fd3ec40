#include "core/ErrorMetrics.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/Error.h"

namespace osgBTF {

ErrorSummary computeError(const BtfSource& measured, const AbrdfEvaluator& model,
                          const std::vector<std::size_t>* subset,
                          const std::vector<std::size_t>* pairSubset) {
    ErrorSummary summary;
    std::vector<std::size_t> all;
    if (!subset) {
        all.resize(measured.texelCount());
        std::iota(all.begin(), all.end(), std::size_t(0));
        subset = &all;
    }
    const std::size_t texels = subset->size();
    const std::size_t values = measured.imageCount() * 3;
    std::vector<std::size_t> allPairs;
    if (!pairSubset) {
        allPairs.resize(values / 3);
        std::iota(allPairs.begin(), allPairs.end(), std::size_t(0));
        pairSubset = &allPairs;
    }
    const std::size_t pairs = pairSubset->size();
    summary.texelsCompared = texels;
    summary.perTexel.assign(measured.texelCount(),
                            subset == &all ? 0.0f : std::numeric_limits<float>::quiet_NaN());
    // Per texel, summed in texel order afterwards: the totals do not depend on how the work was
    // split between threads (reports and tests compare them exactly).
    std::vector<double> squaredOf(texels, 0.0);
    std::vector<std::size_t> nonFiniteOf(texels, 0);
    const std::size_t block = std::max<std::size_t>(measured.abrdfBlockTexels(), 16);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, texels, block), [&](const auto& range) {
        std::vector<float> truths(range.size() * values), approx(values);
        measured.readAbrdfs(subset->data() + range.begin(), range.size(), truths.data());
        for (std::size_t j = range.begin(); j != range.end(); ++j) {
            const std::size_t t = (*subset)[j];
            const float* truth = truths.data() + (j - range.begin()) * values;
            model(t, approx.data());
            double lengthSum = 0;
            for (const std::size_t p : *pairSubset) {
                double sq = 0;
                for (int c = 0; c < 3; ++c) {
                    double d = double(truth[p * 3 + c]) - double(approx[p * 3 + c]);
                    if (!std::isfinite(d)) {
                        ++nonFiniteOf[j];
                        // A NaN must not vanish from the averages: count it as a full-scale miss.
                        d = 1.0;
                    }
                    sq += d * d;
                }
                squaredOf[j] += sq;
                lengthSum += std::sqrt(sq);
            }
            summary.perTexel[t] = float(lengthSum / double(pairs));
        }
    });
    double squared = 0;
    for (std::size_t j = 0; j < texels; ++j) {
        squared += squaredOf[j];
        summary.nonFiniteValues += nonFiniteOf[j];
    }
    double sum = 0;
    summary.minimum = std::numeric_limits<double>::infinity();
    summary.maximum = 0;
    for (std::size_t t : *subset) {
        const double e = summary.perTexel[t];
        sum += e;
        summary.minimum = std::min(summary.minimum, double(e));
        summary.maximum = std::max(summary.maximum, double(e));
    }
    summary.average = texels ? sum / double(texels) : 0.0;
    if (!texels) summary.minimum = 0;
    const double mse = squared / double(texels * pairs * 3);
    summary.rmse = std::sqrt(mse);
    summary.psnr = mse > 0 ? 10.0 * std::log10(1.0 / mse) : std::numeric_limits<double>::infinity();
    return summary;
}

ErrorSummary computeError(const MeasuredBtf& measured, const MeasuredBtf& model) {
    if (measured.width() != model.width() || measured.height() != model.height() ||
        !(measured.views() == model.views()) || !(measured.lights() == model.lights()))
        throw Error("cannot compare BTFs of different sizes or direction sets (" +
                    std::to_string(measured.width()) + "x" + std::to_string(measured.height()) +
                    " vs " + std::to_string(model.width()) + "x" + std::to_string(model.height()) +
                    ")");
    return computeError(measured, [&](std::size_t texel, float* out) { model.abrdf(texel, out); });
}

}  // namespace osgBTF
