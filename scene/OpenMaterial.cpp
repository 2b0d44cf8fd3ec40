#include "scene/OpenMaterial.h"

#include "loaders/LoadBtf.h"
#include "loaders/Ubo2014.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

osg::ref_ptr<Material> openUbo2014Material(const std::string& path,
                                           MaterialTexture::PixelKind storage) {
    Ubo2014Factors file = readUbo2014(path);
    if (file.scalarSize == 2) storage = MaterialTexture::Half;
    osg::ref_ptr<Material> material =
        factorMethod().factors->fromFactors(std::move(static_cast<FactoredBtf&>(file)), storage);
    material->sourceFile = path;
    return material;
}

osg::ref_ptr<Material> openMaterial(const std::string& path, MaterialTexture::PixelKind storage) {
    return isUbo2014File(path) ? openUbo2014Material(path, storage) : loadMaterial(path);
}

}  // namespace osgBTF
