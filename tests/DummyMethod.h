// A compression method defined entirely in the test binaries, registered like the built-in ones
// (tests/DummyMethod.cpp): the proof that MethodInfo's hooks are complete. Nothing outside these
// two files names "dummy", yet it shows up in fit --help, compare, the serializers, the scene
// round trip and the shader program (tests/method_plugin_test.cpp), and renders mip-mapped,
// through a coordinate map and under folded environment lighting with the GPU equal to its CPU
// reference (tests/gl/method_plugin_gl_test.cpp). Both test executables compile DummyMethod.cpp
// as one of their own sources, so its static registration is always linked in.
#pragma once

#include <vector>

#include "materials/MethodMaterial.h"
#include "materials/MethodOptions.h"

namespace osgBTFTest {

/** DummyMaterial's members (materials/MethodMaterial.h). */
struct DummyData {
    std::vector<float> value;  ///< RGB per texel
};

/** rho(x) * gain * l_z: a lit texture with one option, enough to exercise everything. Its
 *  environment lighting folds (MethodInfo::environment): sum_i g_i rho(x) l_i,z = rho(x) times
 *  one RGB value per vertex, sum_i g_i l_i,z. */
class DummyMaterial : public osgBTF::MethodMaterial<DummyMaterial, DummyData> {
public:
    static constexpr const char* kMethod = "dummy";

    DummyMaterial() = default;
    DummyMaterial(const DummyMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop) {}
    META_Object(osgBTFTest, DummyMaterial)

        static osg::ref_ptr<DummyMaterial> fit(const osgBTF::BtfSource& btf,
                                               const osgBTF::FitOptions& options);
    static osg::ref_ptr<DummyMaterial> fromFile(const osgBTF::FittedMaterial& file);

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    osgBTF::MemoryFootprint memory() const override;
    osgBTF::FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

    /** The texel's colour rho(x) (no light term). */
    glm::vec3 texel(int x, int y) const;
};

/** The dummy's point-light fragment shader, as registered (MethodInfo::fragmentShader). */
extern const char* const kDummyShader;
/** The dummy's environment fragment shader, as registered (environment/dummy.frag). */
extern const char* const kDummyEnvironmentShader;

}  // namespace osgBTFTest
