#include "materials/MaterialMath.h"

#include <algorithm>

#include <Imath/half.h>

namespace osgBTF {

float roundHalf(double x) {
    return float(Imath::half(float(std::clamp(x, -65504.0, 65504.0))));
}

double texelError(const std::vector<double>& rgb, const std::vector<float>& model) {
    double sum = 0;
    for (std::size_t j = 0; j < model.size(); j += 3) {
        const double dr = rgb[j] - model[j], dg = rgb[j + 1] - model[j + 1],
                     db = rgb[j + 2] - model[j + 2];
        sum += std::sqrt(dr * dr + dg * dg + db * db);
    }
    return sum / double(model.size() / 3);
}

MemoryFootprint footprintOf(const FittedMaterial& file, std::size_t texels) {
    double values = 0, bytes = 0;
    for (const MaterialTexture& t : file.textures) {
        values += double(t.valueCount());
        bytes += double(t.valueCount()) * bytesPerValue(t.kind);
    }
    MemoryFootprint footprint;
    footprint.valuesPerTexel = values / double(texels);
    footprint.bytesPerTexel = bytes / double(texels);
    footprint.totalBytes = std::uint64_t(bytes);
    return footprint;
}

void nonNegativeLeastSquares2(const double* f, const double* g, const double* y, std::size_t n,
                              std::size_t strideY, double& alpha, double& beta) {
    double ff = 0, fg = 0, gg = 0, fy = 0, gy = 0;
    for (std::size_t j = 0; j < n; ++j) {
        const double yj = y[j * strideY];
        ff += f[j] * f[j];
        fg += f[j] * g[j];
        gg += g[j] * g[j];
        fy += f[j] * yj;
        gy += g[j] * yj;
    }
    auto cost = [&](double a, double b) {
        return a * a * ff + b * b * gg + 2 * a * b * fg - 2 * a * fy - 2 * b * gy;
    };
    // Candidates: the interior optimum (if feasible), each variable alone, and zero; the convex
    // quadratic's constrained minimum is the best feasible one among them.
    double bestA = 0, bestB = 0, bestCost = 0;
    auto consider = [&](double a, double b) {
        if (!(a >= 0 && b >= 0) || !std::isfinite(a) || !std::isfinite(b)) return;
        const double c = cost(a, b);
        if (c < bestCost) {
            bestCost = c;
            bestA = a;
            bestB = b;
        }
    };
    const double det = ff * gg - fg * fg;
    if (det > 1e-12 * std::max(ff * gg, 1e-300))
        consider((fy * gg - gy * fg) / det, (gy * ff - fy * fg) / det);
    if (ff > 0) consider(fy / ff, 0);
    if (gg > 0) consider(0, gy / gg);
    alpha = bestA;
    beta = bestB;
}

}  // namespace osgBTF
