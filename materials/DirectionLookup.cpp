#include "materials/DirectionLookup.h"

#include <cmath>

#include "core/Error.h"
#include "materials/MaterialState.h"
#include "materials/ShaderCost.h"
#include "materials/ShaderInterface.h"

namespace osgBTF {

struct DirectionLookup::Shared {
    DirectionInterpolator interpolator;
    DirectionTable table;
    osg::ref_ptr<osg::Texture> texture;
};

DirectionLookup::DirectionLookup(const DirectionSet& directions) {
    auto shared = std::make_shared<Shared>();
    shared->interpolator = DirectionInterpolator(directions);
    shared->table =
        shared->interpolator.table(shader::kDirectionGrid, shader::kDirectionTableWidth);
    const DirectionTable& t = shared->table;
    shared->texture = createFloatTexture({"directions " + directions.name(), t.width, t.height, 1,
                                          4, MaterialTexture::Float, t.texels});
    _shared = std::move(shared);
}

const DirectionInterpolator& DirectionLookup::interpolator() const {
    if (!_shared) throw Error("direction lookup used before its direction set was given");
    return _shared->interpolator;
}

const DirectionTable& DirectionLookup::table() const {
    if (!_shared) throw Error("direction lookup used before its direction set was given");
    return _shared->table;
}

InterpolationWeights DirectionLookup::weights(const glm::vec3& direction) const {
    return interpolator().weights(direction);
}

void DirectionLookup::addToStateSet(osg::StateSet& stateSet, const std::string& sampler,
                                    int unit) const {
    table();  // throws when empty
    addTexture(stateSet, _shared->texture.get(), sampler, unit);
}

DirectionLookup::Cost DirectionLookup::cost() const {
    const DirectionTable& t = table();
    const double alu = ShaderCost::kLookupAlu +
                       t.meanTrianglesTested * ShaderCost::kLookupTriangleAlu +
                       t.meanEdgesTested * ShaderCost::kLookupEdgeAlu +
                       (1.0 - t.outsideShare) * ShaderCost::kLookupInsideAlu +
                       t.outsideShare * ShaderCost::kLookupOutsideAlu;
    const double tex = ShaderCost::kLookupTex +
                       t.meanTrianglesTested * ShaderCost::kLookupTriangleTex +
                       t.meanEdgesTested * ShaderCost::kLookupEdgeTex;
    return {int(std::lround(alu)), int(std::lround(tex))};
}

}  // namespace osgBTF
