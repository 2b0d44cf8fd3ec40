// A method defined entirely in the test binary (tests/DummyMethod.{h,cpp}), registered like the
// built-in ones: it must show up in every place that lists methods (fit --help, compare, the
// serializers, the scene round trip, the shader program) without any other file naming it. This
// is the "one method = one folder" promise: nothing outside the method's own sources has to
// change. tests/gl/method_plugin_gl_test.cpp renders it: mip-mapped, through a coordinate map and
// under folded environment lighting.
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
#include "materials/MaterialFiles.h"
#include "materials/MaterialState.h"
#include "materials/MethodPrograms.h"
#include "materials/MethodRegistry.h"
#include "scene/MaterialNode.h"
#include "tests/DummyMethod.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;

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
    options.holdoutFraction = 0;  // held-out fits would need the tool
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

}  // namespace OSGBTF_TEST_FILE
