// osgBTF method "lambert": the plain lit texture, the baseline every BTF method must beat.
//
//   BTF(x, v, l) ~ rho(x) * l_z        (rho RGB; l_z = cos theta_l, the foreshortening)
//
// Fit: per texel and channel, least squares over all measured (v, l):
//   rho = sum(BTF * l_z) / sum(l_z^2).
// Memory: 3 values (RGB) per texel, stored as half: 3 values, 6 bytes.
#pragma once

#include "materials/MethodMaterial.h"
#include "materials/MethodOptions.h"
#include "materials/StoredValues.h"

namespace osgBTF {

/** LambertMaterial's members (materials/MethodMaterial.h). */
struct LambertData {
    /** RGB per texel, rows bottom-up; half, as the file stores it (materials/StoredValues.h). */
    StoredValues albedo;
};

class LambertMaterial : public MethodMaterial<LambertMaterial, LambertData> {
public:
    static constexpr const char* kMethod = "lambert";
    /** fromFile takes the file's half texture as it is stored. */
    static constexpr bool kLoadsHalves = true;

    LambertMaterial() = default;
    LambertMaterial(const LambertMaterial& other,
                    const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop) {}
    META_Object(osgBTF, LambertMaterial)

        static osg::ref_ptr<LambertMaterial> fit(const BtfSource& btf, const FitOptions& options);
    static osg::ref_ptr<LambertMaterial> fromFile(FittedMaterial file);

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    MemoryFootprint memory() const override;
    FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

protected:
    ~LambertMaterial() override = default;
};

}  // namespace osgBTF
