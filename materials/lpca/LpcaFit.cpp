// LPCA fit: generalised Lloyd iteration of local PCA (Kambhatla & Leen 1997, as Müller et al.
// 2003 use it), trained on a random subsample of the texels as Meseth et al. 2003 section 4.4 says
// it can be ("does not require the full dataset for training"), then every texel is assigned to the
// cluster that reconstructs it best and projected onto that cluster's Eigen-BRDFs.
//
// Each cluster is the best rank-c linear subspace of its members (mean folded in, README.md):
// its Eigen-BRDFs are the top-c right singular vectors of the members' ABRDF matrix X_k (m x D,
// D = V*L*3), found from the small Gram matrix X_k X_k^T (m x m): if X_k X_k^T u = s^2 u then
// E = X_k^T u / s. The reconstruction error of texel x in cluster k is |x|^2 - |E_k^T x|^2, so the
// assignment of n texels to K clusters is one GEMM (n x D) * (D x K*c).
//
// This is the only translation unit that instantiates Eigen's SelfAdjointEigenSolver (slow to
// compile); it is reached through LpcaMaterial::fit only.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <numeric>
#include <random>
#include <set>
#include <sstream>

#include <Imath/half.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <Eigen/Dense>

#include "core/Error.h"
#include "core/Progress.h"
#include "materials/MethodOptions.h"
#include "materials/lpca/Lpca.h"

namespace osgBTF {

namespace {

using RowMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
using ColMatrix = Eigen::MatrixXf;

/** Members beyond this are subsampled when a cluster's subspace is refitted: the Gram matrix and
 *  its eigendecomposition grow with the square and cube of the member count. */
constexpr std::size_t kMaxRefitMembers = 256;
/** Texels per block of the final projection pass (bounds the gathered ABRDF block's memory). */
constexpr std::size_t kChunkTexels = 2048;

/** Rows = the ABRDFs of `texels` (ascending reads fastest), in parallel blocks of the size the
 *  source reads efficiently (for factored input one decoding GEMM per block). */
void gatherRows(const BtfSource& btf, const std::size_t* texels, std::size_t count,
                RowMatrix& rows) {
    const std::size_t values = btf.imageCount() * 3;
    rows.resize(Eigen::Index(count), Eigen::Index(values));
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, count, btf.abrdfBlockTexels()),
        [&](const auto& r) {
            btf.readAbrdfs(texels + r.begin(), r.size(), rows.data() + r.begin() * values);
        },
        tbb::simple_partitioner());
}

/** out = rows * basis, in parallel over blocks of rows (Eigen's GEMM is single-threaded here). */
void project(const RowMatrix& rows, const Eigen::Ref<const ColMatrix>& basis, RowMatrix& out) {
    out.resize(rows.rows(), basis.cols());
    const Eigen::Index block = 128;
    tbb::parallel_for(Eigen::Index(0), (rows.rows() + block - 1) / block, [&](Eigen::Index b) {
        const Eigen::Index r0 = b * block, n = std::min(block, rows.rows() - r0);
        out.middleRows(r0, n).noalias() = rows.middleRows(r0, n) * basis;
    });
}

/** Best cluster of each row and its reconstruction error |x|^2 - |E_k^T x|^2 (>= 0). */
void assign(const RowMatrix& rows, const Eigen::VectorXf& norms2,
            const Eigen::Ref<const ColMatrix>& basis, int clusters, int components,
            std::vector<int>& clusterOf, std::vector<double>& error, RowMatrix& projections) {
    project(rows, basis, projections);
    const std::size_t n = std::size_t(rows.rows());
    clusterOf.resize(n);
    error.resize(n);
    tbb::parallel_for(std::size_t(0), n, [&](std::size_t j) {
        double best = 1e300;
        int bestK = 0;
        for (int k = 0; k < clusters; ++k) {
            const double captured =
                projections.row(Eigen::Index(j)).segment(k * components, components).squaredNorm();
            const double e = double(norms2[Eigen::Index(j)]) - captured;
            if (e < best) {
                best = e;
                bestK = k;
            }
        }
        clusterOf[j] = bestK;
        error[j] = std::max(best, 0.0);
    });
}

