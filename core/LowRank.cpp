#include "core/LowRank.h"

#include <algorithm>
#include <cmath>
#include <string>

#include <Eigen/Cholesky>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

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
    const Eigen::Index n = Eigen::Index(small);

    MatrixF gramF = MatrixF::Zero(n, n);
    if (wide)
        gramF.selfadjointView<Eigen::Lower>().rankUpdate(a);
    else
        gramF.selfadjointView<Eigen::Lower>().rankUpdate(a.transpose());
    const MatrixD gram = gramF.cast<double>();
    const SymmetricEigen eigen = symmetricEigen(gram.data(), int(n));

    TruncatedSvd svd;
    svd.rows = rows;
    svd.cols = cols;
    svd.rank = rank;
    svd.singularValues.resize(small);
    for (std::size_t i = 0; i < small; ++i)
        svd.singularValues[i] = std::sqrt(std::max(0.0, eigen.values[i]));

    // Eigenvectors of the Gram matrix are one side; the other is A (or A^T) times them over S.
    MatrixF gramSide(n, rank);
    for (int k = 0; k < rank; ++k)
        for (Eigen::Index r = 0; r < n; ++r)
            gramSide(r, k) = float(eigen.vectors[std::size_t(k) * small + std::size_t(r)]);
    MatrixF otherSide = wide ? MatrixF(a.transpose() * gramSide) : MatrixF(a * gramSide);
    const double tiny = 1e-6 * svd.singularValues[0];
    for (int k = 0; k < rank; ++k) {
        const double s = svd.singularValues[std::size_t(k)];
        if (s > tiny && s > 0) {
            otherSide.col(k) /= float(s);
        } else {
            otherSide.col(k).setZero();
            gramSide.col(k).setZero();
        }
    }
    const MatrixF& u = wide ? gramSide : otherSide;
    const MatrixF& v = wide ? otherSide : gramSide;
    svd.u.assign(u.data(), u.data() + u.size());
    svd.v.assign(v.data(), v.data() + v.size());
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
