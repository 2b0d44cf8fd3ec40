// Method "ptm": the fragment shader (materials/ptm/ptm.frag) equals PtmMaterial::evaluate for both
// colour variants and both view models, at measured (view, light) pairs and between them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "harness/sample/SampleBtf.h"
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
    const double bound = test::ptmGpuTolerance(*m);
    double worst = 0;
    for (const auto& [v, l] : pairs) {
        const test::GpuCpuComparison r = test::compareGpuWithCpu(*m, v.toVector(), l.toVector());
        worst = std::max(worst, r.maxAbsDifference);
        EXPECT_GT(r.pixelsCompared, 48) << "view " << v.theta << "/" << v.phi;
        EXPECT_LE(r.maxAbsDifference, bound)
            << options << ": view " << v.theta << "/" << v.phi << " light " << l.theta << "/"
            << l.phi << ": " << r.worst;
    }
    std::cout << "ptm [" << options << "] GPU vs CPU: largest difference " << worst << " (bound "
              << bound << ") over " << pairs.size() << " (view, light) pairs\n";
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
        const double bound = test::ptmGpuTolerance(*m);
        for (const auto& light : {glm::vec3(0, 0, 1), glm::vec3(0.48f, -0.6f, 0.64f)}) {
            const test::GpuCpuComparison r = test::compareGpuWithCpu(*m, {0, 0, 1}, light);
            EXPECT_GT(r.pixelsCompared, 40) << colour;
            EXPECT_LE(r.maxAbsDifference, bound) << colour << ": " << r.worst;
        }
    }
}

}  // namespace OSGBTF_TEST_FILE