/** The top-`components` right singular vectors of the member rows, as columns of `basis`
 *  (zero columns where the members span fewer dimensions). */
void fitSubspace(const RowMatrix& rows, const std::vector<std::size_t>& members, int components,
                 Eigen::Ref<ColMatrix> basis) {
    basis.setZero();
    if (members.empty()) return;
    using RowMatrixD = Eigen::Matrix<double, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;
    RowMatrixD x(Eigen::Index(members.size()), rows.cols());
    for (std::size_t j = 0; j < members.size(); ++j)
        x.row(Eigen::Index(j)) = rows.row(Eigen::Index(members[j])).cast<double>();
    // Double, not float: a float Gram matrix of length-D dot products carries rounding of about
    // 1e-7 * sqrt(D) of its largest eigenvalue, so on rank-deficient members (identical or
    // proportional texels) the "small" eigenvalues were rounding noise far above any cut-off, and
    // their eigenvectors, divided by sqrt(noise), became large non-orthogonal junk Eigen-BRDFs.
    // Only the lower triangle is formed (the solver reads no more), half the work of x x^T.
    Eigen::MatrixXd gram = Eigen::MatrixXd::Zero(x.rows(), x.rows());
    gram.selfadjointView<Eigen::Lower>().rankUpdate(x);
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(gram);
    const Eigen::VectorXd& values = solver.eigenvalues();  // ascending
    const Eigen::Index m = values.size();
    const double largest = std::max(values[m - 1], 0.0);
    // Eigenvalues below this are indistinguishable from zero: each Gram entry is a length-D dot
    // product, off by up to about D * eps * |x_i| |x_j| in double, and the m x m eigensolver adds
    // m * eps * ||G||; summed over the m rows that is at most about m * D * eps * largest. With
    // D = 19683 (Bonn) and m = 256 this is ~1e-9 of the largest eigenvalue, a singular value of
    // ~3e-5 of the largest: a real component that small changes the squared error by less than
    // 1e-9 of the data's energy, so dropping it costs nothing, while keeping noise is what broke.
    const double cutoff =
        largest * double(m) * double(x.cols()) * std::numeric_limits<double>::epsilon();
    Eigen::MatrixXd kept(x.cols(), components);
    int count = 0;
    for (int i = 0; i < components && i < m; ++i) {
        const double value = values[m - 1 - i];
        if (!(value > cutoff) || value <= 0) break;
        Eigen::VectorXd e = x.transpose() * solver.eigenvectors().col(m - 1 - i);
        const double expected = std::sqrt(value);  // |X^T u| = s for an exact eigenpair
        // Re-orthogonalise against the kept ones (twice: one modified Gram-Schmidt pass can leave
        // rounding of the order of what it removed). A direction that loses most of its length
        // here was not a new one, so it and everything smaller are dropped (left zero).
        for (int pass = 0; pass < 2; ++pass)
            for (int j = 0; j < count; ++j) e -= kept.col(j).dot(e) * kept.col(j);
        const double norm = e.norm();
        if (!(norm > 0.5 * expected)) break;
        kept.col(count++) = e / norm;
    }
    for (int i = 0; i < count; ++i) basis.col(i) = kept.col(i).cast<float>();
}

// ---- the same clustering through the training set's Gram matrix ----
// With n training texels of D values and n < D (a UBO2014 file: D = 68403), every quantity of the
// clustering is a function of G = X X^T (n x n): a cluster's member Gram is G[M, M], its
// Eigen-BRDFs are E = X[M]^T A with coefficients A (m x c) from that matrix, and texel j's
// projections are G[j, M] A. Forming G once (n^2 D / 2) replaces, per iteration, the member
// Grams (K m^2 D) and the assignment GEMM (n D K c): at n = 4096, D = 68403, K = 32, c = 8 the
// clustering drops from ~25 s per iteration on this machine to well under one. Exact up to
// rounding: the same eigenproblems and projections, in double throughout.

/** Texels above this keep the direct path: G and its partial sums would exceed ~1.5 GB. */
constexpr std::size_t kMaxGramTexels = 8192;

