// HSH's fit (libosgBTFFit): least squares of the harmonics per texel, channel and view slot,
// through the lights' pseudo-inverse computed once (fit/LightBasisFit.h).
#include "materials/MethodOptions.h"
#include "materials/hsh/Hsh.h"

#include <chrono>
#include <sstream>

#include <Eigen/Core>

#include "core/Error.h"
#include "fit/LightBasisFit.h"

namespace osgBTF {

osg::ref_ptr<HshMaterial> HshMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const OptionValues o = validateOptions(kMethod, options);
    if (btf.empty()) throw Error("hsh: the BTF is empty");
    Shape shape;
    shape.order = o.integer("order");
    shape.perView = o.choice("views") == "all";
    shape.storage = o.choice("storage") == "float" ? MaterialTexture::Float : MaterialTexture::Half;

    const std::size_t front = frontViewOf(btf.views());
    const int slots = shape.perView ? int(btf.viewCount()) : 1;
    const int terms = shape.order * shape.order;
    checkMemoryBeside(btf,
                      std::uint64_t(btf.texelCount()) * std::size_t(slots) * std::size_t(terms) *
                              3 * sizeof(float) +
                          lightBasisFitWorkingBytes(btf, shape.perView),
                      "hsh: the model and the images of the views fitted at once");
    osg::ref_ptr<HshMaterial> m =
        create(btf.width(), btf.height(), btf.views(), btf.lights(), shape, front);

    Eigen::MatrixXd a(Eigen::Index(btf.lightCount()), terms);
    for (Eigen::Index l = 0; l < a.rows(); ++l) {
        const auto row = basisDouble(btf.lights().vector(std::size_t(l)));
        for (int k = 0; k < terms; ++k) a(l, k) = row[std::size_t(k)];
    }
    const LightBasisDesign design = makeLightBasisDesign(a);
    fitLightBasis(btf, design, shape.perView, front,
                  shape.perView ? "hsh: fitting " + std::to_string(slots) + " views"
                                : std::string("hsh: fitting the front view"),
                  [&](std::size_t texel, int slot, const Eigen::Ref<const Eigen::MatrixXd>& c) {
                      for (int ch = 0; ch < 3; ++ch)
                          for (int k = 0; k < terms; ++k)
                              m->setCoefficient(texel, slot, k, ch,
                                                toStorage(c(ch, k), shape.storage));
                  });

    std::ostringstream seconds, condition, frontView;
    seconds << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    condition << design.condition;
    frontView << btf.views()[front].theta << "/" << btf.views()[front].phi;
    m->fitInfo["seconds"] = seconds.str();
    m->fitInfo["order"] = std::to_string(shape.order);
    m->fitInfo["views"] = o.choice("views");
    m->fitInfo["storage"] = o.choice("storage");
    m->fitInfo["front-view"] = frontView.str();
    m->fitInfo["rank"] = std::to_string(design.rank);
    m->fitInfo["condition"] = condition.str();
    return m;
}

namespace {
// The fit hook of the method registered in Hsh.cpp (libosgBTF).
const bool hshFitterRegistered = registerFitterClass<HshMaterial>();
}  // namespace

}  // namespace osgBTF
