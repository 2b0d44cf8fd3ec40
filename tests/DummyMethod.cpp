#include "tests/DummyMethod.h"

#include "core/ShaderSource.h"
#include "materials/EnvironmentLighting.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"

namespace osgBTFTest {

using namespace osgBTF;

osg::ref_ptr<DummyMaterial> DummyMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const OptionValues o = validateOptions(kMethod, options);
    osg::ref_ptr<DummyMaterial> m = new DummyMaterial;
    m->setGeometry(btf.width(), btf.height(), btf.views(), btf.lights());
    m->value.assign(btf.texelCount() * 3, 0.0f);
    const float gain = float(o.number("gain"));
    std::vector<float> abrdf(btf.imageCount() * 3);
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        btf.readAbrdfs(&t, 1, abrdf.data());
        // The first measured value, as a plain colour: a poor model, but a deterministic one.
        for (int c = 0; c < 3; ++c) m->value[t * 3 + c] = abrdf[std::size_t(c)] * gain;
    }
    return m;
}

osg::ref_ptr<DummyMaterial> DummyMaterial::fromFile(const FittedMaterial& file) {
    osg::ref_ptr<DummyMaterial> m = new DummyMaterial;
    m->readCommon(file);
    m->value = file.texture("value").data;
    return m;
}

glm::vec3 DummyMaterial::texel(int x, int y) const {
    const std::size_t t = (std::size_t(y) * std::size_t(_width) + std::size_t(x)) * 3;
    return glm::vec3(value[t], value[t + 1], value[t + 2]);
}

glm::vec3 DummyMaterial::evaluate(int x, int y, const glm::vec3&, const glm::vec3& light) const {
    return texel(x, y) * light.z;
}

MemoryFootprint DummyMaterial::memory() const {
    return {3.0, 12.0, std::uint64_t(value.size()) * 4};
}

FittedMaterial DummyMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.textures.push_back({"value", _width, _height, 1, 3, MaterialTexture::Float, value});
    return file;
}

osg::ref_ptr<osg::StateSet> DummyMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addTexture(
        *stateSet,
        createFloatTexture({"value", _width, _height, 1, 3, MaterialTexture::Float, value}).get(),
        "dummyValue", 0);
    return stateSet;
}

const char* const kDummyShader = R"(#version 330 compatibility
// Method "dummy" (tests/DummyMethod.cpp): value(x) * l_z.
#pragma include "common/btf_main.glsl"

uniform sampler2D dummyValue;

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    return texelFetch(dummyValue, texel, 0).rgb * light.z;
}
)";

const char* const kDummyEnvironmentShader = R"(#version 330 compatibility
// Environment lighting of method "dummy" (tests/DummyMethod.cpp): value(x) times the vertex's
// folded sum_i g_i l_i,z, slot 0 of its data.
#pragma include "common/environment.glsl"

uniform sampler2D dummyValue;

vec3 btfEnvironmentEvaluate(ivec2 texel, vec3 view) {
    return texelFetch(dummyValue, texel, 0).rgb * btfEnvData(0);
}
)";

namespace {

const DummyMaterial& dummy(const Material& material) {
    return static_cast<const DummyMaterial&>(material);
}

const bool registered = registerMethodClass<DummyMaterial>([] {
    MethodInfo m;
    m.description = "test-only lit texture defined in the test binary";
    m.options = {OptionSpec::number("gain", 1, 0, 4, "factor on the first measured value")};
    // Set directly (no registerFitterClass): a method outside the library has no libosgBTFFit
    // part whose loading would register it.
    m.fit = [](const BtfSource& btf, const FitOptions& o) -> osg::ref_ptr<Material> {
        return DummyMaterial::fit(btf, o);
    };
    m.shaderCost = [](const Material&) { return ShaderCost::ofEvaluate(1, 1, "ALU 11, TEX 1"); };
    m.fragmentShader = kDummyShader;
    // Folded environment lighting: the point-light value is linear in the light's weights, so
    // the environment projected onto the measured lights (g) folds into one RGB value per
    // vertex. Its shader has no MethodInfo field: it is added under the name environmentProgram
    // looks for, as a method outside the library's sources must (core/ShaderSource.h).
    EnvironmentHooks environment;
    environment.fold = [](const Material& material, const std::vector<glm::vec3>& g) {
        checkProjected(material, g);
        glm::vec3 sum(0.0f);
        for (std::size_t i = 0; i < g.size(); ++i) sum += g[i] * material.lights().vector(i).z;
        return std::vector<float>{sum.x, sum.y, sum.z};
    };
    environment.evaluateFolded = [](const Material& material, const std::vector<float>& folded,
                                    int x, int y, const glm::vec3&) {
        return dummy(material).texel(x, y) * glm::vec3(folded[0], folded[1], folded[2]);
    };
    environment.foldedStride = [](const Material&) { return std::size_t(3); };
    m.environment = environment;
    addShaderSource(std::string("environment/") + DummyMaterial::kMethod + ".frag",
                    kDummyEnvironmentShader);
    m.order = 1000;
    return m;
}());

}  // namespace

}  // namespace osgBTFTest
