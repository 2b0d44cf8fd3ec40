// PTM's fit (libosgBTFFit): least squares of the biquadratic in (lx, ly) per texel and view slot,
// through the lights' pseudo-inverse computed once.
#include "materials/ptm/Ptm.h"

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <sstream>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <Eigen/Core>
#include <Eigen/SVD>

#include "core/Error.h"
#include "core/Progress.h"

namespace osgBTF {

// ---- fitter ------------------------------------------------------------------------------------

namespace {

/** The lights' design matrix and what the fit derives from it once for all texels. */
struct Design {
    Eigen::MatrixXd pinvT;  ///< (A+)^T, lights x 6: coefficients of a column y are y^T (A+)^T
    Eigen::MatrixXd gram;   ///< A^T A, 6 x 6
    int rank = 0;
    double condition = 0;  ///< largest / smallest kept singular value
};

Design makeDesign(const DirectionSet& lights) {
    const Eigen::Index n = Eigen::Index(lights.size());
    Eigen::MatrixXd a(n, PtmMaterial::kTerms);
    for (Eigen::Index l = 0; l < n; ++l) {
        const auto row = PtmMaterial::monomials(lights.vector(std::size_t(l)));
        for (int k = 0; k < PtmMaterial::kTerms; ++k) a(l, k) = row[std::size_t(k)];
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd& s = svd.singularValues();
    // Singular values at the level of rounding are no information about the data: clamped to zero
    // (the paper's "clamp small eigenvalues"), so fewer than 6 lights, or lights on one line, give
    // the minimum-norm polynomial instead of amplified noise. Eigen's own rank threshold.
    const double threshold =
        s.size() > 0 ? s(0) * double(std::max<Eigen::Index>(n, PtmMaterial::kTerms)) * DBL_EPSILON
                     : 0.0;
    Eigen::VectorXd inverse = Eigen::VectorXd::Zero(s.size());
    Design d;
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

/** Stores one texel's fit: `c` holds the unrounded least-squares coefficients of its R, G and B
 *  channels (rows), in double. */
void storeTexel(PtmMaterial& m, const Design& design, std::size_t texel, int slot,
                const Eigen::Matrix<double, 3, PtmMaterial::kTerms>& c) {
    const MaterialTexture::PixelKind kind = m.shape().storage;
    if (!m.shape().luminance) {
        for (int ch = 0; ch < 3; ++ch)
            for (int k = 0; k < PtmMaterial::kTerms; ++k)
                m.setCoefficient(texel, slot, k, ch, PtmMaterial::toStorage(c(ch, k), kind));
        return;
    }
    // The luminance PTM is the luminance of the channel PTMs (least squares is linear), rounded
    // to storage; the colour is then the least-squares colour for exactly that stored polynomial.
    Eigen::Matrix<double, PtmMaterial::kTerms, 1> stored;
    for (int k = 0; k < PtmMaterial::kTerms; ++k) {
        double y = 0;
        for (int ch = 0; ch < 3; ++ch) y += PtmMaterial::kLuminance[std::size_t(ch)] * c(ch, k);
        stored(k) = PtmMaterial::toStorage(y, kind);
        m.setCoefficient(texel, slot, k, 0, float(stored(k)));
    }
    const Eigen::Matrix<double, PtmMaterial::kTerms, 1> gp = design.gram * stored;
    const double pp = stored.dot(gp);  // <P, P> over the measured lights
    const std::size_t out = (std::size_t(slot) * m.texelCount() + texel) * 3;
    for (int ch = 0; ch < 3; ++ch)
        // <y_c, P> = (A^T y_c) . a = (A^T A c_c) . a; a zero polynomial (black texel) gets white,
        // which has unit luminance like every other colour.
        m.colour.set(out + ch, PtmMaterial::toStorage(
                                   pp > 0 ? c.row(ch).dot(gp.transpose()) / pp : 1.0, kind));
}

}  // namespace

osg::ref_ptr<PtmMaterial> PtmMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const OptionValues o = validateOptions(kMethod, options);
    if (btf.empty()) throw Error("ptm: the BTF is empty");
    Shape shape;
    shape.luminance = o.choice("colour") == "luminance";
    shape.perView = o.choice("views") == "all";
    shape.storage = o.choice("storage") == "float" ? MaterialTexture::Float : MaterialTexture::Half;

    // The measured view nearest the normal (the paper's front view).
    std::size_t front = 0;
    for (std::size_t v = 1; v < btf.viewCount(); ++v)
        if (btf.views().vector(v).z > btf.views().vector(front).z) front = v;

    const std::size_t texels = btf.texelCount(), lights = btf.lightCount(), rows = texels * 3;
    const int slots = shape.perView ? int(btf.viewCount()) : 1;
    // The model plus, per worker fitting a view, that view's images (a views=all fit runs views in
    // parallel; a front fit reads its one view in parallel blocks into one buffer).
    const std::size_t workers = std::min<std::size_t>(
        std::size_t(slots), std::size_t(std::max(1, tbb::this_task_arena::max_concurrency())));
    const std::size_t layers = shape.luminance ? 2 : kTerms;
    const std::uint64_t modelBytes = std::uint64_t(texels) * std::size_t(slots) *
                                     (layers * 3 + (shape.luminance ? 3 : 0)) * sizeof(float);
    checkMemory(modelBytes + std::uint64_t(workers) * rows * lights * sizeof(float),
                "ptm: the model and the images of " + std::to_string(workers) + " view(s)");
    osg::ref_ptr<PtmMaterial> m =
        create(btf.width(), btf.height(), btf.views(), btf.lights(), shape, front);
    const Design design = makeDesign(btf.lights());

    // Images per read: ~16 MiB, at least what the source reads efficiently.
    const std::size_t perRead =
        std::clamp<std::size_t>((std::size_t(16) << 20) / std::max<std::size_t>(rows * 4, 1),
                                std::max<std::size_t>(btf.imageBlock(), 1), lights);
    const std::size_t reads = (lights + perRead - 1) / perRead;
    // Texels per coefficient product: the double copy of their rows stays small.
    const std::size_t texelBlock = 4096;
    const std::size_t texelBlocks = (texels + texelBlock - 1) / texelBlock;

    Progress progress(shape.perView ? "ptm: fitting " + std::to_string(slots) + " views"
                                    : std::string("ptm: fitting the front view"),
                      std::size_t(slots) * lights);
    const auto fitSlot = [&](int slot, bool parallelInside) {
        const std::size_t view = shape.perView ? std::size_t(slot) : front;
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
                storeTexel(*m, design, first + t, slot, c.middleRows(Eigen::Index(t * 3), 3));
        };
        if (parallelInside) {
            tbb::parallel_for(std::size_t(0), reads, read);
            tbb::parallel_for(std::size_t(0), texelBlocks, solve);
        } else {
            for (std::size_t r = 0; r < reads; ++r) read(r);
            for (std::size_t b = 0; b < texelBlocks; ++b) solve(b);
        }
    };
    if (shape.perView)
        // One view per task and nothing parallel inside: at most one image buffer per worker.
        tbb::parallel_for(0, slots, [&](int slot) { fitSlot(slot, false); });
    else
        fitSlot(0, true);
    progress.finish();

    std::ostringstream seconds, condition;
    seconds << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    condition << design.condition;
    m->fitInfo["seconds"] = seconds.str();
    m->fitInfo["colour"] = o.choice("colour");
    m->fitInfo["views"] = o.choice("views");
    m->fitInfo["storage"] = o.choice("storage");
    std::ostringstream frontView;
    frontView << btf.views()[front].theta << "/" << btf.views()[front].phi;
    m->fitInfo["front-view"] = frontView.str();
    m->fitInfo["rank"] = std::to_string(design.rank);
    m->fitInfo["condition"] = condition.str();
    return m;
}

namespace {
// The fit hook of the method registered in Ptm.cpp (libosgBTF).
const bool ptmFitterRegistered = registerFitterClass<PtmMaterial>();
}  // namespace

}  // namespace osgBTF
