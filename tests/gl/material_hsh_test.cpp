// Method "hsh": the fragment shader (materials/hsh/hsh.frag) equals HshMaterial::evaluate for
// every order and both view models, at measured (view, light) pairs, between them and below the
// horizon.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include <osg/Program>
#include "harness/sample/SampleBtf.h"

#include "materials/MethodOptions.h"
#include "materials/MethodPrograms.h"
#include "materials/hsh/Hsh.h"
#include "materials/hsh/RtiFile.h"
#include "tests/TestUtil.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

void expectGpuEqualsCpu(const std::string& options,
                        const std::vector<std::pair<Direction, Direction>>& pairs) {
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;  // not square: catches swapped axes
    const osg::ref_ptr<HshMaterial> m =
        HshMaterial::fit(makeSampleBtf(sample), FitOptions::parse(options));
    test::expectGpuEqualsCpuAtPairs(*m, test::hshGpuTolerance(*m), pairs, "hsh [" + options + "]");
}

/** The fragment source of the program in `material`'s own state set. */
std::string fragmentSourceOf(const Material& material) {
    const auto* program = dynamic_cast<const osg::Program*>(
        material.sharedStateSet()->getAttribute(osg::StateAttribute::PROGRAM));
    if (!program) return "";
    for (unsigned i = 0; i < program->getNumShaders(); ++i)
        if (program->getShader(i)->getType() == osg::Shader::FRAGMENT)
            return program->getShader(i)->getShaderSource();
    return "";
}

}  // namespace

// The order and the view model are compiled into the material's program (shaderDefines): the
// loops run to a constant, and no uniform branch that a software rasterizer runs both sides of
// (README.md, "Pass cost"). Each shape its own program, holding only its defines.
TEST(HshGpu, EachShapeHasItsOwnProgramWithItsDefines) {
    SampleOptions sample;
    sample.width = sample.height = 4;
    const auto btf = makeSampleBtf(sample);
    const osg::ref_ptr<HshMaterial> order3 = HshMaterial::fit(btf, FitOptions::parse(""));
    const osg::ref_ptr<HshMaterial> order2All =
        HshMaterial::fit(btf, FitOptions::parse("order=2 views=all"));
    EXPECT_EQ(order3->shaderDefines(),
              (std::vector<std::string>{"OSGBTF_HSH_TERMS 9", "OSGBTF_HSH_FILTERED"}));
    EXPECT_EQ(order2All->shaderDefines(),
              (std::vector<std::string>{"OSGBTF_HSH_TERMS 4", "OSGBTF_HSH_PER_VIEW",
                                        "OSGBTF_HSH_FILTERED"}));
    EXPECT_NE(methodProgram(*order3).get(), methodProgram(*order2All).get());
    const std::string nine = fragmentSourceOf(*order3), four = fragmentSourceOf(*order2All);
    // "NAME VALUE" defines NAME as VALUE (addShaderDefine), among the lines after #version.
    EXPECT_EQ(nine.rfind("#version 330 compatibility\n#define ", 0), 0u) << nine.substr(0, 200);
    const std::size_t terms = nine.find("\n#define OSGBTF_HSH_TERMS 9\n");
    EXPECT_LT(terms, nine.find("uniform sampler2DArray hshCoefficients")) << nine.substr(0, 200);
    EXPECT_EQ(nine.find("#define OSGBTF_HSH_PER_VIEW"), std::string::npos);
    EXPECT_NE(four.find("#define OSGBTF_HSH_TERMS 4\n"), std::string::npos);
    EXPECT_NE(four.find("#define OSGBTF_HSH_PER_VIEW 1\n"), std::string::npos);
    EXPECT_EQ(nine.find("hshTerms"), std::string::npos);
    EXPECT_EQ(nine.find("hshPerView"), std::string::npos);
}

TEST(HshGpu, FrontViewMatchesCpuAtEveryOrder) {
    // The front model ignores the view: lights at the normal (phi undefined), on every ring,
    // between them and at the horizon.
    const std::vector<std::pair<Direction, Direction>> pairs{{{0, 0}, {0, 0}},
                                                             {{30, 90}, {45, 20}},
                                                             {{52.5f, 171}, {75, 300}},
                                                             {{10, 33}, {68, 300}},
                                                             {{44, 333}, {89.5f, 45}}};
    for (const char* order : {"order=2", "order=3", "order=4"}) expectGpuEqualsCpu(order, pairs);
}

TEST(HshGpu, PerViewMatchesCpuAtMeasuredAndUnmeasuredDirections) {
    const DirectionSet bonn = DirectionSet::bonn81();
    std::vector<std::pair<Direction, Direction>> pairs;
    for (std::size_t i = 0; i < 5; ++i)
        pairs.push_back({bonn[(i * 9 + 1) % 57], bonn[(i * 23 + 5) % 81]});
    pairs.push_back({{31.7f, 77}, {52, 200}});
    pairs.push_back({{80, 10}, {20, 100}});  // beyond the outermost ring of views
    expectGpuEqualsCpu("views=all order=4", pairs);
}

// An .rti file renders from its own coefficients (no refit): GPU == CPU for the material read
// from a written file of every order.
TEST(HshGpu, MaterialsReadFromRtiFilesMatchCpu) {
    test::TempDir dir;
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;
    for (const char* order : {"order=2", "order=3", "order=4"}) {
        const osg::ref_ptr<HshMaterial> fitted =
            HshMaterial::fit(makeSampleBtf(sample), FitOptions::parse(order));
        writeRtiFile(*fitted, dir.file("m.rti"));
        const osg::ref_ptr<HshMaterial> m = readRtiFile(dir.file("m.rti"));
        test::expectGpuEqualsCpuAtPairs(*m, test::hshGpuTolerance(*m),
                                        {{{0, 0}, {0, 0}}, {{0, 0}, {50, 310}}},
                                        std::string("rti file [") + order + "]");
    }
}

}  // namespace OSGBTF_TEST_FILE
