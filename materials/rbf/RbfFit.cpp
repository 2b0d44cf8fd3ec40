// rbf's fit (libosgBTFFit): one PCA of the front view's per-texel light profiles (relight's
// RtiBuilder::pickBasePCA in colorspace mrgb, from its description; no code taken), the
// coefficients projected and rounded to storage.
#include "materials/MethodOptions.h"
#include "materials/rbf/Rbf.h"

#include <chrono>
#include <mutex>
#include <sstream>

#include <tbb/parallel_for.h>
#include <Eigen/Core>
#include <Eigen/Eigenvalues>

#include "core/Error.h"
#include "core/SizeGuard.h"
#include "fit/LightBasisFit.h"

namespace osgBTF {

osg::ref_ptr<RbfMaterial> RbfMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const OptionValues o = validateOptions(kMethod, options);
    if (btf.empty()) throw Error("rbf: the BTF is empty");
    const int planes = o.integer("planes");
    const float sigma = float(o.number("sigma"));
    const MaterialTexture::PixelKind storage =
        o.choice("storage") == "float" ? MaterialTexture::Float : MaterialTexture::Half;
    const std::size_t lights = btf.lightCount(), dim = lights * 3, texels = btf.texelCount();
    if (lights > std::size_t(kMaxNodes))
        throw Error("rbf: " + std::to_string(lights) + " lights, at most " +
                    std::to_string(kMaxNodes) + " are held");
    if (std::size_t(planes) > std::min(dim, texels))
        throw Error("rbf: option planes " + std::to_string(planes) + " exceeds 3 x lights (" +
                    std::to_string(dim) + ") or the texels (" + std::to_string(texels) + ")");
    const std::size_t front = frontViewOf(btf.views());
    osg::ref_ptr<RbfMaterial> m = create(btf.width(), btf.height(), btf.views(), btf.lights(),
                                         planes, int(lights), sigma, 0, storage);
    for (std::size_t l = 0; l < lights; ++l) m->setNode(int(l), btf.lights().vector(l));

    // Pass 1: the sum and the second moments of the profiles (double), block by block.
    const std::size_t block = btf.abrdfBlockTexels(), values = btf.imageCount() * 3;
    const std::size_t blocks = (texels + block - 1) / block;
    checkMemory(saturatedProduct({dim, dim, sizeof(double), 2}) +
                    saturatedProduct({block, values, sizeof(float), 2}),
                "rbf: the profiles' second moments");
    Eigen::VectorXd sum = Eigen::VectorXd::Zero(Eigen::Index(dim));
    Eigen::MatrixXd moments = Eigen::MatrixXd::Zero(Eigen::Index(dim), Eigen::Index(dim));
    std::mutex merge;
    const auto profiles = [&](std::size_t b, Eigen::MatrixXd& x) {
        const std::size_t first = b * block, count = std::min(block, texels - first);
        std::vector<float> abrdfs(count * values);
        btf.readAbrdfRange(first, count, abrdfs.data());
        x.resize(Eigen::Index(dim), Eigen::Index(count));
        for (std::size_t t = 0; t < count; ++t)
            for (std::size_t k = 0; k < dim; ++k)
                x(Eigen::Index(k), Eigen::Index(t)) = abrdfs[t * values + front * dim + k];
        return first;
    };
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
        Eigen::MatrixXd x;
        profiles(b, x);
        const Eigen::VectorXd s = x.rowwise().sum();
        Eigen::MatrixXd mm = Eigen::MatrixXd::Zero(x.rows(), x.rows());
        mm.selfadjointView<Eigen::Lower>().rankUpdate(x);
        std::lock_guard<std::mutex> lock(merge);
        sum += s;
        moments += mm;
    });
    const Eigen::VectorXd mean = sum / double(texels);
    Eigen::MatrixXd covariance = moments.selfadjointView<Eigen::Lower>();
    covariance -= double(texels) * mean * mean.transpose();
    const Eigen::SelfAdjointEigenSolver<Eigen::MatrixXd> eigen(covariance);
    if (eigen.info() != Eigen::Success) throw Error("rbf: the eigen-decomposition failed");
    // Eigen sorts ascending: the principal profiles are the last columns.
    Eigen::MatrixXd principal(Eigen::Index(dim), planes);
    double kept = 0, total = std::max(0.0, eigen.eigenvalues().sum());
    for (int p = 0; p < planes; ++p) {
        const Eigen::Index column = Eigen::Index(dim) - 1 - p;
        principal.col(p) = eigen.eigenvectors().col(column);
        kept += std::max(0.0, eigen.eigenvalues()(column));
    }
    for (std::size_t l = 0; l < lights; ++l) {
        m->setBasisValue(
            0, int(l),
            glm::vec3(float(mean(Eigen::Index(l * 3))), float(mean(Eigen::Index(l * 3 + 1))),
                      float(mean(Eigen::Index(l * 3 + 2)))));
        for (int p = 0; p < planes; ++p)
            m->setBasisValue(p + 1, int(l),
                             glm::vec3(float(principal(Eigen::Index(l * 3), p)),
                                       float(principal(Eigen::Index(l * 3 + 1), p)),
                                       float(principal(Eigen::Index(l * 3 + 2), p))));
    }

    // Pass 2: each texel's coefficients, projected on the principal profiles, rounded to storage.
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
        Eigen::MatrixXd x;
        const std::size_t first = profiles(b, x);
        x.colwise() -= mean;
        const Eigen::MatrixXd a = principal.transpose() * x;
        for (Eigen::Index t = 0; t < a.cols(); ++t)
            for (int p = 0; p < planes; ++p)
                m->setCoefficient(first + std::size_t(t), p, float(a(p, t)));
    });

    std::ostringstream seconds, variance, frontView;
    seconds << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    variance << (total > 0 ? kept / total : 1.0);
    frontView << btf.views()[front].theta << "/" << btf.views()[front].phi;
    m->fitInfo["seconds"] = seconds.str();
    m->fitInfo["planes"] = std::to_string(planes);
    m->fitInfo["sigma"] = std::to_string(sigma);
    m->fitInfo["storage"] = o.choice("storage");
    m->fitInfo["front-view"] = frontView.str();
    m->fitInfo["variance-kept"] = variance.str();
    return m;
}

namespace {
// The fit hook of the method registered in Rbf.cpp (libosgBTF).
const bool rbfFitterRegistered = registerFitterClass<RbfMaterial>();
}  // namespace

}  // namespace osgBTF
