#include "fit/MipMapping.h"
#include "materials/MethodRegistry.h"

#include "core/MipPyramid.h"

namespace osgBTF {

osg::ref_ptr<Material> fitMipMapped(const MethodInfo& method, const BtfSource& source,
                                    const FitOptions& options) {
    const MipAtlasSource atlas(source);
    osg::ref_ptr<Material> material = method.fit(atlas, options);
    material->setMipLayout(atlas.layout());
    material->fitInfo["mipLevels"] = std::to_string(atlas.layout().levelCount());
    return material;
}

}  // namespace osgBTF
