// Every registered method on the GPU: its fragment shader equals its CPU evaluator (through
// Material::evaluateFiltered) at the (view, light) pairs of the cases the method registers from its
// folder (materials/<m>/test/<m>_gl_test.cpp, tests/gl/MethodGpuCases.h). One test per method,
// named after it (EveryMethod/MethodGpu.MatchesCpuAtItsCases/<method>, '-' as '_'); a method
// that registers no case is skipped with a message saying so.
#include <gtest/gtest.h>

#include <algorithm>
#include <iostream>
#include <string>

#include "materials/MethodOptions.h"
#include "materials/MethodRegistry.h"
#include "tests/gl/MaterialGpuCheck.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

class MethodGpu : public ::testing::TestWithParam<std::string> {};

TEST_P(MethodGpu, MatchesCpuAtItsCases) {
    const std::string name = GetParam();
    const std::vector<test::GpuCase>& cases = test::gpuCases(name);
    if (cases.empty()) GTEST_SKIP() << name << " registers no GPU cases (test::registerGpuCases)";
    for (const test::GpuCase& c : cases) {
        const std::string label = name + " [" + c.options + "]";
        const osg::ref_ptr<Material> m =
            findMethod(name).fit(makeSampleBtf(c.sample), FitOptions::parse(c.options));
        ASSERT_TRUE(m) << label;
        double worst = 0, largestBound = 0;
        for (const auto& [view, light] : c.pairs) {
            const test::GpuCpuComparison r = test::compareGpuWithCpu(*m, view, light);
            const double bound = c.bound(*m, view, light);
            worst = std::max(worst, r.maxAbsDifference);
            largestBound = std::max(largestBound, bound);
            const Direction v = Direction::fromVector(view), l = Direction::fromVector(light);
            if (c.morePixelsThan >= 0) {
                EXPECT_GT(r.pixelsCompared, c.morePixelsThan)
                    << label << ": view " << v.theta << "/" << v.phi;
            }
            EXPECT_LE(r.maxAbsDifference, bound)
                << label << ": view " << v.theta << "/" << v.phi << " light " << l.theta << "/"
                << l.phi << ": " << r.worst;
        }
        std::cout << label << " GPU vs CPU: largest difference " << worst << " (bound "
                  << largestBound << ") over " << c.pairs.size() << " (view, light) pairs\n";
    }
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, MethodGpu, ::testing::ValuesIn(methodNames()),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                             std::string name = info.param;
                             std::replace(name.begin(), name.end(), '-', '_');
                             return name;
                         });

}  // namespace OSGBTF_TEST_FILE
