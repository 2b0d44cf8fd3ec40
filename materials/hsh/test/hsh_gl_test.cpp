// Method "hsh" on the GPU: the fragment shader (materials/hsh/hsh.frag) equals
// HshMaterial::evaluate for every order and both view models, at measured (view, light) pairs,
// between them and below the horizon (its cases of EveryMethod/MethodGpu,
// tests/gl/method_gpu_test.cpp), for materials read from .rti files; and each shape has its own
// program.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include "harness/sample/SampleBtf.h"

#include "materials/MethodOptions.h"
#include "materials/MethodPrograms.h"
#include "materials/hsh/Hsh.h"
#include "materials/hsh/RtiFile.h"
#include "tests/TestUtil.h"
#include "tests/gl/MaterialGpuCheck.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

test::Bound hshBound() {
    return test::materialBound([](const Material& m) {
        return test::hshGpuTolerance(static_cast<const HshMaterial&>(m));
    });
}

// The front model ignores the view: lights at the normal (phi undefined), on every ring, between
// them and at the horizon, at every order.
std::vector<test::GpuCase> frontCases() {
    const auto pairs = test::vectorPairs({{{0, 0}, {0, 0}},
                                          {{30, 90}, {45, 20}},
                                          {{52.5f, 171}, {75, 300}},
                                          {{10, 33}, {68, 300}},
                                          {{44, 333}, {89.5f, 45}}});
    std::vector<test::GpuCase> cases;
    for (const char* order : {"order=2", "order=3", "order=4"})
        cases.push_back({order, test::GpuCase::sampleOfSize(8, 6), pairs, hshBound()});
    return cases;
}

const bool kFrontCases = test::registerGpuCases(HshMaterial::kMethod, frontCases());
// The per-view model at measured pairs and between them, the last beyond the outer ring.
const bool kPerViewCases = test::registerGpuCases(
    HshMaterial::kMethod,
    {{"views=all order=4", test::GpuCase::sampleOfSize(8, 6),
      test::innerViewPairs(5, {{{31.7f, 77}, {52, 200}}, {{80, 10}, {20, 100}}}), hshBound()}});

// The order and the view model are compiled into the material's program
// (shaderDefines): the loops run to a constant, and no uniform branch that a software
// rasterizer runs both sides of (README.md, "Pass cost"). Each shape its own program,
// holding only its defines.
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
    const std::string nine = test::fragmentSourceOf(*order3),
                      four = test::fragmentSourceOf(*order2All);
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

// An .rti file renders from its own coefficients (no refit): GPU == CPU for the material
// read from a written file of every order.
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
