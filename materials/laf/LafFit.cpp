// LAF's fit (libosgBTFFit): LobeMaterial's fitter with T fixed at 1 (LobeMaterialFit.cpp).
#include "materials/MethodOptions.h"
#include "materials/laf/Laf.h"

#include "core/Error.h"

namespace osgBTF {

// ---- fitter: LobeMaterial's, with T fixed at 1 -----------------------------------------------

osg::ref_ptr<LafMaterial> LafMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const OptionValues o = validateOptions(kMethod, options);
    if (btf.empty() || btf.viewCount() == 0 || btf.lightCount() == 0)
        throw Error("laf: cannot fit an empty BTF");
    osg::ref_ptr<LafMaterial> m =
        create(btf.width(), btf.height(), o.integer("lobes"), btf.views(), btf.lights());
    m->_cosine = o.flag("cosine");
    m->fitLobes(btf, o.integer("iterations"), 0, nullptr);
    return m;
}

namespace {
// The fit hook of the method registered in Laf.cpp (libosgBTF).
const bool lafFitterRegistered = registerFitterClass<LafMaterial>();
}  // namespace

}  // namespace osgBTF
