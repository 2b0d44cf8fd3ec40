// Mip-mapped BTFs on the GPU: a plane on which 8 texels fall in a pixel,
// seen from a grazing measured view. Each pixel covers an aligned 8x8 block of the tiled sample,
// so the box-filtered reference is the mean of those 64 measured values, computed here from the
// sample itself. The render must equal the CPU lookup (Material::evaluateFiltered at lod 3) and
// lie within the method's own fit error of the reference; the base level alone aliases: its
// nearest texel is one of the 64, its bilinear blend (what a material without levels shows) four.
// Between two levels (a pixel covering 6 texels), the render blends both levels' bilinear
// lookups, as GL_LINEAR_MIPMAP_LINEAR: equal to the CPU reference there too.
#include <cmath>
#include <iostream>

#include <gtest/gtest.h>

#include "fit/MipMapping.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "tests/SmallSample.h"
#include "tests/gl/GlTestEnv.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

constexpr int kPixels = 32, kTexels = 32, kRepeats = 8;  // 32 * 8 / 32 = 8 texels per pixel
constexpr int kPerPixel = kTexels * kRepeats / kPixels;

const MeasuredBtf& sample() {
    static const MeasuredBtf btf = smallSampleBtf(kTexels);
    return btf;
}

/** The measured direction of largest theta among the views (the most grazing one). */
std::size_t grazingView(const DirectionSet& views) {
    std::size_t best = 0;
    for (std::size_t v = 1; v < views.size(); ++v)
        if (views.vector(v).z < views.vector(best).z) best = v;
    return best;
}

struct MinifiedRender {
    std::vector<glm::vec3> pixels;  // rows bottom-up
};

/** The unit square under orthoUnitSquare, texture repeated `repeats` times, shaded as seen from
 *  `view` (osgBTF_fixedView) and lit from `light`; `levels` overrides osgBTF_mipLevels, `blend`
 *  false reads the nearest texel (of each level) instead of blending four. */
MinifiedRender render(const Material& material, const glm::vec3& view, const glm::vec3& light,
                      int levels, bool blend = true, float repeats = float(kRepeats)) {
    RectifiedPatchRender r;
    r.view = view;
    r.light = light;
    r.textureScale = repeats;
    r.width = r.height = kPixels;
    r.mipLevels = levels;
    r.blendTexels = blend;
    const osg::ref_ptr<osg::Image> image = renderRectifiedPatch(material, r);
    MinifiedRender out;
    for (int j = 0; j < kPixels; ++j)
        for (int i = 0; i < kPixels; ++i)
            out.pixels.emplace_back(pixel(*image, i, j, 0), pixel(*image, i, j, 1),
                                    pixel(*image, i, j, 2));
    return out;
}

/** The mean of the measured values pixel (i, j) covers: base texels [8 (i mod 8), + 8) and the
 *  same for j (the pixel spans 1/32 of eight repeats of 32 texels). */
glm::dvec3 boxFiltered(int i, int j, std::size_t view, std::size_t light) {
    const int x0 = (i * kPerPixel) % kTexels, y0 = (j * kPerPixel) % kTexels;
    glm::dvec3 sum(0.0);
    for (int y = y0; y < y0 + kPerPixel; ++y)
        for (int x = x0; x < x0 + kPerPixel; ++x)
            for (int c = 0; c < 3; ++c)
                sum[c] += sample().value(view, light, std::size_t(y) * kTexels + x, c);
    return sum / double(kPerPixel * kPerPixel);
}

double rms(const std::vector<double>& squares) {
    double sum = 0;
    for (double s : squares) sum += s;
    return std::sqrt(sum / double(squares.size()));
}

struct MinificationErrors {
    double gpuVsCpu = 0;       ///< max |render - evaluateFiltered(lod 3)|
    double filtered = 0;       ///< RMS of the mip-mapped render against the box-filtered mean
    double ownFitError = 0;    ///< RMS of the material's level-3 texels against the same means
    double baseLevelOnly = 0;  ///< RMS of the base level's nearest texels against them
    double baseBilinear = 0;   ///< RMS of the base level's bilinear render against them
    double meanValue = 0;
};

MinificationErrors measure(const Material& material) {
    const std::size_t v = grazingView(sample().views());
    const std::size_t l = 4;  // a light away from the horizon
    const glm::vec3 view = sample().views().vector(v), light = sample().lights().vector(l);
    const MinifiedRender mip = render(material, view, light, material.mipLayout().levelCount());
    const MinifiedRender base = render(material, view, light, 1, false);
    const MinifiedRender bilinear = render(material, view, light, 1);
    MinificationErrors e;
    std::vector<double> filtered, own, baseOnly, baseBilinear;
    for (int j = 0; j < kPixels; ++j)
        for (int i = 0; i < kPixels; ++i) {
            const float u = (i + 0.5f) / kPixels * kRepeats, t = (j + 0.5f) / kPixels * kRepeats;
            const glm::vec3 cpu = material.evaluateFiltered(u, t, 3.0f, view, light);
            const glm::dvec3 reference = boxFiltered(i, j, v, l);
            const glm::vec3 gpu = mip.pixels[std::size_t(j) * kPixels + i];
            const glm::vec3 gpuBase = base.pixels[std::size_t(j) * kPixels + i];
            const glm::vec3 gpuBilinear = bilinear.pixels[std::size_t(j) * kPixels + i];
            for (int c = 0; c < 3; ++c) {
                e.gpuVsCpu = std::max(e.gpuVsCpu, double(std::abs(gpu[c] - cpu[c])));
                filtered.push_back(std::pow(gpu[c] - reference[c], 2));
                own.push_back(std::pow(cpu[c] - reference[c], 2));
                baseOnly.push_back(std::pow(gpuBase[c] - reference[c], 2));
                baseBilinear.push_back(std::pow(gpuBilinear[c] - reference[c], 2));
                e.meanValue += reference[c] / (3.0 * kPixels * kPixels);
            }
        }
    e.filtered = rms(filtered);
    e.ownFitError = rms(own);
    e.baseLevelOnly = rms(baseOnly);
    e.baseBilinear = rms(baseBilinear);
    return e;
}

