// PTM's fit (libosgBTFFit): least squares of the biquadratic in (lx, ly) per texel and view slot,
// through the lights' pseudo-inverse computed once (fit/LightBasisFit.h).
#include "materials/MethodOptions.h"
#include "materials/ptm/Ptm.h"

#include <chrono>
#include <sstream>

#include <Eigen/Core>

#include "core/Error.h"
#include "fit/LightBasisFit.h"

namespace osgBTF {

// ---- fitter ------------------------------------------------------------------------------------

namespace {

LightBasisDesign ptmDesign(const DirectionSet& lights) {
    Eigen::MatrixXd a(Eigen::Index(lights.size()), PtmMaterial::kTerms);
    for (Eigen::Index l = 0; l < a.rows(); ++l) {
        const auto row = PtmMaterial::monomials(lights.vector(std::size_t(l)));
        for (int k = 0; k < PtmMaterial::kTerms; ++k) a(l, k) = row[std::size_t(k)];
    }
    return makeLightBasisDesign(a);
}

/** Stores one texel's fit: `c` holds the unrounded least-squares coefficients of its R, G and B
 *  channels (rows), in double. */
void storePtmTexel(PtmMaterial& m, const LightBasisDesign& design, std::size_t texel, int slot,
                   const Eigen::Ref<const Eigen::MatrixXd>& c) {
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
    const std::size_t front = frontViewOf(btf.views());
    const int slots = shape.perView ? int(btf.viewCount()) : 1;
    const std::size_t layers = shape.luminance ? 2 : kTerms;
    const std::uint64_t modelBytes = std::uint64_t(btf.texelCount()) * std::size_t(slots) *
                                     (layers * 3 + (shape.luminance ? 3 : 0)) * sizeof(float);
    checkMemoryBeside(btf, modelBytes + lightBasisFitWorkingBytes(btf, shape.perView),
                "ptm: the model and the images of the views fitted at once");
    osg::ref_ptr<PtmMaterial> m =
        create(btf.width(), btf.height(), btf.views(), btf.lights(), shape, front);
    const LightBasisDesign design = ptmDesign(btf.lights());
    fitLightBasis(btf, design, shape.perView, front,
                  shape.perView ? "ptm: fitting " + std::to_string(slots) + " views"
                                : std::string("ptm: fitting the front view"),
                  [&](std::size_t texel, int slot, const Eigen::Ref<const Eigen::MatrixXd>& c) {
                      storePtmTexel(*m, design, texel, slot, c);
                  });

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
