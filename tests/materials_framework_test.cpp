#include <filesystem>

#include <gtest/gtest.h>

#include "core/Error.h"
#include "core/ShaderSource.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/lambert/Lambert.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

TEST(FitOptions, ParsesKeyValuePairs) {
    // Values stay text: only validateOptions (MethodOptions.h) interprets them.
    const FitOptions o = FitOptions::parse("lobes=3, clusters=32 name=x");
    const std::map<std::string, std::string> expected = {
        {"lobes", "3"}, {"clusters", "32"}, {"name", "x"}};
    EXPECT_EQ(o.values(), expected);
    EXPECT_TRUE(o.has("name"));
    EXPECT_FALSE(o.has("missing"));
    EXPECT_EQ(test::errorOf([] { FitOptions::parse("lobes"); }),
              "option 'lobes': expected KEY=VALUE");
}

TEST(MethodRegistry, UnknownMethodListsTheKnownOnes) {
    try {
        findMethod("nope");
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("unknown method 'nope' (known: "), std::string::npos);
        EXPECT_NE(std::string(e.what()).find("lambert"), std::string::npos);
    }
}

TEST(MethodRegistry, MaterialFileOfUnknownMethodIsRefused) {
    test::TempDir dir;
    FittedMaterial file;
    file.method = "martian";
    file.views = file.lights = DirectionSet::bonn81();
    file.textures.push_back({"a", 1, 1, 1, 1, MaterialTexture::Float, {1.0f}});
    saveFittedMaterial(file, dir.file("m.exr"));
    try {
        loadMaterial(dir.file("m.exr"));
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find(dir.file("m.exr") + ": unknown method 'martian'"),
                  std::string::npos)
            << e.what();
    }
}

TEST(Shaders, EmbeddedAndIncludesResolved) {
    const std::string source = shaderSource("lambert.frag");
    EXPECT_NE(source.find("void main()"), std::string::npos);  // from common/btf_main.glsl
    EXPECT_EQ(source.find("#pragma include"), std::string::npos);
    EXPECT_EQ(shaderOrigin("lambert.frag"), "embedded:lambert.frag");
    EXPECT_THROW(shaderSource("nonexistent.frag"), Error);
}

TEST(Lambert, FitRecoversAnExactLambertianBtf) {
    MeasuredBtf btf(3, 2, DirectionSet::bonn81(), DirectionSet::bonn81());
    for (std::size_t v = 0; v < 81; ++v)
        for (std::size_t l = 0; l < 81; ++l)
            for (std::size_t t = 0; t < 6; ++t)
                for (int c = 0; c < 3; ++c)
                    btf.setValue(v, l, t, c,
                                 (0.1f + 0.1f * t + 0.05f * c) * btf.lights().vector(l).z);
    osg::ref_ptr<LambertMaterial> m = LambertMaterial::fit(btf, {});
    EXPECT_NEAR(m->albedo[5 * 3 + 2], 0.7f, 1e-3);  // half precision
    EXPECT_EQ(m->memory().valuesPerTexel, 3.0);
}

TEST(Lambert, SaveLoadRoundTripIsExact) {
    test::TempDir dir;
    SampleOptions options;
    options.width = options.height = 8;
    osg::ref_ptr<LambertMaterial> m = LambertMaterial::fit(makeSampleBtf(options), {});
    m->fitInfo["seconds"] = "0.5";
    saveMaterial(*m, dir.file("l.exr"));
    osg::ref_ptr<Material> back = loadMaterial(dir.file("l.exr"));
    ASSERT_EQ(back->methodName(), "lambert");
    EXPECT_EQ(static_cast<LambertMaterial&>(*back).albedo, m->albedo);
    EXPECT_EQ(back->fitInfo.at("seconds"), "0.5");
    EXPECT_TRUE(back->views() == m->views());
    const auto info = test::runCommand("oiiotool --info " + test::shellQuote(dir.file("l.exr")));
    EXPECT_EQ(info.exitCode, 0) << info.output;
}

TEST(FittedMaterialUNorm8, RefusesValuesThatAreNotEightBit) {
    test::TempDir dir;
    FittedMaterial file;
    file.method = "lambert";
    file.textures.push_back({"a", 2, 1, 1, 1, MaterialTexture::UNorm8, {0.5f, 1.0f}});
    try {
        saveFittedMaterial(file, dir.file("m.exr"));
        FAIL();
    } catch (const Error& e) {
        EXPECT_NE(std::string(e.what()).find("texture 'a' is stored as 8-bit but holds 0.5"),
                  std::string::npos)
            << e.what();
    }
    EXPECT_FALSE(std::filesystem::exists(dir.file("m.exr")));
}

TEST(FittedMaterialUNorm8, RoundTripIsExact) {
    test::TempDir dir;
    FittedMaterial file;
    file.method = "lambert";
    std::vector<float> values;
    for (int k = 0; k < 256; ++k) values.push_back(float(k) / 255.0f);
    file.textures.push_back({"a", 16, 16, 1, 1, MaterialTexture::UNorm8, values});
    saveFittedMaterial(file, dir.file("m.exr"));
    const FittedMaterial back = loadFittedMaterial(dir.file("m.exr"));
    EXPECT_EQ(back.texture("a").kind, MaterialTexture::UNorm8);
    EXPECT_EQ(back.texture("a").data, values);
}

}  // namespace OSGBTF_TEST_FILE
