// Issue 49: GPU == CPU for every method fitted on the direction sets of real captures: one view
// (an RTI capture), two views, a few irregular views, one view under irregular lights, three views
// on one azimuth. The shader reads the same interpolation table as the CPU reference (a chain of
// segments where a set has no triangle), so each render is held to the method's usual GPU-CPU
// bound, at a measured view and at one between the measured views.
#include <cctype>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>

#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "tests/FewDirectionCases.h"
#include "tests/gl/GlTestEnv.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

class FewDirectionsGpu : public ::testing::TestWithParam<test::MethodAndDirections> {};

TEST_P(FewDirectionsGpu, GpuEqualsCpuAtAMeasuredViewAndBetweenViews) {
    const std::string method = std::get<0>(GetParam());
    const test::DirectionCase directions =
        test::directionCases()[std::size_t(std::get<1>(GetParam()))];
    SampleOptions sample;
    sample.width = sample.height = 4;
    sample.views = directions.views;
    sample.lights = directions.lights;
    const MethodInfo& info = findMethod(method);
    osg::ref_ptr<Material> material =
        info.fit(makeSampleBtf(sample), FitOptions::parse(info.quickFitOptions));
    const glm::vec3 light = glm::normalize(glm::vec3(0.3f, 0.2f, 0.9f));
    for (const glm::vec3& view : {directions.views.vector(directions.views.size() - 1),
                                  glm::normalize(glm::vec3(0.25f, 0.3f, 0.9f))}) {
        const test::GpuCpuComparison result = test::compareGpuWithCpu(*material, view, light);
        EXPECT_GT(result.pixelsCompared, 0);
        EXPECT_LE(result.maxAbsDifference, test::methodGpuBound(*material, view, light))
            << method << " on " << directions.name << ": " << result.worst;
    }
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, FewDirectionsGpu,
                         ::testing::Combine(::testing::ValuesIn(methodNames()),
                                            ::testing::Range(0,
                                                             int(test::directionCases().size()))),
                         test::methodAndDirectionsName);

}  // namespace OSGBTF_TEST_FILE
