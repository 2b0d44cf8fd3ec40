#include "core/ErrorMetrics.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/combinable.h>
#include <tbb/parallel_for.h>

#include "core/Error.h"

namespace osgBTF {

ErrorSummary computeError(const MeasuredBtf& measured, const AbrdfEvaluator& model) {
    ErrorSummary summary;
    const std::size_t texels = measured.texelCount();
    const std::size_t values = measured.viewCount() * measured.lightCount() * 3;
    const std::size_t pairs = values / 3;
    summary.perTexel.assign(texels, 0.0f);
    struct Partial {
        double squared = 0;
        std::size_t nonFinite = 0;
    };
    tbb::combinable<Partial> partials;
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, texels, 64), [&](const auto& range) {
        std::vector<float> truth(values), approx(values);
        Partial& partial = partials.local();
        for (std::size_t t = range.begin(); t != range.end(); ++t) {
            measured.abrdf(t, truth.data());
            model(t, approx.data());
            double lengthSum = 0;
            for (std::size_t p = 0; p < pairs; ++p) {
                double sq = 0;
                for (int c = 0; c < 3; ++c) {
                    double d = double(truth[p * 3 + c]) - double(approx[p * 3 + c]);
                    if (!std::isfinite(d)) {
                        ++partial.nonFinite;
                        // A NaN must not vanish from the averages: count it as a full-scale miss.
                        d = 1.0;
                    }
                    sq += d * d;
                }
                partial.squared += sq;
                lengthSum += std::sqrt(sq);
            }
            summary.perTexel[t] = float(lengthSum / double(pairs));
        }
    });
    double squared = 0;
    partials.combine_each([&](const Partial& p) {
        squared += p.squared;
        summary.nonFiniteValues += p.nonFinite;
    });
    double sum = 0;
    summary.minimum = std::numeric_limits<double>::infinity();
    summary.maximum = 0;
    for (float e : summary.perTexel) {
        sum += e;
        summary.minimum = std::min(summary.minimum, double(e));
        summary.maximum = std::max(summary.maximum, double(e));
    }
    summary.average = texels ? sum / double(texels) : 0.0;
    if (!texels) summary.minimum = 0;
    const double mse = squared / double(texels * values);
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
