#include "core/LowRank.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <string>

#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>
#include <Eigen/QR>

#include "core/Error.h"

namespace osgBTF {

namespace {
using MatrixF = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic>;
using MatrixD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic>;
using ConstMapF = Eigen::Map<const MatrixF>;
}  // namespace

SymmetricEigen symmetricEigen(const double* matrix, int n) {
    if (n <= 0) throw Error("symmetricEigen: size must be positive, got " + std::to_string(n));
    const MatrixD m = Eigen::Map<const MatrixD>(matrix, n, n);
    Eigen::SelfAdjointEigenSolver<MatrixD> solver(m);
    if (solver.info() != Eigen::Success) throw Error("symmetricEigen: decomposition failed");
    SymmetricEigen result;
    result.size = n;
    result.values.resize(std::size_t(n));
    result.vectors.resize(std::size_t(n) * n);
    // Eigen sorts ascending; callers want the dominant components first.
    for (int i = 0; i < n; ++i) {
        const int src = n - 1 - i;
        result.values[std::size_t(i)] = solver.eigenvalues()(src);
        for (int r = 0; r < n; ++r)
            result.vectors[std::size_t(i) * n + r] = solver.eigenvectors()(r, src);
    }
    return result;
}

double TruncatedSvd::residualSquared() const {
    if (totalSquared >= 0) {
        double kept = 0;
        for (std::size_t i = 0; i < std::size_t(rank) && i < singularValues.size(); ++i)
            kept += singularValues[i] * singularValues[i];
        return std::max(0.0, totalSquared - kept);
    }
    double sum = 0;
    for (std::size_t i = std::size_t(rank); i < singularValues.size(); ++i)
        sum += singularValues[i] * singularValues[i];
    return sum;
}

TruncatedSvd truncatedSvd(const float* matrix, std::size_t rows, std::size_t cols, int rank) {
    const std::size_t small = std::min(rows, cols);
    if (rows == 0 || cols == 0) throw Error("truncatedSvd: empty matrix");
    if (rank < 1 || std::size_t(rank) > small)
        throw Error("truncatedSvd: rank " + std::to_string(rank) + " outside 1.." +
                    std::to_string(small));
    const ConstMapF a(matrix, Eigen::Index(rows), Eigen::Index(cols));
    const bool wide = rows < cols;  // Gram over the rows instead of the columns
    const Eigen::Index n = Eigen::Index(small), length = Eigen::Index(std::max(rows, cols));
    // The slices of A along its long dimension, as an n x b double block: rows of A (transposed)
    // or columns of A. Blocks bound the double copy's memory for the 3 * 65536-row PCA matrices.
    const Eigen::Index block = 4096;
    auto slice = [&](Eigen::Index first, Eigen::Index count) -> MatrixD {
        return wide ? MatrixD(a.middleCols(first, count).cast<double>())
                    : MatrixD(a.middleRows(first, count).transpose().cast<double>());
    };

    // Double: a float Gram matrix carries rounding of ~1e-7 * sqrt(length) of its largest
    // eigenvalue, which on rank-deficient data (constant or duplicate texels) became "singular
    // values" far above any cut-off, and their vectors, divided by them, amplified noise.
    MatrixD gram = MatrixD::Zero(n, n);
    for (Eigen::Index first = 0; first < length; first += block)
        gram.selfadjointView<Eigen::Lower>().rankUpdate(
            slice(first, std::min(block, length - first)));
    const SymmetricEigen eigen = symmetricEigen(gram.data(), int(n));

    TruncatedSvd svd;
    svd.rows = rows;
    svd.cols = cols;
    svd.rank = rank;
    svd.singularValues.resize(small);
    for (std::size_t i = 0; i < small; ++i)
        svd.singularValues[i] = std::sqrt(std::max(0.0, eigen.values[i]));

    // Eigenvalues below this are zero up to rounding: each Gram entry is a dot product of `length`
    // terms, off by up to length * eps * |a_i| |a_j|, and the n x n eigensolver adds n * eps *
    // ||G||; over n rows that is at most about n * length * eps of the largest eigenvalue (for a
    // 256x256 Bonn PCA view ~1e-8, a singular value of 1e-4 of the largest: a real component that
    // small carries less than 1e-8 of the data's energy, so dropping it costs nothing).
    const double cutoff = std::max(0.0, eigen.values[0]) * double(n) * double(length) *
                          std::numeric_limits<double>::epsilon();
    int kept = 0;
    while (kept < rank && eigen.values[std::size_t(kept)] > cutoff) ++kept;

    // Eigenvectors of the Gram matrix are one side; the other is A (or A^T) times them over S.
    MatrixD gramSide = MatrixD::Zero(n, rank), otherSide = MatrixD::Zero(length, rank);
    for (int k = 0; k < kept; ++k)
        for (Eigen::Index r = 0; r < n; ++r)
            gramSide(r, k) = eigen.vectors[std::size_t(k) * small + std::size_t(r)];
    for (Eigen::Index first = 0; first < length; first += block) {
        const Eigen::Index count = std::min(block, length - first);
        otherSide.middleRows(first, count) = slice(first, count).transpose() * gramSide;
    }
    // Re-orthogonalised (modified Gram-Schmidt, two passes): a column that loses most of its
    // length s to the earlier ones was no new direction; it and all smaller ones are dropped.
    for (int k = 0; k < kept; ++k) {
        const double s = svd.singularValues[std::size_t(k)];
        auto column = otherSide.col(k);
        for (int pass = 0; pass < 2; ++pass)
            for (int j = 0; j < k; ++j) column -= otherSide.col(j).dot(column) * otherSide.col(j);
        const double norm = column.norm();
        if (!(norm > 0.5 * s)) {
            kept = k;
            break;
        }
        column /= norm;
    }
    for (int k = kept; k < rank; ++k) {
        otherSide.col(k).setZero();
        gramSide.col(k).setZero();
    }
    const MatrixF u = (wide ? gramSide : otherSide).cast<float>();
    const MatrixF v = (wide ? otherSide : gramSide).cast<float>();
    svd.u.assign(u.data(), u.data() + u.size());
    svd.v.assign(v.data(), v.data() + v.size());
    return svd;
}

namespace {

/** The passes over a streamed matrix: each reads every row block once, in parallel. Sums over
 *  blocks go into a fixed number of chunks of consecutive blocks, each summed in order, and the
 *  chunks are added in order: the result does not depend on how TBB schedules the blocks, so the
 *  fit is deterministic (per-thread sums were not, in the last bits). */
class StreamedPasses {
public:
    static constexpr std::size_t kChunks = 4;

