// A method defined entirely here, in the test binary, registered like the built-in ones: it must
// show up in every place that lists methods (fit --help, compare, the serializers, the scene
// round trip, the shader program) without any other file naming it. This is the "one method =
// one folder" promise: nothing outside the method's own sources has to change.
#include <algorithm>
#include <filesystem>

#include <gtest/gtest.h>
#include <osgDB/ReadFile>
#include <osgDB/WriteFile>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/Compare.h"
#include "harness/FitRunner.h"
#include "harness/sample/SampleBtf.h"
#include "loaders/LoadBtf.h"
#include "materials/Material.h"
#include "materials/MaterialState.h"
#include "scene/MaterialNode.h"
#include "tests/TestUtil.h"

namespace fs = std::filesystem;

namespace osgBTFTest {

using namespace osgBTF;

/** rho(x) * gain * l_z: a lit texture with one option, enough to exercise everything. */
class DummyMaterial : public Material {
public:
    DummyMaterial() = default;
    DummyMaterial(const DummyMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : Material(other, copyop), value(other.value) {}
    META_Object(osgBTFTest, DummyMaterial)

        static osg::ref_ptr<DummyMaterial> fit(const BtfSource& btf, const FitOptions& options) {
        const OptionValues o = validateOptions("dummy", options);
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
    static osg::ref_ptr<DummyMaterial> fromFile(const FittedMaterial& file) {
        osg::ref_ptr<DummyMaterial> m = new DummyMaterial;
        m->readCommon(file);
        m->value = file.texture("value").data;
        return m;
    }

    std::string methodName() const override { return "dummy"; }
    glm::vec3 evaluate(int x, int y, const glm::vec3&, const glm::vec3& light) const override {
        const std::size_t t = (std::size_t(y) * std::size_t(_width) + std::size_t(x)) * 3;
        return glm::vec3(value[t], value[t + 1], value[t + 2]) * light.z;
    }
    MemoryFootprint memory() const override { return {3.0, 12.0, std::uint64_t(value.size()) * 4}; }
    FittedMaterial toFittedMaterial() const override {
        FittedMaterial file = writeCommon();
        file.textures.push_back({"value", _width, _height, 1, 3, MaterialTexture::Float, value});
        return file;
    }
    osg::ref_ptr<osg::StateSet> createStateSet() const override {
        osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
        addCommonState(*stateSet, *this);
        addTexture(
            *stateSet,
            createFloatTexture({"value", _width, _height, 1, 3, MaterialTexture::Float, value})
                .get(),
            "dummyValue", 0);
        return stateSet;
    }
    void assignFrom(const Material& other) override {
        value = assignCommon<DummyMaterial>(other).value;
    }

    std::vector<float> value;  ///< RGB per texel
};

const char* const kDummyShader = R"(#version 330 compatibility
// Method "dummy" (tests/method_plugin_test.cpp): value(x) * l_z.
#pragma include "common/btf_main.glsl"

uniform sampler2D dummyValue;

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    return texelFetch(dummyValue, texel, 0).rgb * light.z;
}
)";

const bool registered = registerMethod([] {
    MethodInfo m;
    m.name = "dummy";
    m.description = "test-only lit texture defined in the test binary";
    m.options = {OptionSpec::number("gain", 1, 0, 4, "factor on the first measured value")};
    m.fit = [](const BtfSource& btf, const FitOptions& o) -> osg::ref_ptr<Material> {
        return DummyMaterial::fit(btf, o);
    };
    m.load = [](const FittedMaterial& f) -> osg::ref_ptr<Material> {
        return DummyMaterial::fromFile(f);
    };
    m.createInstance = []() -> osg::Object* { return new DummyMaterial; };
    m.shaderCost = [](const Material&) { return ShaderCost::ofEvaluate(1, 1, "ALU 11, TEX 1"); };
    m.fragmentShader = kDummyShader;
    m.order = 1000;
    return m;
}());

}  // namespace osgBTFTest

using namespace osgBTF;
using namespace osgBTF::test;
using osgBTFTest::DummyMaterial;

namespace {

MeasuredBtf smallSample() {
    SampleOptions options;
    options.width = 4;
    options.height = 3;
    return makeSampleBtf(options);
}

std::size_t count(const std::string& text, const std::string& part) {
    std::size_t n = 0;
    for (auto at = text.find(part); at != std::string::npos; at = text.find(part, at + 1)) ++n;
    return n;
}

}  // namespace

TEST(MethodPlugin, IsListedWithItsOptionsInFitHelpAndCompareAll) {
    const std::string help = methodsHelp();
    EXPECT_NE(help.find("\n  dummy: test-only lit texture defined in the test binary"),
              std::string::npos)
        << help;
    EXPECT_NE(help.find("gain=  factor on the first measured value (number in 0..4, default 1)"),
              std::string::npos)
        << help;
    const std::vector<std::string> all = allCompareMethods();
    ASSERT_FALSE(all.empty());
    EXPECT_EQ(all.back(), "dummy");  // order 1000: after the paper's methods
    EXPECT_EQ(std::count(all.begin(), all.end(), "lambert"), 0);  // the baseline is added apart
}

TEST(MethodPlugin, OptionsAreValidatedByItsTable) {
    EXPECT_EQ(errorOf([] { findMethod("dummy").fit(smallSample(), FitOptions::parse("gain=5")); }),
              "dummy: option gain must be a number in 0..4, got 5");
    EXPECT_EQ(errorOf([] { findMethod("dummy").fit(smallSample(), FitOptions::parse("lobes=1")); }),
              "dummy: option lobes is unknown (known: gain)");
}

