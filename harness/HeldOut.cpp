#include "harness/HeldOut.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <tbb/parallel_for.h>

#include "core/Error.h"

namespace osgBTF {

namespace {

/** The normalised 1D Gaussian of sigma 1.5 over `size` taps (odd), centred. */
std::vector<double> gaussianTaps(int size) {
    std::vector<double> taps(static_cast<std::size_t>(size));
    double sum = 0;
    for (int i = 0; i < size; ++i) {
        const double d = i - (size - 1) / 2.0;
        taps[std::size_t(i)] = std::exp(-d * d / (2 * 1.5 * 1.5));
        sum += taps[std::size_t(i)];
    }
    for (double& t : taps) t /= sum;
    return taps;
}

/** `in` (width x height, one value per pixel) filtered by the separable window `taps` at every
 *  position where it fits: (width - n + 1) x (height - n + 1) values. */
std::vector<double> windowMeans(const std::vector<double>& in, int width, int height,
                                const std::vector<double>& taps) {
    const int n = int(taps.size()), ow = width - n + 1, oh = height - n + 1;
    std::vector<double> rows(std::size_t(ow) * std::size_t(height));
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < ow; ++x) {
            double sum = 0;
            for (int k = 0; k < n; ++k)
                sum += taps[std::size_t(k)] *
                       in[std::size_t(y) * std::size_t(width) + std::size_t(x + k)];
            rows[std::size_t(y) * std::size_t(ow) + std::size_t(x)] = sum;
        }
    std::vector<double> out(std::size_t(ow) * std::size_t(oh));
    for (int y = 0; y < oh; ++y)
        for (int x = 0; x < ow; ++x) {
            double sum = 0;
            for (int k = 0; k < n; ++k)
                sum += taps[std::size_t(k)] *
                       rows[std::size_t(y + k) * std::size_t(ow) + std::size_t(x)];
            out[std::size_t(y) * std::size_t(ow) + std::size_t(x)] = sum;
        }
    return out;
}

}  // namespace

double structuralSimilarity(const float* a, const float* b, int width, int height, int channels) {
    if (width <= 0 || height <= 0 || channels <= 0)
        throw Error("SSIM: empty image " + std::to_string(width) + "x" + std::to_string(height));
    int size = std::min({11, width, height});
    if (size % 2 == 0) --size;
    const std::vector<double> taps = gaussianTaps(size);
    const double c1 = 0.01 * 0.01, c2 = 0.03 * 0.03;  // (K L)^2 with L = 1
    const std::size_t pixels = std::size_t(width) * std::size_t(height);
    double total = 0;
    for (int c = 0; c < channels; ++c) {
        std::vector<double> x(pixels), y(pixels), xx(pixels), yy(pixels), xy(pixels);
        for (std::size_t p = 0; p < pixels; ++p) {
            x[p] = a[p * std::size_t(channels) + std::size_t(c)];
            y[p] = b[p * std::size_t(channels) + std::size_t(c)];
            xx[p] = x[p] * x[p];
            yy[p] = y[p] * y[p];
            xy[p] = x[p] * y[p];
        }
        const auto mx = windowMeans(x, width, height, taps),
                   my = windowMeans(y, width, height, taps);
        const auto mxx = windowMeans(xx, width, height, taps);
        const auto myy = windowMeans(yy, width, height, taps);
        const auto mxy = windowMeans(xy, width, height, taps);
        double sum = 0;
        for (std::size_t i = 0; i < mx.size(); ++i) {
            const double vx = mxx[i] - mx[i] * mx[i], vy = myy[i] - my[i] * my[i];
            const double cxy = mxy[i] - mx[i] * my[i];
            sum += (2 * mx[i] * my[i] + c1) * (2 * cxy + c2) /
                   ((mx[i] * mx[i] + my[i] * my[i] + c1) * (vx + vy + c2));
        }
        total += sum / double(mx.size());
    }
    return total / channels;
}

HeldOutScores scoreHeldOut(const BtfSource& measured, const Material& model,
                           const batch::HoldoutSplit& split, const std::vector<std::size_t>* texels,
                           std::size_t maxImages) {
    if (split.leftOutPairs.empty()) throw Error("held-out scores: no direction is left out");
    if (model.width() != measured.width() || model.height() != measured.height())
        throw Error("held-out scores: the model is " + std::to_string(model.width()) + "x" +
                    std::to_string(model.height()) + ", the data " +
                    std::to_string(measured.width()) + "x" + std::to_string(measured.height()));
    const std::size_t lights = measured.lightCount(), width = std::size_t(measured.width());
    const auto valueAt = [&](std::size_t texel, std::size_t pair) {
        return model.evaluate(int(texel % width), int(texel / width),
                              measured.views().vector(pair / lights),
                              measured.lights().vector(pair % lights));
    };
    HeldOutScores scores;
    scores.pairs = split.leftOutPairs.size();
    scores.error = computeError(
        measured,
        [&](std::size_t t, float* out) {
            for (const std::size_t p : split.leftOutPairs) {
                const glm::vec3 v = valueAt(t, p);
                out[p * 3] = v.r;
                out[p * 3 + 1] = v.g;
                out[p * 3 + 2] = v.b;
            }
        },
        texels, &split.leftOutPairs);

    // Whole images, evenly chosen among the left-out pairs.
    const std::size_t images = std::min(std::max<std::size_t>(maxImages, 1), scores.pairs);
    const std::size_t values = measured.texelCount() * 3;
    std::vector<float> data(values), fitted(values);
    double ssim = 0;
    for (std::size_t i = 0; i < images; ++i) {
        const std::size_t pair = split.leftOutPairs[i * scores.pairs / images];
        measured.readImages(pair, 1, data.data());
        tbb::parallel_for(std::size_t(0), measured.texelCount(), [&](std::size_t t) {
            const glm::vec3 v = valueAt(t, pair);
            fitted[t * 3] = v.r;
            fitted[t * 3 + 1] = v.g;
            fitted[t * 3 + 2] = v.b;
        });
        ssim += structuralSimilarity(data.data(), fitted.data(), measured.width(),
                                     measured.height(), 3);
    }
    scores.ssim = ssim / double(images);
    scores.imagesScored = images;
    return scores;
}

}  // namespace osgBTF
