// osgBTF: small linear-algebra building blocks shared by the linear-basis methods (PCA, LPCA).
//
// Eigen's decompositions are expensive to compile (SelfAdjointEigenSolver ~9 s per translation
// unit), so they live in LowRank.cpp only, behind this non-template API. Matrices are plain
// column-major arrays: element (r, c) of a rows x cols matrix is data[c * rows + r].
//
// Truncated SVD through the Gram matrix: for A (m x n) with n <= m, A^T A = V S^2 V^T, so the top
// singular values and right vectors come from the eigen decomposition of the small n x n Gram
// matrix, and U = A V S^-1. The Gram matrix is accumulated and decomposed in double: in float its
// rounding (~1e-7 ||A||^2) turned the zero singular values of rank-deficient data into noise that
// was kept as components. When m < n the roles of rows and columns are swapped.
#pragma once

#include <cstddef>
#include <functional>
#include <vector>

namespace osgBTF {

/** Eigen decomposition of a symmetric matrix, eigenvalues in DESCENDING order. */
struct SymmetricEigen {
    int size = 0;
    std::vector<double> values;   ///< size
    std::vector<double> vectors;  ///< size x size, column-major, column i belongs to values[i]
};

/** Decomposes the symmetric n x n matrix (column-major; only its lower triangle is read). */
SymmetricEigen symmetricEigen(const double* matrix, int n);

/** The best rank-`rank` approximation of a matrix A ~ U diag(S) V^T (Eckart-Young). */
struct TruncatedSvd {
    std::size_t rows = 0, cols = 0;
    int rank = 0;
    std::vector<float> u;                ///< rows x rank, column-major, orthonormal columns
    std::vector<float> v;                ///< cols x rank, column-major, orthonormal columns
    std::vector<double> singularValues;  ///< ALL min(rows, cols) of them, descending
    /** ||A||_F^2 when known (streamedTruncatedSvd sets it; its randomised path estimates only the
     *  leading singular values), else -1. */
    double totalSquared = -1;
    /** sum of the squared singular values beyond `rank`: the squared Frobenius error of the best
     *  rank-`rank` approximation (with totalSquared: totalSquared minus the kept squares, the
     *  error of the returned factors). */
    double residualSquared() const;
};

/** Truncated SVD of the column-major rows x cols matrix through its Gram matrix (see above).
 *  1 <= rank <= min(rows, cols). Columns of U (or V) for singular values that are zero up to
 *  rounding (squared, below min(rows, cols) * max(rows, cols) * DBL_EPSILON of the largest squared
 *  one) are set to zero rather than made up; the kept ones are re-orthogonalised. Single-threaded:
 *  callers parallelise over independent matrices. Throws Error on invalid sizes. */
TruncatedSvd truncatedSvd(const float* matrix, std::size_t rows, std::size_t cols, int rank);

/** Least squares X = argmin ||B - A X|| for A (rows x n, n small) and B (rows x m), column-major,
 *  through the normal equations (A^T A) X = A^T B, with a tiny ridge (1e-10 of the trace) so that
 *  zero columns of A get zero coefficients instead of a failure. Returns X (n x m, column-major).
 *  Accurate when A's columns are well conditioned (e.g. near-orthogonal bases). */
std::vector<float> leastSquares(const float* a, std::size_t rows, int n, const float* b, int m);

/** A matrix A (rows x cols) that is read in blocks of rows and never stored whole (a measured BTF
 *  of gigabytes). fill(first, count, out) writes rows [first, first + count) of A into `out` as a
 *  cols x count column-major matrix (row r of A becomes column r - first). It is called with
 *  first a multiple of blockRows and count = blockRows (less for the last block), from several
 *  threads at once. */
struct RowBlockSource {
    std::size_t rows = 0, cols = 0;
    std::size_t blockRows = 1;
    std::function<void(std::size_t first, std::size_t count, float* out)> fill;
};

struct StreamedSvdOptions {
    /** Up to this many columns: exact, through the cols x cols Gram matrix (accumulated in double
     *  over the row blocks), then one more pass for U. Beyond: randomised. */
    std::size_t gramColumns = 512;
    /** Randomised range finder (Halko, Martinsson, Tropp 2011, algorithms 4.4 and 5.1): rank +
     *  oversampling Gaussian test vectors, powerIterations subspace iterations (each
     *  re-orthonormalised), seeded and therefore deterministic. */
    int oversampling = 16;
    int powerIterations = 2;
    unsigned seed = 1;
    /** Called after each block with the rows it covered (progress over all passes: passes()). */
    std::function<void(std::size_t rows)> progress;
    /** Passes over A the chosen path makes, for progress totals. */
    int passes(std::size_t cols) const { return cols <= gramColumns ? 2 : 2 * powerIterations + 2; }
};

/** Truncated SVD of a streamed matrix, 1 <= rank <= min(rows, cols), in parallel over row blocks
 *  (TBB, one block of scratch per thread, 4 fixed chunks of blocks summed in order so results are
 *  deterministic; Eigen single-threaded inside). Returns u (rows x rank),
 *  v (cols x rank), the leading singular values (all min(rows, cols) on the Gram path, the
 *  rank + oversampling estimated ones on the randomised path) and totalSquared. Components of
 *  singular values that are zero up to rounding are zero columns. Throws Error on invalid sizes. */
TruncatedSvd streamedTruncatedSvd(const RowBlockSource& a, int rank,
                                  const StreamedSvdOptions& options = {});

}  // namespace osgBTF
