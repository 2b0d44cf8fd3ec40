// Bilinear filtering with wrap-around for every method, both ways
// (Material::TexelFilter): the methods whose value is linear in their per-texel parameters filter
// those (lambert, pca, ptm, fmf), the others have btf_main.glsl blend four evaluations (laf, slaf,
// rf, lpca, lpca-revised, ptm's luminance variant). A magnified view (4 x 4 texels over 64 x 64
// pixels) and one straddling the texture's wrap edge (texture coordinates beyond 1) equal
// Material::evaluateFiltered at every pixel, within the tolerance of each method's own GPU == CPU
// test.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodRegistry.h"
#include "materials/fmf/Fmf.h"
#include "materials/lambert/Lambert.h"
#include "materials/pca/Pca.h"
#include "materials/ptm/Ptm.h"
#include "tests/RandomFactors.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

// Not square (catches swapped axes); powers of two, so that texel positions are exact floats.
constexpr int kWidth = 8, kHeight = 4;

MeasuredBtf sample() {
    SampleOptions options;
    options.width = kWidth;
    options.height = kHeight;
    return makeSampleBtf(options);
}

/** The largest value of the material's image for (view, light): materials/fmf/test/fmf_gl_test.cpp
 * compares relative to it. */
double largestValue(const Material& m, const glm::vec3& view, const glm::vec3& light) {
    double scale = 1;
    for (int y = 0; y < m.height(); ++y)
        for (int x = 0; x < m.width(); ++x) {
            const glm::vec3 value = m.evaluate(x, y, view, light);
            for (int c = 0; c < 3; ++c) scale = std::max(scale, double(std::abs(value[c])));
        }
    return scale;
}

float largest(const glm::vec3& v) {
    return std::max({std::abs(v.x), std::abs(v.y), std::abs(v.z)});
}

/** Renders the magnified views and the wrap edge; `tolerance` for a (view, light). */
void expectFilteredGpuEqualsCpu(const Material& m, const std::string& name,
                                const std::function<double(const glm::vec3&)>& tolerance,
                                Material::TexelFilter filter = Material::TexelFilter::Parameters) {
    ASSERT_EQ(m.texelFilter(), filter) << name;
    const glm::vec3 top(0, 0, 1);
    double worstMagnified = 0, worstWrap = 0;
    for (const Direction& l : {Direction{45, 20}, Direction{60, 126}, Direction{0, 0}}) {
        const glm::vec3 light = l.toVector();
        const double bound = tolerance(light);
        // The reference blends: half-way between texels 1 and 2 of a row, and across the wrap
        // between the last texel and the first, it is neither texel's value.
        const float v = 2.5f / kHeight;
        const glm::vec3 between = m.evaluateFiltered(2.0f / kWidth, v, 0.0f, top, light);
        const glm::vec3 across = m.evaluateFiltered(0.0f, v, 0.0f, top, light);
        EXPECT_GT(largest(between - m.evaluate(1, 2, top, light)), 2 * bound) << name;
        EXPECT_GT(largest(between - m.evaluate(2, 2, top, light)), 2 * bound) << name;
        EXPECT_GT(largest(across - m.evaluate(0, 2, top, light)), 2 * bound) << name;
        EXPECT_GT(largest(across - m.evaluate(kWidth - 1, 2, top, light)), 2 * bound) << name;
        // Texels 0-3 x 0-3 (the left and bottom half-texel bands blend with the last column and
        // row); at texture scale 2 (the patch shows [0, 2]^2), texels 3-6 x 1-3 and 0 (v passes
        // 1), and the corner where u and v pass 1.
        for (const auto& [centre, scale] :
             {std::pair{glm::vec2(2.0f / kWidth, 2.0f / kHeight), 1.0f},
              {glm::vec2(5.0f / kWidth, 3.0f / kHeight), 2.0f},
              {glm::vec2(1.0f, 1.0f), 2.0f}}) {
            const test::GpuCpuComparison r =
                test::compareGpuWithCpu(m, test::magnifiedPatchRender(m, centre, scale, light));
            EXPECT_EQ(r.pixelsCompared, 64 * 64) << name;
            EXPECT_LE(r.maxAbsDifference, bound)
                << name << " centre " << centre.x << ", " << centre.y << " scale " << scale
                << " light " << l.theta << "/" << l.phi << ": " << r.worst;
            double& worst = scale > 1.0f ? worstWrap : worstMagnified;
            worst = std::max(worst, r.maxAbsDifference);
        }
    }
    std::cout << name << " filtered GPU vs CPU: largest difference magnified " << worstMagnified
              << ", across the wrap " << worstWrap << "\n";
}

}  // namespace

