// materials/ShaderInterface.h states the C++ side of the shared shader stages; the GLSL in
// shaders/common/ must declare the same names and the same light limit.
#include <filesystem>
#include <regex>

#include <gtest/gtest.h>

#include "materials/MethodPrograms.h"
#include "materials/ShaderInterface.h"
#include "scene/MaterialNode.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

std::string commonShader(const std::string& name) {
    return test::readTextFile(
        (std::filesystem::path(osgBTF::test::sourceDir()) / "shaders" / "common" / name).string());
}

bool declares(const std::string& source, const std::string& pattern) {
    return std::regex_search(source, std::regex(pattern));
}

}  // namespace

TEST(ShaderInterface, GlslDeclaresTheSameNamesAndLimits) {
    const std::string vert = commonShader("btf.vert"), frag = commonShader("btf_main.glsl");
    EXPECT_TRUE(declares(frag, std::string("const int ") + shader::kMaxLightsName + " = " +
                                   std::to_string(shader::kMaxLights) + ";"));
    EXPECT_TRUE(declares(vert, std::string("\\bin vec4 ") + shader::kTangentAttributeName + ";"));
    EXPECT_TRUE(declares(frag, std::string("uniform int ") + shader::kLightCount + "\\b"));
    EXPECT_TRUE(declares(frag, std::string("uniform vec4 ") + shader::kLightPosition + "\\[" +
                                   shader::kMaxLightsName + "\\];"));
    EXPECT_TRUE(declares(frag, std::string("uniform vec3 ") + shader::kLightColor + "\\[" +
                                   shader::kMaxLightsName + "\\];"));
    EXPECT_TRUE(declares(frag, std::string("uniform ivec2 ") + shader::kSize + ";"));
    EXPECT_TRUE(declares(frag, std::string("uniform vec4 ") + shader::kFixedView + "\\b"));
    EXPECT_TRUE(declares(vert, std::string("uniform float ") + shader::kTextureScale + "\\b"));
    EXPECT_TRUE(declares(frag, std::string("uniform bool ") + shader::kBilinear + "\\b"));
    EXPECT_TRUE(declares(frag, std::string("uniform bool ") + shader::kBlendTexels + "\\b"));
    // The smooth terminator (both stages) and the shadow-map variant.
    EXPECT_TRUE(declares(vert, std::string("const int ") + shader::kMaxLightsName + " = " +
                                   std::to_string(shader::kMaxLights) + ";"));
    for (const std::string* stage : {&vert, &frag})
        EXPECT_TRUE(declares(*stage, std::string("uniform bool ") + shader::kTerminator + "\\b"));
    EXPECT_TRUE(declares(vert, std::string("uniform float ") + shader::kTerminatorAlpha + "\\b"));
    EXPECT_TRUE(
        declares(frag, std::string("uniform sampler1D ") + shader::kTerminatorTexture + ";"));
    EXPECT_TRUE(declares(vert, std::string("#ifdef ") + shader::kShadowMapDefine + "\\b"));
    EXPECT_TRUE(declares(frag, std::string("#ifdef ") + shader::kShadowMapDefine + "\\b"));
    EXPECT_TRUE(declares(vert, std::string("uniform int ") + shader::kShadowTexGenUnit + "\\b"));
    EXPECT_TRUE(declares(frag, std::string("uniform sampler2DShadow ") + shader::kShadowMap + ";"));
    EXPECT_TRUE(declares(frag, std::string("uniform int ") + shader::kShadowLight + "\\b"));
    // The coordinate-map variant: the map and its number of mip levels.
    EXPECT_TRUE(declares(frag, std::string("#ifdef ") + shader::kCoordinateMapDefine + "\\b"));
    EXPECT_TRUE(declares(frag, std::string("uniform isampler2D ") + shader::kCoordinateMap + ";"));
    EXPECT_TRUE(declares(frag, std::string("uniform int ") + shader::kCoordinateMapLevels + "\\b"));
    // No other copy of the limit: MaterialNode uses the header's.
    EXPECT_EQ(kMaxLights, shader::kMaxLights);
}

TEST(ShaderInterface, DirectionLookupConstantsAgree) {
    const std::string glsl = commonShader("directions.glsl");
    EXPECT_TRUE(declares(glsl, std::string("const int ") + shader::kDirectionGridName + " = " +
                                   std::to_string(shader::kDirectionGrid) + ";"));
    EXPECT_TRUE(declares(glsl, std::string("const int ") + shader::kDirectionTableWidthName +
                                   " = " + std::to_string(shader::kDirectionTableWidth) + ";"));
    // The shader splits table addresses with a mask.
    EXPECT_EQ(shader::kDirectionTableWidth & (shader::kDirectionTableWidth - 1), 0);
}

TEST(ShaderInterface, ProgramsBindTheTangentAttribute) {
    osg::ref_ptr<osg::Program> program = methodProgram("lambert");
    const auto& bindings = program->getAttribBindingList();
    const auto it = bindings.find(shader::kTangentAttributeName);
    ASSERT_NE(it, bindings.end());
    EXPECT_EQ(it->second, shader::kTangentAttribute);
}

}  // namespace OSGBTF_TEST_FILE
