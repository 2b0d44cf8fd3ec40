// FMF's fit (libosgBTFFit): one streamed truncated SVD of the whole BTF as a (3 x images) x
// texels matrix, read in blocks of images.
#include "materials/MethodOptions.h"
#include "materials/fmf/Fmf.h"

#include <algorithm>
#include <chrono>

#include <tbb/task_arena.h>

#include "core/Error.h"
#include "core/LowRank.h"
#include "core/Progress.h"

namespace osgBTF {

// ---- fit -------------------------------------------------------------------------------------

osg::ref_ptr<FmfMaterial> FmfMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const OptionValues o = validateOptions(kMethod, options);
    if (btf.empty()) throw Error("fmf: the BTF is empty");
    const int components = o.integer("components");
    const MaterialTexture::PixelKind storage =
        o.choice("storage") == "float" ? MaterialTexture::Float : MaterialTexture::Half;
    const std::size_t texels = btf.texelCount(), images = btf.viewCount() * btf.lightCount();
    const std::size_t rows = images * 3, maxComponents = std::min(rows, texels);
    if (std::size_t(components) > maxComponents)
        throw Error("fmf: option components must be at most " + std::to_string(maxComponents) +
                    " for this BTF (its texels, or 3 x views x lights if fewer), got " +
                    std::to_string(components));

    // Rows (image, channel) in blocks of whole images, read straight from the BTF's storage:
    // the only copies are one block per thread, de-interleaved into A^T's columns.
    const std::size_t blockImages = std::max<std::size_t>(
        btf.imageBlock(),
        std::clamp<std::size_t>((std::size_t(16) << 20) / (texels * 3 + 1), 1, 256));
    RowBlockSource source;
    source.rows = rows;
    source.cols = texels;
    source.blockRows = blockImages * 3;
    source.fill = [&btf, texels](std::size_t first, std::size_t count, float* out) {
        const std::size_t firstImage = first / 3, images = count / 3;
        std::vector<float> interleaved(images * texels * 3);
        btf.readImages(firstImage, images, interleaved.data());
        for (std::size_t j = 0; j < images; ++j) {
            const float* f = interleaved.data() + j * texels * 3;
            float* r = out + (j * 3) * texels;
            float* g = r + texels;
            float* b = g + texels;
            for (std::size_t t = 0; t < texels; ++t, f += 3) r[t] = f[0], g[t] = f[1], b[t] = f[2];
        }
    };
    StreamedSvdOptions svdOptions;
    // What the streamed SVD holds (core/LowRank.cpp): on the Gram path four partial texels x
    // texels sums and the total, in double; on the randomised path A^T Y (texels x (rank +
    // oversampling)) as four float partial sums, their double total and the basis; beside them one
    // block of images per worker, read and de-interleaved.
    const std::uint64_t sketch = std::min<std::uint64_t>(
        std::uint64_t(components) + std::uint64_t(svdOptions.oversampling), rows);
    const std::uint64_t workers =
        std::uint64_t(std::max(1, tbb::this_task_arena::max_concurrency()));
    checkMemoryBeside(btf,
                      (texels <= svdOptions.gramColumns ? std::uint64_t(texels) * texels * 8 * 5
                                                        : std::uint64_t(texels) * sketch * 32) +
                          workers * std::uint64_t(blockImages) * texels * 3 * sizeof(float) * 2,
                      "fmf: the streamed SVD of " + std::to_string(rows) + " x " +
                          std::to_string(texels) + " values");
    Progress progress(
        "fmf: factorising " + std::to_string(rows) + " x " + std::to_string(texels) + " values",
        rows * std::size_t(svdOptions.passes(texels)));
    svdOptions.progress = [&progress](std::size_t n) { progress.advance(n); };
    const TruncatedSvd svd = streamedTruncatedSvd(source, components, svdOptions);
    progress.finish();

    FactoredBtf factors;
    factors.model = FactorModel::Fmf;
    factors.source = btf.source.empty() ? std::string(kMethod) : btf.source;
    factors.views = btf.views();
    factors.lights = btf.lights();
    factors.width = btf.width();
    factors.height = btf.height();
    factors.factors.resize(1);
    BtfFactor& f = factors.factors[0];
    f.S.resize(components);
    for (int k = 0; k < components; ++k) f.S(k) = float(svd.singularValues[std::size_t(k)]);
    f.U = Eigen::Map<const Eigen::MatrixXf>(svd.u.data(), Eigen::Index(rows), components);
    f.SxV.resize(Eigen::Index(texels), components);
    const Eigen::Map<const Eigen::MatrixXf> v(svd.v.data(), Eigen::Index(texels), components);
    for (int y = 0; y < btf.height(); ++y)
        for (int x = 0; x < btf.width(); ++x) {
            const Eigen::Index t = Eigen::Index(y) * btf.width() + x;
            f.SxV.row(Eigen::Index(factors.factorRow(x, y))) =
                v.row(t).cwiseProduct(f.S.transpose());
        }

    osg::ref_ptr<FmfMaterial> m = new FmfMaterial;
    m->setFactors(std::move(factors), storage);
    const double residual = svd.residualSquared();
    m->fitInfo["seconds"] = std::to_string(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    m->fitInfo["components"] = std::to_string(components);
    m->fitInfo["storage"] = o.choice("storage");
    m->fitInfo["algorithm"] = texels <= svdOptions.gramColumns ? "gram" : "randomised";
    // Share of the data's squared norm the rank-C factors capture (before rounding to half).
    m->fitInfo["energy"] =
        std::to_string(svd.totalSquared > 0 ? 1.0 - residual / svd.totalSquared : 1.0);
    return m;
}

namespace {
// The fit hook of the method registered in Fmf.cpp (libosgBTF).
const bool fmfFitterRegistered = registerFitterClass<FmfMaterial>();
}  // namespace

}  // namespace osgBTF