TEST(BilinearFilterGpu, LambertMatchesCpu) {
    osg::ref_ptr<LambertMaterial> m = LambertMaterial::fit(sample(), {});
    // lambert's GPU case's tolerance (materials/lambert/test/lambert_gl_test.cpp).
    expectFilteredGpuEqualsCpu(*m, "lambert", [](const glm::vec3&) { return 1e-5; });
}

TEST(BilinearFilterGpu, PcaMatchesCpu) {
    // Four components, tiles of each view's layer: the blend must wrap within a tile.
    osg::ref_ptr<PcaMaterial> m = PcaMaterial::fit(sample(), FitOptions::parse("components=4"));
    expectFilteredGpuEqualsCpu(*m, "pca", [](const glm::vec3&) { return 1e-3; });
}

TEST(BilinearFilterGpu, PtmMatchesCpu) {
    for (const char* options : {"", "views=all storage=float"}) {
        osg::ref_ptr<PtmMaterial> m = PtmMaterial::fit(sample(), FitOptions::parse(options));
        const double bound = test::ptmGpuTolerance(*m);
        expectFilteredGpuEqualsCpu(*m, std::string("ptm [") + options + "]",
                                   [&](const glm::vec3&) { return bound; });
    }
}

TEST(BilinearFilterGpu, PtmLuminanceBlendsTexelValues) {
    // Colour times luminance: a product of two per-texel parameters, which filtering them would
    // not blend; btf_main.glsl blends the four texels' values instead.
    osg::ref_ptr<PtmMaterial> m = PtmMaterial::fit(sample(), FitOptions::parse("colour=luminance"));
    const double bound = test::ptmGpuTolerance(*m);
    expectFilteredGpuEqualsCpu(
        *m, "ptm [colour=luminance]", [&](const glm::vec3&) { return bound; },
        Material::TexelFilter::Values);
}

TEST(BilinearFilterGpu, MethodsNotLinearInTheirParametersBlendTexelValues) {
    // Lafortune exponents, cluster ids: btf_main.glsl evaluates the four texels and blends, the
    // methods' shaders unchanged. The tolerance of their own GPU == CPU tests (float data).
    for (const std::string& name : methodNamesInOrder()) {
        const MethodInfo& method = findMethod(name);
        if (method.filtersParameters) continue;
        const osg::ref_ptr<Material> m =
            method.fit(sample(), FitOptions::parse(method.quickFitOptions));
        // A method that blends its inputs (TexelFilter::Inputs) evaluates their blend once.
        expectFilteredGpuEqualsCpu(
            *m, name, [](const glm::vec3&) { return 1e-3; },
            method.blendsInputs ? Material::TexelFilter::Inputs : Material::TexelFilter::Values);
    }
}

TEST(BilinearFilterGpu, FmfMatchesCpuWithDecodingAfterTheBlend) {
    // Plain, with DRR (exp after the blend) and cosine, and DFMF's exp-YUV colour model.
    FactoredBtf drr = test::randomFactors(FactorModel::Fmf, {6, 6, 6}, kWidth, kHeight, 2);
    drr.dynamicRangeReduction = 1;
    drr.cosine = true;
    FactoredBtf yuv = test::randomFactors(FactorModel::Dfmf, {8, 3, 4}, kWidth, kHeight, 21);
    yuv.colorModel = 11;
    yuv.cosine = true;
    const std::vector<std::pair<std::string, osg::ref_ptr<FmfMaterial>>> materials = {
        {"fmf fitted", FmfMaterial::fit(sample(), FitOptions::parse("components=7"))},
        {"fmf drr cosine half", FmfMaterial::fromFactors(drr)},
        {"fmf drr cosine float", FmfMaterial::fromFactors(drr, MaterialTexture::Float)},
        {"dfmf exp-yuv", FmfMaterial::fromFactors(yuv)}};
    for (const auto& [name, m] : materials)
        // fmf_gl_test.cpp's tolerance: relative to the image's largest value.
        expectFilteredGpuEqualsCpu(*m, name, [&, &m = m](const glm::vec3& light) {
            return 1e-3 * largestValue(*m, glm::vec3(0, 0, 1), light);
        });
}

}  // namespace OSGBTF_TEST_FILE
