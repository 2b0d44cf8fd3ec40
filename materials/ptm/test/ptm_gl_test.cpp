// Method "ptm" on the GPU: the fragment shader (materials/ptm/ptm.frag) equals
// PtmMaterial::evaluate for both colour variants and both view models, at measured (view, light)
// pairs and between them (its cases of EveryMethod/MethodGpu, tests/gl/method_gpu_test.cpp), for
// materials read from .ptm files; and each shape has its own program.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include "harness/sample/SampleBtf.h"

#include "materials/MethodOptions.h"
#include "materials/MethodPrograms.h"
#include "materials/ptm/Ptm.h"
#include "materials/ptm/PtmFile.h"
#include "tests/TestUtil.h"
#include "tests/gl/MaterialGpuCheck.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

test::Bound ptmBound() {
    return test::materialBound([](const Material& m) {
        return test::ptmGpuTolerance(static_cast<const PtmMaterial&>(m));
    });
}

// The front rgb model ignores the view: a few views, lights on every ring and between them. The
// luminance per-view model at measured and unmeasured pairs; the per-view rgb branch, two pairs.
const bool kCases = test::registerGpuCases(
    PtmMaterial::kMethod,
    {{"", test::GpuCase::sampleOfSize(8, 6),
      test::vectorPairs({{{0, 0}, {0, 0}},
                         {{30, 90}, {45, 20}},
                         {{52.5f, 171}, {75, 300}},
                         {{10, 33}, {68, 300}},
                         {{44, 333}, {82, 45}}}),
      ptmBound()},
     {"colour=luminance views=all", test::GpuCase::sampleOfSize(8, 6),
      test::innerViewPairs(6, {{{31.7f, 77}, {52, 200}},
                               {{80, 10}, {20, 100}},  // beyond the outermost ring of views
                               {{66, 250}, {44, 135}}}),
      ptmBound()},
     {"views=all", test::GpuCase::sampleOfSize(8, 6),
      test::vectorPairs({{{31.7f, 77}, {52, 200}}, {{15, 60}, {45, 20}}}), ptmBound()}});

// The colour and view models are compiled into the material's program (shaderDefines), not
// uniform branches that a software rasterizer runs both sides of (README.md, "Pass cost"): each
// shape its own program, shared by materials of that shape, holding only its defines.
TEST(PtmGpu, EachShapeHasItsOwnProgramWithItsDefines) {
    SampleOptions sample;
    sample.width = sample.height = 4;
    const auto btf = makeSampleBtf(sample);
    const osg::ref_ptr<PtmMaterial> rgb = PtmMaterial::fit(btf, FitOptions::parse(""));
    const osg::ref_ptr<PtmMaterial> rgb2 = PtmMaterial::fit(btf, FitOptions::parse(""));
    const osg::ref_ptr<PtmMaterial> lumAll =
        PtmMaterial::fit(btf, FitOptions::parse("colour=luminance views=all"));
    EXPECT_EQ(rgb->shaderDefines(), std::vector<std::string>{"OSGBTF_PTM_FILTERED"});
    // Luminance blends texel values (not linear in its parameters): not filtered.
    EXPECT_EQ(lumAll->shaderDefines(),
              (std::vector<std::string>{"OSGBTF_PTM_LUMINANCE", "OSGBTF_PTM_PER_VIEW"}));
    EXPECT_EQ(methodProgram(*rgb).get(), methodProgram(*rgb2).get());
    EXPECT_NE(methodProgram(*rgb).get(), methodProgram(*lumAll).get());
    EXPECT_NE(methodProgram(*rgb).get(), methodProgram("ptm").get());
    EXPECT_NE(coordinateMapProgram(*rgb).get(), coordinateMapProgram(*lumAll).get());
    EXPECT_NE(shadowMapProgram(*rgb, false).get(), shadowMapProgram(*lumAll, false).get());
    const std::string plain = test::fragmentSourceOf(*rgb),
                      luminance = test::fragmentSourceOf(*lumAll);
    EXPECT_NE(plain.find("#define OSGBTF_PTM_FILTERED 1\n"), std::string::npos);
    EXPECT_EQ(plain.find("#define OSGBTF_PTM_LUMINANCE"), std::string::npos);
    EXPECT_EQ(plain.find("#define OSGBTF_PTM_PER_VIEW"), std::string::npos);
    EXPECT_NE(luminance.find("#define OSGBTF_PTM_LUMINANCE 1\n"), std::string::npos);
    EXPECT_NE(luminance.find("#define OSGBTF_PTM_PER_VIEW 1\n"), std::string::npos);
    EXPECT_EQ(luminance.find("#define OSGBTF_PTM_FILTERED"), std::string::npos);
    // No uniform selects the model any more.
    EXPECT_EQ(plain.find("ptmPerView"), std::string::npos);
    EXPECT_EQ(plain.find("ptmLuminance"), std::string::npos);
}

// A .ptm file renders from its own coefficients (no refit): GPU == CPU for the material read
// from a written RGB and LRGB file.
TEST(PtmGpu, MaterialsReadFromPtmFilesMatchCpu) {
    test::TempDir dir;
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;
    for (const char* colour : {"rgb", "luminance"}) {
        const osg::ref_ptr<PtmMaterial> fitted = PtmMaterial::fit(
            makeSampleBtf(sample), FitOptions::parse(std::string("colour=") + colour));
        writePtmFile(*fitted, dir.file("m.ptm"));
        const osg::ref_ptr<PtmMaterial> m = readPtmFile(dir.file("m.ptm"));
        test::expectGpuEqualsCpuAtPairs(*m, test::ptmGpuTolerance(*m),
                                        {{{0, 0}, {0, 0}}, {{0, 0}, {50, 310}}},
                                        std::string("ptm file [") + colour + "]");
    }
}

}  // namespace OSGBTF_TEST_FILE