/** G = X X^T in double, accumulated over column blocks of X in two fixed parts summed in order
 *  (deterministic whatever the thread schedule). */
Eigen::MatrixXd trainingGram(const RowMatrix& x) {
    const Eigen::Index n = x.rows(), dims = x.cols(), block = 512;
    constexpr int kParts = 2;
    std::vector<Eigen::MatrixXd> parts(kParts);
    tbb::parallel_for(0, kParts, [&](int p) {
        Eigen::MatrixXd& g = parts[std::size_t(p)];
        g = Eigen::MatrixXd::Zero(n, n);
        for (Eigen::Index first = p * block; first < dims; first += kParts * block) {
            const Eigen::MatrixXd columns =
                x.middleCols(first, std::min(block, dims - first)).cast<double>();
            g.selfadjointView<Eigen::Lower>().rankUpdate(columns);
        }
    });
    for (int p = 1; p < kParts; ++p) parts[0] += parts[std::size_t(p)];
    return parts[0].selfadjointView<Eigen::Lower>();
}

/** fitSubspace in coefficients: E = X[members]^T A (A: members x components, zero columns where
 *  fitSubspace would leave zero columns). */
Eigen::MatrixXd fitSubspaceGram(const Eigen::MatrixXd& gram,
                                const std::vector<std::size_t>& members, int components,
                                Eigen::Index dims) {
    const Eigen::Index m = Eigen::Index(members.size());
    Eigen::MatrixXd a = Eigen::MatrixXd::Zero(m, components);
    if (m == 0) return a;
    Eigen::MatrixXd g(m, m);
    for (Eigen::Index i = 0; i < m; ++i)
        for (Eigen::Index j = 0; j < m; ++j)
            g(i, j) =
                gram(Eigen::Index(members[std::size_t(i)]), Eigen::Index(members[std::size_t(j)]));
    Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> solver(g);
    const Eigen::VectorXd& values = solver.eigenvalues();  // ascending
    const double largest = std::max(values[m - 1], 0.0);
    // fitSubspace's cut-off and re-orthogonalisation, with dot products e_i . e_j = a_i^T G a_j.
    const double cutoff =
        largest * double(m) * double(dims) * std::numeric_limits<double>::epsilon();
    Eigen::MatrixXd gKept(m, components);  // G a_j of the kept ones
    int count = 0;
    for (int i = 0; i < components && i < m; ++i) {
        const double value = values[m - 1 - i];
        if (!(value > cutoff) || value <= 0) break;
        Eigen::VectorXd b = solver.eigenvectors().col(m - 1 - i);
        const double expected = std::sqrt(value);
        for (int pass = 0; pass < 2; ++pass)
            for (int j = 0; j < count; ++j) b -= gKept.col(j).dot(b) * a.col(j);
        const Eigen::VectorXd gb = g * b;
        const double norm = std::sqrt(std::max(b.dot(gb), 0.0));
        if (!(norm > 0.5 * expected)) break;
        a.col(count) = b / norm;
        gKept.col(count) = gb / norm;
        ++count;
    }
    return a;
}

/** assign() through G: projections of texel j on cluster k = G[j, M_k] A_k. */
void assignGram(const Eigen::MatrixXd& gram, const std::vector<std::vector<std::size_t>>& members,
                const std::vector<Eigen::MatrixXd>& coefficients, int clusters,
                std::vector<int>& clusterOf, std::vector<double>& error) {
    const Eigen::Index n = gram.rows();
    Eigen::MatrixXd captured(n, clusters);
    tbb::parallel_for(0, clusters, [&](int k) {
        const std::vector<std::size_t>& m = members[std::size_t(k)];
        Eigen::MatrixXd columns(n, Eigen::Index(m.size()));
        for (std::size_t i = 0; i < m.size(); ++i)
            columns.col(Eigen::Index(i)) = gram.col(Eigen::Index(m[i]));
        captured.col(k) = (columns * coefficients[std::size_t(k)]).rowwise().squaredNorm();
    });
    clusterOf.resize(std::size_t(n));
    error.resize(std::size_t(n));
    for (Eigen::Index j = 0; j < n; ++j) {
        double best = 1e300;
        int bestK = 0;
        for (int k = 0; k < clusters; ++k) {
            const double e = gram(j, j) - captured(j, k);
            if (e < best) {
                best = e;
                bestK = k;
            }
        }
        clusterOf[std::size_t(j)] = bestK;
        error[std::size_t(j)] = std::max(best, 0.0);
    }
}

}  // namespace

