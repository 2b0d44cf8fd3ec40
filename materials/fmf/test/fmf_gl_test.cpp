// Method "fmf": the shader's blend of 9 U rows, factor sums, colour / exp decode and cosine
// division equal the CPU reference (FmfMaterial::evaluate on the same stored values) at measured
// and unmeasured directions, for FMF plain and with DRR + cosine, and DFMF colour models 0, 3 and
// 11 with different per-channel ranks, in half and float storage, and for a fitted material (its
// case of EveryMethod/MethodGpu).
#include <algorithm>
#include <cmath>
#include <iostream>
#include <random>

#include <gtest/gtest.h>

#include "materials/fmf/Fmf.h"
#include "tests/RandomFactors.h"
#include "tests/gl/MaterialGpuCheck.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

constexpr int kWidth = 8, kHeight = 6;  // not square: catches swapped axes

/** The shared generator at this test's size, with a colour mean and matrix for model 3. */
FactoredBtf randomFactors(FactorModel model, std::array<int, 3> ranks, unsigned seed) {
    FactoredBtf f = test::randomFactors(model, ranks, kWidth, kHeight, seed);
    f.colorMean = {0.1f, 0.2f, 0.3f};
    f.colorMatrix = {0.5f, 0.2f, 0.1f, -0.3f, 0.6f, 0.2f, 0.1f, -0.2f, 0.7f};
    return f;
}

double worstRelative = 0;  // over the whole test binary, printed for the record

void expectGpuEqualsCpu(const FmfMaterial& m, const Direction& v, const Direction& l,
                        const std::string& name) {
    const glm::vec3 view = v.toVector(), light = l.toVector();
    // Relative to the largest value of this image (values near zero compare absolutely).
    double scale = 1;
    for (int y = 0; y < m.height(); ++y)
        for (int x = 0; x < m.width(); ++x) {
            const glm::vec3 value = m.evaluate(x, y, view, light);
            for (int c = 0; c < 3; ++c) scale = std::max(scale, double(std::abs(value[c])));
        }
    const test::GpuCpuComparison r = test::compareGpuWithCpu(m, view, light);
    worstRelative = std::max(worstRelative, r.maxAbsDifference / scale);
    EXPECT_GT(r.pixelsCompared, 48) << name << " view " << v.theta << "/" << v.phi;
    EXPECT_LE(r.maxAbsDifference, 1e-3 * scale)
        << name << " view " << v.theta << "/" << v.phi << " light " << l.theta << "/" << l.phi
        << ": " << r.worst;
}

void expectGpuEqualsCpuEverywhere(const FmfMaterial& m, const std::string& name) {
    const DirectionSet& bonn = m.views();
    // Measured pairs over several theta rings (view theta < 75 so the patch covers pixels).
    for (int i = 0; i < 6; ++i) {
        const std::size_t v = std::size_t(i * 37) % 57, l = std::size_t(i * 23 + 5) % 81;
        expectGpuEqualsCpu(m, bonn[v], bonn[l], name);
    }
    // Unmeasured: inside triangles and beyond the outermost ring.
    const std::vector<std::pair<Direction, Direction>> unmeasured = {
        {{31.7f, 77}, {52, 200}}, {{8, 11}, {68, 301}}, {{52, 160}, {82, 45}}};
    for (const auto& [v, l] : unmeasured) expectGpuEqualsCpu(m, v, l, name);
}

}  // namespace

TEST(FmfGpu, FmfPlainAndWithDrrAndCosineMatchCpu) {
    // 6 components: the second group of 4 is half padding.
    expectGpuEqualsCpuEverywhere(
        *FmfMaterial::fromFactors(randomFactors(FactorModel::Fmf, {6, 6, 6}, 1)), "fmf half");
    FactoredBtf drr = randomFactors(FactorModel::Fmf, {9, 9, 9}, 2);
    drr.dynamicRangeReduction = 1;
    drr.cosine = true;
    expectGpuEqualsCpuEverywhere(*FmfMaterial::fromFactors(drr, MaterialTexture::Float),
                                 "fmf drr cosine float");
    expectGpuEqualsCpuEverywhere(*FmfMaterial::fromFactors(drr), "fmf drr cosine half");
}

TEST(FmfGpu, DfmfColourModelsWithPerChannelRanksMatchCpu) {
    const std::vector<std::pair<int, std::array<int, 3>>> models = {
        {0, {3, 5, 2}}, {3, {2, 6, 3}}, {11, {8, 3, 4}}};
    for (const auto& [model, ranks] : models) {
        FactoredBtf f = randomFactors(FactorModel::Dfmf, ranks, unsigned(10 + model));
        f.colorModel = model;
        f.cosine = model == 11;
        expectGpuEqualsCpuEverywhere(*FmfMaterial::fromFactors(f),
                                     "dfmf model " + std::to_string(model));
    }
    std::cout << "fmf GPU vs CPU: largest relative difference " << worstRelative << "\n";
}

// A fitted material, the case of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp), with the
// bound relative to the image's largest value (test::methodGpuBound, as above).
const bool kCases = test::registerGpuCases(
    FmfMaterial::kMethod,
    {{"components=7", test::GpuCase::sampleOfSize(kWidth, kHeight),
      test::vectorPairs({{{30, 90}, {45, 20}}, {{31.7f, 77}, {52, 200}}}), test::methodGpuBound}});

}  // namespace OSGBTF_TEST_FILE
