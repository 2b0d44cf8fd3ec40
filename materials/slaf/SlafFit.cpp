// SLAF's fit (libosgBTFFit): LobeMaterial's fitter with the view table T fitted.
#include "materials/MethodOptions.h"
#include "materials/slaf/Slaf.h"

#include "core/Error.h"

namespace osgBTF {

// ---- fitter: LobeMaterial's, with the view table T fitted ------------------------------------

osg::ref_ptr<SlafMaterial> SlafMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const OptionValues o = validateOptions(kMethod, options);
    const int rounds = o.integer("rounds");
    if (btf.empty() || btf.viewCount() == 0 || btf.lightCount() == 0)
        throw Error("slaf: cannot fit an empty BTF");
    osg::ref_ptr<SlafMaterial> m =
        create(btf.width(), btf.height(), o.integer("lobes"), btf.views(), btf.lights());
    m->_cosine = o.flag("cosine");
    m->fitLobes(btf, o.integer("iterations"), rounds, &m->scale);
    m->fitInfo["rounds"] = std::to_string(rounds);
    return m;
}

namespace {
// The fit hook of the method registered in Slaf.cpp (libosgBTF).
const bool slafFitterRegistered = registerFitterClass<SlafMaterial>();
}  // namespace

}  // namespace osgBTF