std::string describe(const MinificationErrors& e) {
    return "GPU-CPU " + std::to_string(e.gpuVsCpu) + ", RMS to the box filter: mip-mapped " +
           std::to_string(e.filtered) + " (own fit error " + std::to_string(e.ownFitError) +
           "), base level only: nearest " + std::to_string(e.baseLevelOnly) + ", bilinear " +
           std::to_string(e.baseBilinear) + ", mean value " + std::to_string(e.meanValue);
}

}  // namespace

TEST(MipMapGpu, ExactPcaRendersTheBoxFilteredMeanWhereTheBaseLevelAliases) {
    // PCA with as many components as lights and float storage reproduces every texel of the
    // atlas exactly (each view's matrix has rank <= its 9 lights): the filtered render can only
    // differ from the mean by float rounding.
    const osg::ref_ptr<Material> pca =
        fitMipMapped(findMethod("pca"), sample(), FitOptions::parse("components=9 storage=float"));
    const MinificationErrors e = measure(*pca);
    std::cout << "pca (exact): " << describe(e) << "\n";
    SCOPED_TRACE(describe(e));
    EXPECT_LT(e.gpuVsCpu, 1e-3 * (1.0 + e.meanValue));
    EXPECT_LT(e.filtered, 1e-3 * e.meanValue);
    // A single texel of a woven sample is far from the mean of 64.
    EXPECT_GT(e.baseLevelOnly, 0.05 * e.meanValue);
    EXPECT_GT(e.baseLevelOnly, 50 * e.filtered);
}

TEST(MipMapGpu, EveryMethodRendersItsFitOfTheAveragedData) {
    for (const std::string& name : methodNamesInOrder()) {
        const MethodInfo& method = findMethod(name);
        const osg::ref_ptr<Material> material =
            fitMipMapped(method, sample(), FitOptions::parse(method.quickFitOptions));
        const MinificationErrors e = measure(*material);
        std::cout << name << ": " << describe(e) << "\n";
        SCOPED_TRACE(name + ": " + describe(e));
        // GPU == CPU within the tolerance of the methods' own GPU tests (8-bit and half storage).
        EXPECT_LT(e.gpuVsCpu, 1e-3 * (1.0 + e.meanValue) + 2e-3 * e.meanValue);
        // Within the method's own error on the level's data, and below the aliased render's (the
        // base level's nearest texels). Not always below the base level's bilinear render: lpca's
        // quick fit (2 clusters) of the averaged level has a larger error (0.037) than four base
        // texels blended (0.030); the figures are printed.
        EXPECT_LT(e.filtered, e.ownFitError + 1e-3 * (1.0 + e.meanValue));
        EXPECT_LT(e.filtered, e.baseLevelOnly);
    }
}

TEST(MipMapGpu, MinifiedBetweenLevelsEveryMethodBlendsBothLevelsBilinearly) {
    // 6 texels per pixel: lod log2(6) = 2.58, levels 2 (8 x 8 texels) and 3 (4 x 4), and pixel
    // centres between the texel centres of both ((i + 0.5) 6 / 32 of a repeat: 1.5 i + 0.25 of
    // level 2's texel centres, 0.75 i - 0.125 of level 3's), so every pixel blends eight texels.
    constexpr float kScale = 6.0f;
    const float lod = std::log2(kScale * kTexels / kPixels);
    const std::size_t v = grazingView(sample().views()), l = 4;
    const glm::vec3 view = sample().views().vector(v), light = sample().lights().vector(l);
    for (const std::string& name : methodNamesInOrder()) {
        const MethodInfo& method = findMethod(name);
        const osg::ref_ptr<Material> material =
            fitMipMapped(method, sample(), FitOptions::parse(method.quickFitOptions));
        const MinifiedRender gpu =
            render(*material, view, light, material->mipLayout().levelCount(), true, kScale);
        const MinifiedRender nearest =
            render(*material, view, light, material->mipLayout().levelCount(), false, kScale);
        double worst = 0, mean = 0, fromNearest = 0;
        for (int j = 0; j < kPixels; ++j)
            for (int i = 0; i < kPixels; ++i) {
                const float u = (i + 0.5f) / kPixels * kScale, t = (j + 0.5f) / kPixels * kScale;
                const glm::vec3 cpu = material->evaluateFiltered(u, t, lod, view, light);
                const std::size_t p = std::size_t(j) * kPixels + i;
                for (int c = 0; c < 3; ++c) {
                    worst = std::max(worst, double(std::abs(gpu.pixels[p][c] - cpu[c])));
                    fromNearest = std::max(
                        fromNearest, double(std::abs(gpu.pixels[p][c] - nearest.pixels[p][c])));
                    mean += cpu[c] / (3.0 * kPixels * kPixels);
                }
            }
        std::cout << name << " trilinear GPU-CPU " << worst << " (largest change from the nearest "
                  << "texels " << fromNearest << ", mean " << mean << ")\n";
        // The bound of EveryMethodRendersItsFitOfTheAveragedData.
        EXPECT_LT(worst, 1e-3 * (1.0 + mean) + 2e-3 * mean) << name;
        // The blend is not the nearest texels' (the test would not see a nearest lookup).
        EXPECT_GT(fromNearest, 10 * (1e-3 * (1.0 + mean) + 2e-3 * mean)) << name;
    }
}

}  // namespace OSGBTF_TEST_FILE
