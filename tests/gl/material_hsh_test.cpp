// Method "hsh": the fragment shader (materials/hsh/hsh.frag) equals HshMaterial::evaluate for
// every order and both view models, at measured (view, light) pairs, between them and below the
// horizon.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
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

}  // namespace

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