    StreamedPasses(const RowBlockSource& a, const StreamedSvdOptions& options)
        : _a(a), _options(options) {
        _blocks = (a.rows + a.blockRows - 1) / a.blockRows;
    }

    /** Y = A X (rows x k) for X (cols x k); with `squares`, also ||A||_F^2. */
    MatrixF times(const MatrixF& x, double* squares = nullptr) const {
        MatrixF y(Eigen::Index(_a.rows), x.cols());
        std::vector<double> partial(kChunks, 0.0);
        forEachBlock([&](std::size_t chunk, std::size_t first, const MatrixF& block) {
            y.middleRows(Eigen::Index(first), block.cols()).noalias() = block.transpose() * x;
            if (squares) partial[chunk] += block.cast<double>().squaredNorm();
        });
        if (squares) *squares = std::accumulate(partial.begin(), partial.end(), 0.0);
        return y;
    }

    /** Z = A^T Y (cols x k) for Y (rows x k). */
    MatrixD transposedTimes(const MatrixF& y) const {
        // Float per chunk (a few hundred blocks each: rounding ~1e-5 relative at worst, far below
        // what the subspace iteration needs), the chunks' sums in double.
        std::vector<MatrixF> sums(kChunks);
        forEachBlock([&](std::size_t chunk, std::size_t first, const MatrixF& block) {
            MatrixF& sum = sums[chunk];
            if (sum.size() == 0) sum = MatrixF::Zero(Eigen::Index(_a.cols), y.cols());
            sum.noalias() += block * y.middleRows(Eigen::Index(first), block.cols());
        });
        MatrixD z = MatrixD::Zero(Eigen::Index(_a.cols), y.cols());
        for (const MatrixF& s : sums)
            if (s.size() != 0) z += s.cast<double>();
        return z;
    }

    /** G = A^T A (cols x cols), lower triangle, in double. */
    MatrixD gram() const {
        const Eigen::Index n = Eigen::Index(_a.cols);
        std::vector<MatrixD> sums(kChunks);
        forEachBlock([&](std::size_t chunk, std::size_t, const MatrixF& block) {
            MatrixD& sum = sums[chunk];
            if (sum.size() == 0) sum = MatrixD::Zero(n, n);
            sum.selfadjointView<Eigen::Lower>().rankUpdate(block.cast<double>());
        });
        MatrixD g = MatrixD::Zero(n, n);
        for (const MatrixD& s : sums)
            if (s.size() != 0) g += s;
        return g;
    }

private:
    /** f(chunk, first row, block) for every block; a chunk's blocks in order on one thread. */
    template <typename F>
    void forEachBlock(F&& f) const {
        tbb::enumerable_thread_specific<MatrixF> scratch;
        tbb::parallel_for(std::size_t(0), kChunks, [&](std::size_t chunk) {
            MatrixF& block = scratch.local();
            const std::size_t begin = _blocks * chunk / kChunks,
                              end = _blocks * (chunk + 1) / kChunks;
            for (std::size_t b = begin; b < end; ++b) {
                const std::size_t first = b * _a.blockRows;
                const std::size_t count = std::min(_a.blockRows, _a.rows - first);
                block.resize(Eigen::Index(_a.cols), Eigen::Index(count));
                _a.fill(first, count, block.data());
                f(chunk, first, block);
                if (_options.progress) _options.progress(count);
            }
        });
    }

