// Method "pca": the shader's 3 view x 3 light interpolation of Eigen-Textures equals the CPU
// reference at measured and unmeasured directions, for 8-bit and float Eigen-Textures.
#include <algorithm>
#include <iostream>

#include <gtest/gtest.h>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/pca/Pca.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

osg::ref_ptr<PcaMaterial> fitSample(const std::string& options) {
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;  // not square: catches swapped axes and tile offsets
    return PcaMaterial::fit(makeSampleBtf(sample), FitOptions::parse(options));
}

double worstDifference = 0;  // over the whole test binary, printed for the record

void expectGpuEqualsCpu(const PcaMaterial& m, const Direction& v, const Direction& l) {
    const test::GpuCpuComparison r = test::compareGpuWithCpu(m, v.toVector(), l.toVector());
    worstDifference = std::max(worstDifference, r.maxAbsDifference);
    EXPECT_GT(r.pixelsCompared, 48) << "view " << v.theta << "/" << v.phi;
    EXPECT_LE(r.maxAbsDifference, 1e-3) << "view " << v.theta << "/" << v.phi << " light "
                                        << l.theta << "/" << l.phi << ": " << r.worst;
}

}  // namespace

TEST(PcaGpu, MatchesCpuAtMeasuredAndUnmeasuredDirections) {
    osg::ref_ptr<PcaMaterial> m = fitSample("components=6");  // default unorm8 storage
    const DirectionSet& bonn = m->views();
    // 20 measured (view, light) pairs spread over every theta ring (view theta < 75 so the
    // orthographic patch covers enough pixels).
    for (int i = 0; i < 20; ++i) {
        const std::size_t v = std::size_t(i * 37) % 57, l = std::size_t(i * 23 + 5) % 81;
        expectGpuEqualsCpu(*m, bonn[v], bonn[l]);
    }
    // 5 unmeasured pairs: interpolation inside triangles and beyond the outermost ring.
    const std::vector<std::pair<Direction, Direction>> unmeasured = {{{31.7f, 77}, {52, 200}},
                                                                     {{8, 11}, {68, 301}},
                                                                     {{52, 160}, {82, 45}},
                                                                     {{20, 250}, {5, 190}},
                                                                     {{44, 333}, {37.5f, 95}}};
    for (const auto& [v, l] : unmeasured) expectGpuEqualsCpu(*m, v, l);
    std::cout << "pca GPU vs CPU: largest difference " << worstDifference << "\n";
}

TEST(PcaGpu, FloatStorageMatchesCpu) {
    // 16 components, float Eigen-Textures: exercises the float array texture path.
    osg::ref_ptr<PcaMaterial> m = fitSample("components=16 storage=float");
    expectGpuEqualsCpu(*m, {30, 90}, {45, 20});
    expectGpuEqualsCpu(*m, {31.7f, 77}, {52, 200});
}

}  // namespace OSGBTF_TEST_FILE