LpcaSettings LpcaSettings::fromValues(const OptionValues& values) {
    LpcaSettings s;
    s.clusters = values.integer("clusters");
    s.components = values.integer("components");
    s.iterations = values.integer("iterations");
    s.trainingTexels = values.integer("training");
    s.seed = unsigned(values.integer("seed"));
    return s;
}

LpcaSettings LpcaSettings::fromOptions(const FitOptions& options) {
    return fromValues(validateOptions(LpcaMaterial::kMethod, options));
}

struct LpcaFitter {
    static osg::ref_ptr<LpcaMaterial> run(const BtfSource& btf, const LpcaSettings& s);
};

osg::ref_ptr<LpcaMaterial> LpcaMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    return LpcaFitter::run(btf, LpcaSettings::fromOptions(options));
}

osg::ref_ptr<LpcaMaterial> LpcaMaterial::fit(const BtfSource& btf, const LpcaSettings& settings) {
    return LpcaFitter::run(btf, settings);
}

osg::ref_ptr<LpcaMaterial> LpcaFitter::run(const BtfSource& btf, const LpcaSettings& s) {
    const auto start = std::chrono::steady_clock::now();
    if (btf.empty()) throw Error("lpca: the BTF is empty");
    const std::size_t texels = btf.texelCount();
    const std::size_t dims = btf.viewCount() * btf.lightCount() * 3;
    const int K = s.clusters, c = s.components;
    if (std::size_t(c) > dims)
        throw Error("lpca: option components must be at most " + std::to_string(dims) +
                    " (the values per texel of this BTF), got " + std::to_string(c));
    if (std::size_t(K) > texels)
        throw Error("lpca: option clusters must be at most " + std::to_string(texels) +
                    " (the texels of this BTF), got " + std::to_string(K));
    std::mt19937_64 random(s.seed);  // training sample and refit subsampling

    // ---- training set ----
    std::size_t trainCount = s.trainingTexels == 0
                                 ? texels
                                 : std::min<std::size_t>(texels, std::size_t(s.trainingTexels));
    trainCount = std::max(trainCount, std::size_t(K));
    std::vector<std::size_t> train(texels);
    std::iota(train.begin(), train.end(), std::size_t(0));
    if (trainCount < texels) {
        for (std::size_t i = 0; i < trainCount; ++i)
            std::swap(train[i], train[i + random() % (texels - i)]);
        train.resize(trainCount);
        std::sort(train.begin(), train.end());
    }
    checkMemoryBeside(btf, std::uint64_t(train.size()) * dims * sizeof(float),
                      "lpca: the ABRDFs of " + std::to_string(train.size()) + " training texels");
    RowMatrix x;
    gatherRows(btf, train.data(), train.size(), x);
    const Eigen::VectorXf norms2 = x.rowwise().squaredNorm();
    const std::size_t n = train.size();

    // ---- clustering: LBG-style doubling of generalised Lloyd iterations ----
    // Start with one cluster; iterate (refit the subspaces, reassign) to convergence; split every
    // cluster (the worst ones when fewer splits are needed) into its better and worse
    // reconstructed halves; repeat until K clusters. Deterministic for a given training set, and
    // a K-cluster fit passes through the converged state of each smaller doubling, so more
    // clusters do not end with a larger training error (k-means++ seeding often did).
    std::vector<int> clusterOf(n, 0);
    std::vector<double> error(n, 0.0);
    ColMatrix basis = ColMatrix::Zero(Eigen::Index(dims), Eigen::Index(K) * c);
    const bool viaGram = n < dims && n <= kMaxGramTexels;
    Eigen::MatrixXd gram;
    if (viaGram) gram = trainingGram(x);
    // Gram path: cluster k's Eigen-BRDFs are x[fitted[k]]^T coefficients[k].
    std::vector<std::vector<std::size_t>> fitted(static_cast<std::size_t>(K));
    std::vector<Eigen::MatrixXd> coefficients(static_cast<std::size_t>(K));
    RowMatrix projections;
    double total = 0;
    int iterations = 0, current = 1, reported = 0;
    {
        Progress progress("lpca: clustering", std::size_t(K));
        for (;;) {
            // Intermediate phases only prepare the next split: a few iterations suffice.
            const int phaseIterations = current == K ? s.iterations : std::min(s.iterations, 5);
            double previous = 1e300;
            for (int it = 0; it < phaseIterations; ++it) {
                std::vector<std::vector<std::size_t>> members(static_cast<std::size_t>(current));
                for (std::size_t j = 0; j < n; ++j) members[std::size_t(clusterOf[j])].push_back(j);
                // An empty cluster takes the worst-reconstructed texel of the largest cluster.
                for (int k = 0; k < current; ++k) {
                    if (!members[std::size_t(k)].empty()) continue;
                    auto& donor = *std::max_element(
                        members.begin(), members.end(),
                        [](const auto& a, const auto& b) { return a.size() < b.size(); });
                    if (donor.size() < 2) break;
                    auto worst = std::max_element(
                        donor.begin(), donor.end(),
                        [&](std::size_t a, std::size_t b) { return error[a] < error[b]; });
                    members[std::size_t(k)].push_back(*worst);
                    clusterOf[*worst] = k;
                    donor.erase(worst);
                }
                for (auto& m : members)
                    if (m.size() > kMaxRefitMembers) {
                        std::shuffle(m.begin(), m.end(), random);
                        m.resize(kMaxRefitMembers);
                    }
                const std::vector<int> previousAssignment = clusterOf;
                if (viaGram) {
                    tbb::parallel_for(0, current, [&](int k) {
                        coefficients[std::size_t(k)] =
                            fitSubspaceGram(gram, members[std::size_t(k)], c, Eigen::Index(dims));
                    });
                    for (int k = 0; k < current; ++k)
                        fitted[std::size_t(k)] = members[std::size_t(k)];
                    assignGram(gram, fitted, coefficients, current, clusterOf, error);
                } else {
                    tbb::parallel_for(0, current, [&](int k) {
                        fitSubspace(x, members[std::size_t(k)], c,
                                    basis.middleCols(Eigen::Index(k) * c, c));
                    });
                    assign(x, norms2, basis.leftCols(Eigen::Index(current) * c), current, c,
                           clusterOf, error, projections);
                }
                total = std::accumulate(error.begin(), error.end(), 0.0);
                ++iterations;
                if (clusterOf == previousAssignment || previous - total <= 1e-4 * previous) break;
                previous = total;
            }
            progress.advance(std::size_t(current - reported));
            reported = current;
            if (current == K) break;
            std::vector<double> clusterError(std::size_t(current), 0.0);
            for (std::size_t j = 0; j < n; ++j) clusterError[std::size_t(clusterOf[j])] += error[j];
            std::vector<int> order(static_cast<std::size_t>(current));
            std::iota(order.begin(), order.end(), 0);
            std::stable_sort(order.begin(), order.end(), [&](int a, int b) {
                return clusterError[std::size_t(a)] > clusterError[std::size_t(b)];
            });
            const int splits = std::min(current, K - current);
            for (int i = 0; i < splits; ++i) {
                const int from = order[std::size_t(i)], to = current + i;
                std::vector<double> errors;
                for (std::size_t j = 0; j < n; ++j)
                    if (clusterOf[j] == from) errors.push_back(error[j]);
                if (errors.size() < 2) continue;  // stays empty: the rule above fills it
                std::nth_element(errors.begin(), errors.begin() + errors.size() / 2, errors.end());
                const double median = errors[errors.size() / 2];
                std::size_t moved = 0;
                for (std::size_t j = 0; j < n && moved + 1 < errors.size(); ++j)
                    if (clusterOf[j] == from && error[j] >= median) {
                        clusterOf[j] = to;
                        ++moved;
                    }
            }
            current += splits;
        }
    }
    const double trainingRms = std::sqrt(total / double(n * dims));
    if (viaGram) {
        gram.resize(0, 0);
        // The Eigen-BRDFs themselves, once: E_k = x[fitted[k]]^T A_k.
        tbb::parallel_for(0, K, [&](int k) {
            const std::vector<std::size_t>& m = fitted[std::size_t(k)];
            Eigen::MatrixXd e = Eigen::MatrixXd::Zero(Eigen::Index(dims), c);
            for (std::size_t i = 0; i < m.size(); ++i)
                e.noalias() += x.row(Eigen::Index(m[i])).transpose().cast<double>() *
                               coefficients[std::size_t(k)].row(Eigen::Index(i));
            basis.middleCols(Eigen::Index(k) * c, c) = e.cast<float>();
        });
    }
    x.resize(0, 0);
    projections.resize(0, 0);

    // ---- the model: half Eigen-BRDFs; every texel assigned and projected with them ----
    osg::ref_ptr<LpcaMaterial> m = new LpcaMaterial;
    m->setGeometry(btf.width(), btf.height(), btf.views(), btf.lights());
    for (Eigen::Index i = 0; i < basis.size(); ++i)
        basis.data()[i] = float(Imath::half(basis.data()[i]));
    // Column k c + i of the basis is Eigen-BRDF i of cluster k, [view][light][rgb]; the material
    // holds them as the file does, [cluster][view][component][light][rgb].
    const std::size_t views = btf.viewCount(), run = btf.lightCount() * 3;
    m->eigenBrdfs = StoredValues(MaterialTexture::Half, std::size_t(K) * c * dims);
    for (int k = 0; k < K; ++k)
        for (int i = 0; i < c; ++i)
            for (std::size_t v = 0; v < views; ++v)
                m->eigenBrdfs.write(((std::size_t(k) * views + v) * c + i) * run,
                                    basis.col(Eigen::Index(k) * c + i).data() + v * run, run);
    m->clusterOf.resize(texels);
    m->weights = StoredValues(MaterialTexture::Half, lpcaWeightCount(texels, c));
    double allError = 0;
    {
        Progress progress("lpca: projecting", texels);
        std::vector<std::size_t> chunk;
        RowMatrix rows;
        std::vector<int> chunkCluster;
        std::vector<double> chunkError;
        for (std::size_t t0 = 0; t0 < texels; t0 += kChunkTexels) {
            const std::size_t count = std::min(kChunkTexels, texels - t0);
            chunk.resize(count);
            std::iota(chunk.begin(), chunk.end(), t0);
            gatherRows(btf, chunk.data(), count, rows);
            const Eigen::VectorXf rowNorms2 = rows.rowwise().squaredNorm();
            assign(rows, rowNorms2, basis, K, c, chunkCluster, chunkError, projections);
            for (std::size_t j = 0; j < count; ++j) {
                const int k = chunkCluster[j];
                m->clusterOf[t0 + j] = std::uint8_t(k);
                for (int i = 0; i < c; ++i)
                    m->weights.set(lpcaWeightIndex(texels, t0 + j, i),
                                   projections(Eigen::Index(j), Eigen::Index(k) * c + i));
                allError += chunkError[j];
            }
            progress.advance(count);
        }
    }
    m->finishSetup(K, c);
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    auto text = [](double v) {
        std::ostringstream out;
        out << v;
        return out.str();
    };
    m->fitInfo["seconds"] = text(seconds);
    m->fitInfo["iterations"] = std::to_string(iterations);
    m->fitInfo["training_texels"] = std::to_string(n);
    m->fitInfo["clustering"] = viaGram ? "gram" : "direct";
    m->fitInfo["training_rms"] = text(trainingRms);
    m->fitInfo["rms"] = text(std::sqrt(allError / double(texels * dims)));
    return m;
}

namespace {
// The fit hook of the method registered in Lpca.cpp (libosgBTF).
const bool lpcaFitterRegistered = registerFitterClass<LpcaMaterial>();
}  // namespace

}  // namespace osgBTF
