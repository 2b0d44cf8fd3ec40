// Method "rbf" on the GPU: the fragment shader (materials/rbf/rbf.frag) equals
// RbfMaterial::evaluate for a fitted material (Gaussian weights over the measured lights, at
// measured lights and between them) and for relight's two PCA types read from the fixtures (rbf and
// bilinear, mrgb; rbf, mycc).
#include <gtest/gtest.h>

#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodOptions.h"
#include "materials/rbf/Rbf.h"
#include "tests/TestUtil.h"
#include "tests/gl/MaterialGpuCheck.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

// GPU and CPU run the same float operations in the same order; exp and the GPU's fused
// multiply-adds round differently (llvmpipe: below 1e-6 here), and a weight at the threshold may
// be kept on one side only, which moves the value by about 0.001 of a profile (the profiles here
// are below 2): the bound is 2e-3.
const std::vector<std::pair<Direction, Direction>> kPairs = {
    {{0, 0}, {0, 0}},      {{30, 90}, {45, 20}},  {{52.5f, 171}, {75, 300}},
    {{10, 33}, {68, 300}}, {{44, 333}, {82, 45}}, {{0, 0}, {15, 30}}};

}  // namespace

// Fitted materials, the cases of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp): a front
// view only, as a capture has.
std::vector<test::GpuCase> cases() {
    SampleOptions sample = test::GpuCase::sampleOfSize(8, 6);  // not square: catches swapped axes
    sample.views = DirectionSet("front", {{0, 0}});
    std::vector<test::GpuCase> all;
    for (const char* options : {"planes=5", "planes=4 sigma=0.3 storage=float"})
        all.push_back({options, sample, test::vectorPairs(kPairs), test::fixedBound(2e-3)});
    return all;
}

const bool kCases = test::registerGpuCases(RbfMaterial::kMethod, cases());

TEST(RbfGpu, RelightRbfAndBilinearMatchCpu) {
    for (const char* folder : {"relight-rbf-mrgb", "relight-bilinear-mrgb", "relight-rbf-mycc"}) {
        const osg::ref_ptr<Material> m =
            loadMaterial(test::sourceDir() + "/tests/data/rti-files/" + folder + "/info.json");
        test::expectGpuEqualsCpuAtPairs(*m, 2e-3, kPairs, folder);
    }
}

}  // namespace OSGBTF_TEST_FILE