TEST(MethodPlugin, ProgramUsesTheShaderItRegistered) {
    osg::ref_ptr<osg::Program> program = methodProgram("dummy");
    ASSERT_EQ(program->getNumShaders(), 2u);
    const std::string fragment = program->getShader(1)->getShaderSource();
    EXPECT_NE(fragment.find("uniform sampler2D dummyValue;"), std::string::npos);
    // The include was resolved like a built-in shader's.
    EXPECT_NE(fragment.find("const int osgBTF_maxLights"), std::string::npos);
    EXPECT_EQ(fragment.find("#pragma include"), std::string::npos);
}

TEST(MethodPlugin, RoundTripsThroughTheSerializers) {
    osg::ref_ptr<Material> material =
        findMethod("dummy").fit(smallSample(), FitOptions::parse("gain=0.5"));
    for (const char* format : {"osgt", "osgb"}) {
        SCOPED_TRACE(format);
        TempDir dir;
        const std::string file = dir.file(std::string("dummy.") + format);
        ASSERT_TRUE(osgDB::writeObjectFile(*material, file));
        osg::ref_ptr<osg::Object> read = osgDB::readRefObjectFile(file);
        ASSERT_NE(read, nullptr);
        EXPECT_STREQ(read->libraryName(), "osgBTFTest");
        EXPECT_STREQ(read->className(), "DummyMaterial");
        auto* back = dynamic_cast<DummyMaterial*>(read.get());
        ASSERT_NE(back, nullptr);
        EXPECT_EQ(back->value, static_cast<const DummyMaterial&>(*material).value);
        EXPECT_EQ(back->width(), 4);
    }
}

TEST(MethodPlugin, EmbeddedInAMaterialNodeRoundTripsThroughTheScene) {
    osg::ref_ptr<Material> material = findMethod("dummy").fit(smallSample(), {});
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
    TempDir dir;
    const std::string scene = dir.file("scene.osgt");
    ASSERT_TRUE(osgDB::writeNodeFile(*node, scene));
    EXPECT_NE(readTextFile(scene).find("\"dummy\""), std::string::npos);
    osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(scene);
    auto* readNode = dynamic_cast<MaterialNode*>(read.get());
    ASSERT_NE(readNode, nullptr);
    ASSERT_NE(readNode->getMaterial(), nullptr);
    const auto* back = dynamic_cast<const DummyMaterial*>(readNode->getMaterial());
    ASSERT_NE(back, nullptr);
    EXPECT_EQ(back->value, static_cast<const DummyMaterial&>(*material).value);
}

// `btf compare` reuses a fit found in DIR when its record names the same input, method and
// options: with both fits written beforehand, compare runs in this process and never starts a
// child (the fit tool given does not exist, so a child would fail the method).
TEST(MethodPlugin, AppearsInTheComparisonTables) {
    TempDir dir;
    const std::string zip = dir.file("sample.zip");
    const CommandResult made = runCommand(
        builtTool("btf") + " --no-progress sample --size 8 --format png -o " + shellQuote(zip));
    ASSERT_EQ(made.exitCode, 0) << made.output;
    const MeasuredBtf btf = loadMeasuredBtf(zip);
    const fs::path out = dir.path() / "compare";
    fs::create_directories(out / "fits");
    for (const char* method : {"lambert", "dummy"}) {
        osg::ref_ptr<Material> material = findMethod(method).fit(btf, {});
        material->fitInfo["seconds"] = "0.5";
        FitJob job;
        job.input = zip;
        job.method = method;
        job.output = (out / "fits" / (std::string(method) + ".exr")).string();
        saveMaterial(*material, job.output);
        FitProcessResult done;
        done.ok = true;
        done.wallSeconds = 1;
        writeFitRecord(job, done, job.output + ".json");
    }

    CompareOptions options;
    options.input = zip;
    options.outputDir = out.string();
    options.methods = {"dummy"};
    options.fitTool = (dir.path() / "no-such-btf").string();
    options.gpu = false;
    const CompareResult result = runCompare(options);

    ASSERT_EQ(result.methods.size(), 2u);
    const MethodResult& dummy = result.methods[1];
    EXPECT_EQ(dummy.method, "dummy");
    ASSERT_FALSE(dummy.failed) << dummy.failure;
    EXPECT_TRUE(dummy.fit.reused);
    osg::ref_ptr<Material> fitted = findMethod("dummy").fit(btf, {});
    const ErrorSummary expected =
        computeError(btf, [&](std::size_t t, float* abrdf) { fitted->evaluateMeasured(t, abrdf); });
    EXPECT_DOUBLE_EQ(dummy.error.average, expected.average);
    EXPECT_EQ(dummy.memory.bytesPerTexel, 12.0);
    EXPECT_TRUE(dummy.cost.counted);
    // A method that does not declare MethodInfo::filtersParameters is filtered by btf_main.glsl's
    // blend of four texel values: its one-evaluation count (ALU 1 + light loop 10, TEX 1) four
    // times, plus 4 ALU per texel (ALU 10 + 4 x 5 = 30, TEX 4) and 45 to find the texels.
    EXPECT_EQ(dummy.cost.perLightTex, 4);
    EXPECT_EQ(dummy.cost.perLightAlu, 30);
    EXPECT_EQ(dummy.cost.fixedAlu, 25 + 45);

    const std::string report = readTextFile((out / "report.md").string());
    // One row in each of Table 1 (error), Table 2 (memory), Table 3 (pass cost) and fitting.
    EXPECT_EQ(count(report, "\n| dummy | "), 4u) << report;
    EXPECT_NE(
        report.find("| dummy | 70 + 30 | 0 + 4 | 100 | 4 | 4 texels x (ALU 11, TEX 1, less the "),
        std::string::npos)
        << report;
}
