#include "core/ImageSimilarity.h"

#include <algorithm>
#include <cmath>
#include <string>

#include "core/Error.h"

namespace osgBTF {

double structuralSimilarity(const std::vector<float>& a, const std::vector<float>& b, int width,
                            int height, int channels, double range) {
    if (width < 1 || height < 1 || channels < 1 ||
        a.size() != std::size_t(width) * std::size_t(height) * std::size_t(channels) ||
        b.size() != a.size())
        throw Error("SSIM: the images must both hold " + std::to_string(width) + " x " +
                    std::to_string(height) + " x " + std::to_string(channels) + " values");
    if (!(range > 0)) throw Error("SSIM: the dynamic range must be > 0");
    const double c1 = (0.01 * range) * (0.01 * range), c2 = (0.03 * range) * (0.03 * range);
    // The window: 11 x 11 Gaussian weights of sigma 1.5, normalised (smaller for small images).
    const int wx = std::min(11, width), wy = std::min(11, height);
    std::vector<double> weight(std::size_t(wx) * std::size_t(wy));
    double total = 0;
    for (int j = 0; j < wy; ++j)
        for (int i = 0; i < wx; ++i) {
            const double dx = i - (wx - 1) / 2.0, dy = j - (wy - 1) / 2.0;
            total += weight[std::size_t(j) * wx + i] =
                std::exp(-(dx * dx + dy * dy) / (2 * 1.5 * 1.5));
        }
    for (double& w : weight) w /= total;
    double sum = 0;
    std::size_t windows = 0;
    for (int c = 0; c < channels; ++c)
        for (int y0 = 0; y0 + wy <= height; ++y0)
            for (int x0 = 0; x0 + wx <= width; ++x0) {
                double ma = 0, mb = 0, aa = 0, bb = 0, ab = 0;
                for (int j = 0; j < wy; ++j)
                    for (int i = 0; i < wx; ++i) {
                        const std::size_t k =
                            (std::size_t(y0 + j) * std::size_t(width) + std::size_t(x0 + i)) *
                                std::size_t(channels) +
                            std::size_t(c);
                        const double w = weight[std::size_t(j) * wx + i], va = a[k], vb = b[k];
                        ma += w * va;
                        mb += w * vb;
                        aa += w * va * va;
                        bb += w * vb * vb;
                        ab += w * va * vb;
                    }
                const double va = aa - ma * ma, vb = bb - mb * mb, cov = ab - ma * mb;
                sum += ((2 * ma * mb + c1) * (2 * cov + c2)) /
                       ((ma * ma + mb * mb + c1) * (va + vb + c2));
                ++windows;
            }
    return sum / double(windows);
}

}  // namespace osgBTF
