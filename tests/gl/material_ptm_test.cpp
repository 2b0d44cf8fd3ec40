// Method "ptm": the fragment shader (materials/ptm/ptm.frag) equals PtmMaterial::evaluate for both
// colour variants and both view models, at measured (view, light) pairs and between them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/ptm/Ptm.h"
#include "materials/ptm/PtmFile.h"
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
    const osg::ref_ptr<PtmMaterial> m =
        PtmMaterial::fit(makeSampleBtf(sample), FitOptions::parse(options));
    test::expectGpuEqualsCpuAtPairs(*m, test::ptmGpuTolerance(*m), pairs, "ptm [" + options + "]");
}

}  // namespace

TEST(PtmGpu, RgbFrontViewMatchesCpu) {
    // The front model ignores the view: a few views, lights on every ring and between them.
    expectGpuEqualsCpu("", {{{0, 0}, {0, 0}},
                            {{30, 90}, {45, 20}},
                            {{52.5f, 171}, {75, 300}},
                            {{10, 33}, {68, 300}},
                            {{44, 333}, {82, 45}}});
}

TEST(PtmGpu, LuminancePerViewMatchesCpuAtMeasuredAndUnmeasuredDirections) {
    const DirectionSet bonn = DirectionSet::bonn81();
    std::vector<std::pair<Direction, Direction>> pairs;
    for (std::size_t i = 0; i < 6; ++i)
        pairs.push_back({bonn[(i * 9 + 1) % 57], bonn[(i * 23 + 5) % 81]});
    pairs.push_back({{31.7f, 77}, {52, 200}});
    pairs.push_back({{80, 10}, {20, 100}});  // beyond the outermost ring of views
    pairs.push_back({{66, 250}, {44, 135}});
    expectGpuEqualsCpu("colour=luminance views=all", pairs);
    // The per-view rgb branch, two pairs.
    expectGpuEqualsCpu("views=all", {{{31.7f, 77}, {52, 200}}, {{15, 60}, {45, 20}}});
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