    const RowBlockSource& _a;
    const StreamedSvdOptions& _options;
    std::size_t _blocks = 0;
};

/** Orthonormal basis of the columns of m (thin Householder QR, in double). */
MatrixD orthonormalise(const MatrixD& m) {
    Eigen::HouseholderQR<MatrixD> qr(m);
    return qr.householderQ() * MatrixD::Identity(m.rows(), m.cols());
}

}  // namespace

TruncatedSvd streamedTruncatedSvd(const RowBlockSource& a, int rank,
                                  const StreamedSvdOptions& options) {
    const std::size_t small = std::min(a.rows, a.cols);
    if (a.rows == 0 || a.cols == 0 || a.blockRows == 0 || !a.fill)
        throw Error("streamedTruncatedSvd: empty matrix");
    if (rank < 1 || std::size_t(rank) > small)
        throw Error("streamedTruncatedSvd: rank " + std::to_string(rank) + " outside 1.." +
                    std::to_string(small));
    const StreamedPasses passes(a, options);
    const Eigen::Index rows = Eigen::Index(a.rows), cols = Eigen::Index(a.cols);
    TruncatedSvd svd;
    svd.rows = a.rows;
    svd.cols = a.cols;
    svd.rank = rank;

    if (a.cols <= options.gramColumns) {
        // Exact: A^T A = V S^2 V^T, then U = A V S^-1 (the cut-off as in truncatedSvd).
        const MatrixD g = passes.gram();
        svd.totalSquared = g.diagonal().sum();
        const SymmetricEigen eigen = symmetricEigen(g.data(), int(cols));
        svd.singularValues.resize(small);
        for (std::size_t i = 0; i < small; ++i)
            svd.singularValues[i] = std::sqrt(std::max(0.0, eigen.values[i]));
        const double cutoff = std::max(0.0, eigen.values[0]) * double(cols) * double(rows) *
                              std::numeric_limits<double>::epsilon();
        MatrixF v = MatrixF::Zero(cols, rank);
        for (int k = 0; k < rank && eigen.values[std::size_t(k)] > cutoff; ++k)
            for (Eigen::Index r = 0; r < cols; ++r)
                v(r, k) = float(eigen.vectors[std::size_t(k) * std::size_t(cols) + std::size_t(r)]);
        MatrixF u = passes.times(v);
        for (int k = 0; k < rank; ++k) {
            const double s = svd.singularValues[std::size_t(k)];
            if (eigen.values[std::size_t(k)] > cutoff)
                u.col(k) /= float(s);
            else
                u.col(k).setZero();
        }
        svd.u.assign(u.data(), u.data() + u.size());
        svd.v.assign(v.data(), v.data() + v.size());
        return svd;
    }

    // Randomised: Q spans A's leading column space (subspace iteration from a Gaussian start),
    // then the small SVD of B = Q^T A gives the factors. Oversampling and the iterations make
    // the result's error indistinguishable from the optimum on data whose spectrum decays.
    const Eigen::Index l = Eigen::Index(std::min(small, std::size_t(rank + options.oversampling)));
    std::mt19937 rng(options.seed);
    std::normal_distribution<float> gauss(0.0f, 1.0f);
    MatrixF omega(cols, l);
    for (Eigen::Index j = 0; j < l; ++j)
        for (Eigen::Index i = 0; i < cols; ++i) omega(i, j) = gauss(rng);
    double total = 0;
    MatrixF q = orthonormalise(passes.times(omega, &total).cast<double>()).cast<float>();
    svd.totalSquared = total;
    for (int it = 0; it < options.powerIterations; ++it) {
        const MatrixF z = orthonormalise(passes.transposedTimes(q)).cast<float>();
        q = orthonormalise(passes.times(z).cast<double>()).cast<float>();
    }
    // B^T = A^T Q (cols x l); its SVD B^T = Vb Sb Ub^T gives A ~ (Q Ub) Sb Vb^T.
    const MatrixF bt = passes.transposedTimes(q).cast<float>();
    const TruncatedSvd small2 = truncatedSvd(bt.data(), std::size_t(cols), std::size_t(l), rank);
    svd.singularValues = small2.singularValues;
    const Eigen::Map<const MatrixF> ub(small2.v.data(), l, rank);
    const MatrixF u = q * ub;
    svd.u.assign(u.data(), u.data() + u.size());
    svd.v = small2.u;
    return svd;
}

std::vector<float> leastSquares(const float* a, std::size_t rows, int n, const float* b, int m) {
    if (rows == 0 || n <= 0 || m <= 0) throw Error("leastSquares: empty system");
    const ConstMapF am(a, Eigen::Index(rows), n), bm(b, Eigen::Index(rows), m);
    MatrixF ataF = MatrixF::Zero(n, n);
    ataF.selfadjointView<Eigen::Lower>().rankUpdate(am.transpose());
    MatrixD ata = ataF.selfadjointView<Eigen::Lower>().toDenseMatrix().cast<double>();
    const MatrixD atb = (am.transpose() * bm).cast<double>();
    const double ridge = 1e-10 * std::max(ata.trace(), 1e-30);
    ata.diagonal().array() += ridge;
    const MatrixD x = ata.ldlt().solve(atb);
    const MatrixF xf = x.cast<float>();
    return std::vector<float>(xf.data(), xf.data() + xf.size());
}

}  // namespace osgBTF
