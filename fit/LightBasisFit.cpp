#include "fit/LightBasisFit.h"

#include <algorithm>
#include <cfloat>
#include <vector>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <Eigen/SVD>

#include "core/Progress.h"

namespace osgBTF {

LightBasisDesign makeLightBasisDesign(const Eigen::MatrixXd& a) {
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd& s = svd.singularValues();
    const double threshold =
        s.size() > 0 ? s(0) * double(std::max(a.rows(), a.cols())) * DBL_EPSILON : 0.0;
    Eigen::VectorXd inverse = Eigen::VectorXd::Zero(s.size());
    LightBasisDesign d;
    for (Eigen::Index i = 0; i < s.size(); ++i)
        if (s(i) > threshold) {
            inverse(i) = 1.0 / s(i);
            ++d.rank;
        }
    d.condition = d.rank > 0 ? s(0) / s(d.rank - 1) : 0.0;
    d.pinvT = svd.matrixU() * inverse.asDiagonal() * svd.matrixV().transpose();
    d.gram = a.transpose() * a;
    return d;
}

std::size_t frontViewOf(const DirectionSet& views) {
    std::size_t front = 0;
    for (std::size_t v = 1; v < views.size(); ++v)
        if (views.vector(v).z > views.vector(front).z) front = v;
    return front;
}

namespace {
std::size_t fitWorkers(const BtfSource& btf, bool perView) {
    // A per-view fit runs one view per worker; a front fit reads its one view in parallel
    // blocks into one buffer.
    return perView ? std::min<std::size_t>(
                         btf.viewCount(),
                         std::size_t(std::max(1, tbb::this_task_arena::max_concurrency())))
                   : 1;
}
}  // namespace

/** Texels per coefficient product (and, for data not in memory, per read): the same blocks on
 *  both paths, so that they give the same coefficients bit for bit. */
constexpr std::size_t kTexelBlock = 4096;

namespace {
/** Data not in memory is read in texel blocks when a block of every image is smaller than a
 *  view's images (a one-view capture of any size); factored data of many views (a UBO2014 file:
 *  151 views) stays with image reads of a view. */
bool fitsInTexelBlocks(const BtfSource& btf) {
    return !btf.inMemory() && kTexelBlock * btf.viewCount() < btf.texelCount();
}
}  // namespace

std::uint64_t lightBasisFitWorkingBytes(const BtfSource& btf, bool perView) {
    if (fitsInTexelBlocks(btf))
        // A block of texels' values (every image) per worker.
        return std::uint64_t(std::max(1, tbb::this_task_arena::max_concurrency())) * kTexelBlock *
               btf.imageCount() * 3 * sizeof(float);
    return std::uint64_t(fitWorkers(btf, perView)) * btf.texelCount() * 3 * btf.lightCount() *
           sizeof(float);
}

namespace {
/** The fit of data not in memory (an out-of-core capture, factored data): texel block by texel
 *  block, every slot of a block from one read, so that memory holds blocks, never a view. */
void fitLightBasisInBlocks(const BtfSource& btf, const LightBasisDesign& design, bool perView,
                           std::size_t frontView, const std::string& label,
                           const LightBasisStore& store) {
    const std::size_t texels = btf.texelCount(), lights = btf.lightCount();
    const std::size_t perTexel = btf.imageCount() * 3;
    const int slots = perView ? int(btf.viewCount()) : 1;
    const std::size_t blocks = (texels + kTexelBlock - 1) / kTexelBlock;
    Progress progress(label, texels);
    tbb::parallel_for(std::size_t(0), blocks, [&](std::size_t b) {
        const std::size_t first = b * kTexelBlock, count = std::min(kTexelBlock, texels - first);
        std::vector<float> abrdfs(count * perTexel);
        btf.readAbrdfRange(first, count, abrdfs.data());
        // Row 3 t + c, column l: the layout of the in-memory path's image columns.
        Eigen::MatrixXf y(Eigen::Index(count * 3), Eigen::Index(lights));
        for (int slot = 0; slot < slots; ++slot) {
            const std::size_t view = perView ? std::size_t(slot) : frontView;
            for (std::size_t t = 0; t < count; ++t)
                for (std::size_t l = 0; l < lights; ++l)
                    for (std::size_t c = 0; c < 3; ++c)
                        y(Eigen::Index(t * 3 + c), Eigen::Index(l)) =
                            abrdfs[t * perTexel + (view * lights + l) * 3 + c];
            const Eigen::MatrixXd coefficients = y.cast<double>() * design.pinvT;
            for (std::size_t t = 0; t < count; ++t)
                store(first + t, slot, coefficients.middleRows(Eigen::Index(t * 3), 3));
        }
        progress.advance(count);
    });
    progress.finish();
}
}  // namespace

void fitLightBasis(const BtfSource& btf, const LightBasisDesign& design, bool perView,
                   std::size_t frontView, const std::string& label, const LightBasisStore& store) {
    if (fitsInTexelBlocks(btf)) {
        fitLightBasisInBlocks(btf, design, perView, frontView, label, store);
        return;
    }
    const std::size_t texels = btf.texelCount(), lights = btf.lightCount(), rows = texels * 3;
    const int slots = perView ? int(btf.viewCount()) : 1;
    // Images per read: ~16 MiB, at least what the source reads efficiently.
    const std::size_t perRead =
        std::clamp<std::size_t>((std::size_t(16) << 20) / std::max<std::size_t>(rows * 4, 1),
                                std::max<std::size_t>(btf.imageBlock(), 1), lights);
    const std::size_t reads = (lights + perRead - 1) / perRead;
    // Texels per coefficient product: the double copy of their rows stays small.
    const std::size_t texelBlock = kTexelBlock;
    const std::size_t texelBlocks = (texels + texelBlock - 1) / texelBlock;

    Progress progress(label, std::size_t(slots) * lights);
    const auto fitSlot = [&](int slot, bool parallelInside) {
        const std::size_t view = perView ? std::size_t(slot) : frontView;
        // Column l = image (view, l): the view's values as a rows x lights matrix Y^T.
        std::vector<float> images(rows * lights);
        const auto read = [&](std::size_t r) {
            const std::size_t first = r * perRead, count = std::min(perRead, lights - first);
            btf.readImages(view * lights + first, count, images.data() + first * rows);
            progress.advance(count);
        };
        const auto solve = [&](std::size_t b) {
            const std::size_t first = b * texelBlock, count = std::min(texelBlock, texels - first);
            const Eigen::Map<const Eigen::MatrixXf> y(images.data(), Eigen::Index(rows),
                                                      Eigen::Index(lights));
            // One product for the block: row 3 t + c = the coefficients of texel t, channel c.
            const Eigen::MatrixXd c =
                y.middleRows(Eigen::Index(first * 3), Eigen::Index(count * 3)).cast<double>() *
                design.pinvT;
            for (std::size_t t = 0; t < count; ++t)
                store(first + t, slot, c.middleRows(Eigen::Index(t * 3), 3));
        };
        if (parallelInside) {
            tbb::parallel_for(std::size_t(0), reads, read);
            tbb::parallel_for(std::size_t(0), texelBlocks, solve);
        } else {
            for (std::size_t r = 0; r < reads; ++r) read(r);
            for (std::size_t b = 0; b < texelBlocks; ++b) solve(b);
        }
    };
    if (perView)
        // One view per task and nothing parallel inside: at most one image buffer per worker.
        tbb::parallel_for(0, slots, [&](int slot) { fitSlot(slot, false); });
    else
        fitSlot(0, true);
    progress.finish();
}

}  // namespace osgBTF
