#include "materials/IlluminationPca.h"

#include <tbb/parallel_for.h>

#include <cmath>

#include <Eigen/Dense>

#include "core/Error.h"

namespace osgBTF {

IlluminationPca IlluminationPca::build(const std::function<std::vector<float>(float)>& compute,
                                       int rotations, int components,
                                       const std::function<void(int, int)>& progress) {
    if (rotations < 2) throw Error("illumination pca: at least 2 rotations needed");
    if (components < 1) throw Error("illumination pca: at least 1 component needed");
    IlluminationPca p;
    p._rotations = rotations;
    p._components = std::min(components, rotations);
    std::vector<std::vector<float>> samples;
    for (int a = 0; a < rotations; ++a) {
        samples.push_back(compute(360.0f * float(a) / float(rotations)));
        if (samples.back().size() != samples.front().size())
            throw Error("illumination pca: rotation " + std::to_string(a) + " gave " +
                        std::to_string(samples.back().size()) + " values, rotation 0 gave " +
                        std::to_string(samples.front().size()));
        if (progress) progress(a + 1, rotations);
    }
    const std::size_t n = samples.front().size();
    std::vector<double> mean(n, 0.0);
    for (const auto& s : samples)
        for (std::size_t i = 0; i < n; ++i) mean[i] += s[i];
    for (double& m : mean) m /= rotations;
    p._mean.assign(mean.begin(), mean.end());
    // Gram matrix of the centred samples; its eigenvectors give the coefficients (X = C B with
    // orthonormal rows of B: G = X X^T = C C^T).
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(rotations, rotations);
    for (int a = 0; a < rotations; ++a)
        for (int b = a; b < rotations; ++b) {
            double sum = 0;
            for (std::size_t i = 0; i < n; ++i)
                sum += (samples[a][i] - mean[i]) * (samples[b][i] - mean[i]);
            gram(a, b) = gram(b, a) = sum;
        }
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(gram);
    p._coefficients.assign(rotations, std::vector<double>(p._components, 0.0));
    p._basis.assign(p._components, std::vector<float>(n, 0.0f));
    for (int k = 0; k < p._components; ++k) {
        const int column = rotations - 1 - k;  // eigenvalues ascend
        const double lambda = eigen.eigenvalues()(column);
        if (!(lambda > 1e-12 * std::max(1.0, eigen.eigenvalues()(rotations - 1)))) continue;
        const double sigma = std::sqrt(lambda);
        std::vector<double> basis(n, 0.0);
        for (int a = 0; a < rotations; ++a) {
            const double u = eigen.eigenvectors()(a, column);
            p._coefficients[a][k] = u * sigma;
            for (std::size_t i = 0; i < n; ++i) basis[i] += u * (samples[a][i] - mean[i]);
        }
        for (std::size_t i = 0; i < n; ++i) p._basis[k][i] = float(basis[i] / sigma);
    }
    return p;
}

namespace {

/** out = mean + sum_k c_k basis_k in one pass over blocks that stay in cache, on all cores: the
 *  arrays are tens of MB, so reading each once bounds the time (memory bandwidth). */
void combineInto(const std::vector<float>& mean, const std::vector<std::vector<float>>& basis,
                 const std::vector<double>& c, float* out) {
    constexpr std::size_t kBlock = 4096;
    const std::size_t n = mean.size();
    tbb::parallel_for(std::size_t(0), (n + kBlock - 1) / kBlock, [&](std::size_t b) {
        const std::size_t begin = b * kBlock, end = std::min(n, begin + kBlock);
        std::copy(mean.begin() + std::ptrdiff_t(begin), mean.begin() + std::ptrdiff_t(end),
                  out + begin);
        for (std::size_t k = 0; k < basis.size(); ++k) {
            const float w = float(c[k]);
            if (w == 0.0f) continue;
            const float* row = basis[k].data();
            for (std::size_t i = begin; i < end; ++i) out[i] += w * row[i];
        }
    });
}

std::vector<float> combine(const std::vector<float>& mean,
                           const std::vector<std::vector<float>>& basis,
                           const std::vector<double>& c) {
    std::vector<float> out(mean.size());
    combineInto(mean, basis, c, out.data());
    return out;
}

}  // namespace

std::vector<float> IlluminationPca::reconstructSample(int a) const {
    if (a < 0 || a >= _rotations) throw Error("illumination pca: no sample " + std::to_string(a));
    return combine(_mean, _basis, _coefficients[std::size_t(a)]);
}

std::vector<float> IlluminationPca::reconstruct(float degrees) const {
    std::vector<float> out(_mean.size());
    reconstructInto(degrees, out.data());
    return out;
}

void IlluminationPca::reconstructInto(float degrees, float* out) const {
    if (_rotations < 2) throw Error("illumination pca: not built");
    double position = double(degrees) / 360.0 * _rotations;
    position -= _rotations * std::floor(position / _rotations);
    const int a = int(std::floor(position)) % _rotations, b = (a + 1) % _rotations;
    const double t = position - std::floor(position);
    std::vector<double> c(static_cast<std::size_t>(_components));
    for (int k = 0; k < _components; ++k)
        c[std::size_t(k)] = (1 - t) * _coefficients[std::size_t(a)][std::size_t(k)] +
                            t * _coefficients[std::size_t(b)][std::size_t(k)];
    combineInto(_mean, _basis, c, out);
}

}  // namespace osgBTF
