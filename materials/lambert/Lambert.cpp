#include "materials/lambert/Lambert.h"

#include "core/Error.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

glm::vec3 LambertMaterial::evaluate(int x, int y, const glm::vec3&, const glm::vec3& light) const {
    const std::size_t t = (std::size_t(y) * _width + x) * 3;
    return glm::vec3(albedo[t], albedo[t + 1], albedo[t + 2]) * light.z;
}

MemoryFootprint LambertMaterial::memory() const {
    return {3.0, 6.0, std::uint64_t(albedo.bytes())};
}

FittedMaterial LambertMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.textures.push_back(albedo.texture("albedo", _width, _height, 1, 3));
    return file;
}

osg::ref_ptr<LambertMaterial> LambertMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<LambertMaterial> m = new LambertMaterial;
    m->readCommon(file);
    // The file is this function's own: its values are taken.
    MaterialTexture& t = file.texture("albedo");
    if (t.width != m->_width || t.height != m->_height || t.channels != 3)
        fail(file.source, "texture 'albedo' must be " + std::to_string(m->_width) + "x" +
                              std::to_string(m->_height) + " RGB");
    m->albedo = StoredValues::take(t, MaterialTexture::Half);
    return m;
}

osg::ref_ptr<osg::StateSet> LambertMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addTexture(
        *stateSet,
        createFloatTexture(albedo.texture("albedo", _width, _height, 1, 3), filtersParameters())
            .get(),
        "lambertAlbedo", 0);
    return stateSet;
}

namespace {
const bool lambertRegistered = registerMethodClass<LambertMaterial>([] {
    MethodInfo m;
    m.description = "plain lit texture: rho(x) * cos(theta_l), the baseline";
    // One albedo fetch, times l_z.
    m.shaderCost = [](const Material&) { return ShaderCost::ofEvaluate(1, 1, "ALU 11, TEX 1"); };
    m.filtersParameters = true;  // the value is the albedo times l_z
    m.baseline = true;
    m.compareAll = false;  // the comparison always adds it as its baseline
    m.order = 0;
    return m;
}());
}  // namespace

}  // namespace osgBTF
