// HDR environment lighting on the CPU (materials/EnvironmentLighting.h): hemisphere weights,
// the projection onto measured light directions against the brute-force integral, one bright
// texel as a point light, and PCA folding against the unfolded sum.
#include <cmath>
#include <iostream>
#include <random>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "core/Error.h"
#include "fit/MipMapping.h"
#include "harness/sample/SampleBtf.h"
#include "materials/EnvironmentLighting.h"
#include "materials/EnvironmentState.h"
#include "materials/IlluminationPca.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "materials/fmf/Fmf.h"
#include "materials/lpca/Lpca.h"
#include "materials/pca/Pca.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::errorOf;

namespace {

constexpr double kTwoPi = 6.283185307179586;

EnvironmentMap uniformMap(int width, int height, const glm::vec3& radiance) {
    EnvironmentMap map;
    map.width = width;
    map.height = height;
    map.rgb.resize(std::size_t(width) * height * 3);
    for (std::size_t i = 0; i < map.rgb.size(); ++i) map.rgb[i] = radiance[int(i % 3)];
    return map;
}

EnvironmentMap randomMap(int width, int height, unsigned seed) {
    EnvironmentMap map = uniformMap(width, height, glm::vec3(0.0f));
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> u(0.0f, 4.0f);
    for (float& v : map.rgb) v = u(rng);
    return map;
}

/** A random orthonormal frame (normal anywhere on the sphere). */
SurfaceFrame randomFrame(std::mt19937& rng) {
    std::normal_distribution<float> g(0.0f, 1.0f);
    SurfaceFrame f;
    f.normal = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
    const glm::vec3 any = glm::normalize(glm::vec3(g(rng), g(rng), g(rng)));
    f.tangent = glm::normalize(any - f.normal * glm::dot(any, f.normal));
    f.bitangent = glm::cross(f.normal, f.tangent);
    return f;
}

const PcaMaterial& smallPca() {
    static osg::ref_ptr<PcaMaterial> material = [] {
        SampleOptions options;
        options.width = options.height = 4;
        return PcaMaterial::fit(makeSampleBtf(options),
                                FitOptions::parse("components=6 storage=unorm8"));
    }();
    return *material;
}

double sumOfSolidAngles(const std::vector<EnvironmentSample>& samples) {
    double sum = 0;
    for (const EnvironmentSample& s : samples) sum += s.solidAngle;
    return sum;
}

/** |a - b| per channel against a tolerance relative to the magnitude of the sum's terms. */
void expectClose(const glm::vec3& a, const glm::vec3& b, double scale, double relative) {
    for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(a[ch], b[ch], scale * relative) << "channel " << ch;
}

}  // namespace

TEST(Environment, TexelSolidAnglesCoverTheSphere) {
    const EnvironmentMap map = uniformMap(64, 32, glm::vec3(1.0f));
    double sum = 0;
    for (int r = 0; r < map.height; ++r) sum += map.solidAngle(r) * map.width;
    EXPECT_NEAR(sum, 2 * kTwoPi, 1e-9);
}

TEST(Environment, HemisphereWeightsSumToTwoPi) {
    // Any orientation of the surface, maps coarse enough that most horizon texels are split.
    std::mt19937 rng(4);
    const DirectionInterpolator lights(DirectionSet::bonn81());
    const DirectionTable table = lights.table(32, 1024);
    for (int size : {16, 32, 64, 128, 256}) {
        const EnvironmentMap white = uniformMap(size, size / 2, glm::vec3(1.0f));
        for (int trial = 0; trial < 4; ++trial) {
            const SurfaceFrame frame = randomFrame(rng);
            const std::vector<EnvironmentSample> samples = visibleEnvironment(white, frame);
            EXPECT_NEAR(sumOfSolidAngles(samples), kTwoPi, 1e-3) << size << " trial " << trial;
            // Interpolation weights sum to 1 per sample: the g_i of a white environment (the
            // solid angle each measured direction stands for) sum to 2 pi as well.
            const std::vector<glm::vec3> g =
                projectEnvironment(samples, table, lights.directionCount());
            double sum = 0;
            for (const glm::vec3& v : g) sum += v.x;
            EXPECT_NEAR(sum, kTwoPi, 1e-3) << size << " trial " << trial;
            if (trial > 0 || size > 64) continue;
            // The shaders' grid table gives the exact weights up to float rounding.
            const std::vector<glm::vec3> exact = projectEnvironment(samples, lights);
            for (std::size_t i = 0; i < exact.size(); ++i)
                EXPECT_NEAR(g[i].x, exact[i].x, 1e-5 * kTwoPi) << i;
        }
    }
}

TEST(Environment, RotationTurnsTheMapAboutUp) {
    EnvironmentMap map = randomMap(32, 16, 7);
    const glm::vec3 before = map.radiance(glm::vec3(0.3f, 0.5f, 0.2f));
    map.rotationDegrees = 90.0f;
    // After a quarter turn counter-clockwise, what was at (x, y) is at (-y, x).
    EXPECT_EQ(map.radiance(glm::vec3(-0.5f, 0.3f, 0.2f)), before);
    // The texel's centre direction and the lookup agree.
    EXPECT_EQ(map.radiance(map.direction(5.5, 3.5)), map.texel(5, 3));
}

TEST(Environment, DownsamplingKeepsPower) {
    const EnvironmentMap map = randomMap(64, 32, 9);
    const EnvironmentMap small = map.downsampled(16);
    ASSERT_EQ(small.width, 16);
    ASSERT_EQ(small.height, 8);
    for (int ch = 0; ch < 3; ++ch) {
        double a = 0, b = 0;
        for (int r = 0; r < map.height; ++r)
            for (int c = 0; c < map.width; ++c) a += map.texel(c, r)[ch] * map.solidAngle(r);
        for (int r = 0; r < small.height; ++r)
            for (int c = 0; c < small.width; ++c) b += small.texel(c, r)[ch] * small.solidAngle(r);
        EXPECT_NEAR(a, b, 1e-5 * a);
    }
    EXPECT_EQ(errorOf([&] { map.downsampled(24); }),
              "environment: a 64 x 32 map cannot be averaged down to 24 x 12 (not a whole "
              "number of texels per texel)");
    EXPECT_EQ(errorOf([&] { map.downsampled(1); }),
              "environment: projection width must be at least 2");
}

TEST(Environment, WhiteEnvironmentIsTheSumOverMeasuredLights) {
    // a constant white environment without occlusion gives sum_i dOmega_i BTF(x, v, l_i)
    // (dOmega_i = g_i of the white map), and that equals the integral of the point-light
    // rendering over the hemisphere (pca is linear in the light weights). Both sides are sums
    // of ~10^3 float products of magnitude |term|: the tolerance is 1e-5 of the sum of |terms|.
    const PcaMaterial& pca = smallPca();
    const DirectionInterpolator lights(pca.lights());
    const EnvironmentMap white = uniformMap(64, 32, glm::vec3(1.0f));
    const SurfaceFrame frame;  // normal +Z
    const std::vector<EnvironmentSample> samples = visibleEnvironment(white, frame);
    const std::vector<glm::vec3> g = projectEnvironment(samples, lights);
    for (const glm::vec3& view : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(0.4f, -0.2f, 0.8f))})
        for (int x : {0, 3}) {
            glm::dvec3 expected(0.0), magnitude(0.0);
            for (std::size_t i = 0; i < g.size(); ++i) {
                const glm::vec3 btf = pca.evaluate(x, 1, view, pca.lights().vector(i));
                expected += glm::dvec3(g[i] * btf);
                magnitude += glm::dvec3(glm::abs(g[i] * btf));
            }
            const glm::vec3 reference = environmentReference(pca, x, 1, view, samples);
            expectClose(evaluateProjected(pca, x, 1, view, g), glm::vec3(expected), magnitude.x,
                        1e-5);
            expectClose(reference, glm::vec3(expected), magnitude.x, 1e-5);
            EXPECT_GT(expected.x, 0.0);
        }
}

TEST(Environment, OneBrightTexelIsAPointLight) {
    // A 108 x 54 map: rows of 3.33 degrees, row 40 (k = 13 from the top) has its centre at
    // theta 45; rotating by -1.67 degrees puts column 0's centre at phi 0: Bonn direction
    // (45, 0). The texel then lights exactly as a point light of intensity L Omega there.
    const PcaMaterial& pca = smallPca();
    const int index = pca.lights().find(45.0f, 0.0f);
    ASSERT_GE(index, 0);
    EnvironmentMap map = uniformMap(108, 54, glm::vec3(0.0f));
    map.rotationDegrees = -360.0f * 0.5f / 108.0f;
    const int row = 54 - 1 - 13;
    const glm::vec3 radiance(50.0f, 20.0f, 10.0f);
    float* p = map.rgb.data() + (std::size_t(row) * 108) * 3;
    p[0] = radiance.x, p[1] = radiance.y, p[2] = radiance.z;
    const std::vector<EnvironmentSample> samples = visibleEnvironment(map, SurfaceFrame{});
    const std::vector<glm::vec3> g =
        projectEnvironment(samples, DirectionInterpolator(pca.lights()));
    const float omega = float(map.solidAngle(row));
    // The texel centre equals the measured direction up to float rounding of sin/cos (~1e-7
    // rad), which moves the interpolation weights by that over the triangle size (~0.2 rad).
    for (std::size_t i = 0; i < g.size(); ++i) {
        const glm::vec3 expected = i == std::size_t(index) ? radiance * omega : glm::vec3(0.0f);
        expectClose(g[i], expected, radiance.x * omega, 1e-5);
    }
    const glm::vec3 view = glm::normalize(glm::vec3(-0.3f, 0.1f, 0.9f));
    for (int x : {0, 2})
        for (int y : {1, 3}) {
            const glm::vec3 pointLight =
                radiance * omega * pca.evaluate(x, y, view, pca.lights().vector(index));
            expectClose(evaluateProjected(pca, x, y, view, g), pointLight, glm::length(pointLight),
                        1e-4);
        }
}

TEST(Environment, FoldedPcaEqualsTheBruteForceSum) {
    const PcaMaterial& pca = smallPca();
    const DirectionInterpolator lights(pca.lights());
    std::mt19937 rng(11);
    for (int trial = 0; trial < 2; ++trial) {
        const SurfaceFrame frame = randomFrame(rng);
        const std::vector<EnvironmentSample> samples =
            visibleEnvironment(randomMap(32, 16, 20 + trial), frame);
        const std::vector<glm::vec3> g = projectEnvironment(samples, lights);
        const std::vector<float> folded = foldPca(pca, g);
        for (const glm::vec3& view :
             {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(0.5f, 0.5f, 0.5f)),
              glm::normalize(glm::vec3(-0.9f, 0.1f, 0.3f))}) {
            const glm::vec3 brute = evaluateProjected(pca, 2, 3, view, g);
            // Float sums of 81 x 7 products, regrouped: rounding ~1e-6 of the magnitude.
            double magnitude = 0;
            for (const glm::vec3& v : g) magnitude += v.x;
            expectClose(evaluateFoldedPca(pca, folded, 2, 3, view), brute,
                        std::max(double(glm::length(brute)), 1e-3 * magnitude), 1e-4);
        }
    }
    EXPECT_EQ(errorOf([&] { foldPca(pca, std::vector<glm::vec3>(3)); }),
              "environment: 3 projected values for 81 measured light directions");
}

TEST(Environment, FilteredFoldedBlendsTheFourTexelsAroundACoordinate) {
    // evaluateFoldedFiltered, the environment shader's CPU reference, on the 4 x 4 pca (texel
    // positions and weights exact in float): a texel centre shows that texel, half-way between
    // two texels their mean, u = 0 and u = 1 (left of the first centre, across the wrap) the
    // mean of the last and the first column, the corner (0, 0) the mean of the four corners.
    const PcaMaterial& pca = smallPca();
    ASSERT_EQ(pca.width(), 4);
    ASSERT_EQ(pca.height(), 4);
    const std::vector<glm::vec3> g =
        projectEnvironment(visibleEnvironment(randomMap(32, 16, 5), SurfaceFrame{}),
                           DirectionInterpolator(pca.lights()));
    const std::vector<float> folded = foldEnvironment(pca, g);
    const glm::vec3 view = glm::normalize(glm::vec3(0.2f, 0.3f, 0.9f));
    const auto texel = [&](int x, int y) { return evaluateFolded(pca, folded, x, y, view); };
    const auto filtered = [&](float u, float v) {
        return evaluateFoldedFiltered(pca, folded, u, v, 0.0f, view);
    };
    const double scale = glm::length(texel(1, 2));
    ASSERT_GT(scale, 1e-3);
    // The neighbours differ, so a blend shows.
    ASSERT_GT(glm::length(texel(1, 2) - texel(2, 2)), 1e-3 * scale);
    ASSERT_GT(glm::length(texel(3, 2) - texel(0, 2)), 1e-3 * scale);
    expectClose(filtered(1.5f / 4, 2.5f / 4), texel(1, 2), scale, 1e-6);
    expectClose(filtered(2.0f / 4, 2.5f / 4), 0.5f * (texel(1, 2) + texel(2, 2)), scale, 1e-6);
    for (float u : {0.0f, 1.0f, -1.0f})
        expectClose(filtered(u, 2.5f / 4), 0.5f * (texel(3, 2) + texel(0, 2)), scale, 1e-6);
    expectClose(filtered(0.0f, 0.0f),
                0.25f * (texel(3, 3) + texel(0, 3) + texel(3, 0) + texel(0, 0)), scale, 1e-6);
    // A quarter of the way from texel 1's centre to texel 2's.
    expectClose(filtered(1.75f / 4, 2.5f / 4), 0.75f * texel(1, 2) + 0.25f * texel(2, 2), scale,
                1e-6);
}

TEST(Environment, FilteredFoldedBlendsTwoMipLevelsByTheLevelOfDetail) {
    // A mip-mapped pca of an 8 x 8 base: level 1 (4 x 4 texels) at (8, 0) of the atlas, level 2
    // (2 x 2) at (8, 4), level 3 (1 x 1) at (8, 6). At lod 1.25 and (u, v) = (1.75, 3.25) / 4,
    // level 1 blends columns 1 and 2 (weights 3/4, 1/4) and rows 2 and 3 (1/4, 3/4), level 2
    // columns 0 and 1 (5/8, 3/8) and rows 1 and 0 (7/8, 1/8: across the wrap), the levels by
    // 3/4 and 1/4: all exact in float, written out here rather than through the shared helper.
    SampleOptions options;
    options.width = options.height = 8;
    const osg::ref_ptr<Material> pca =
        fitMipMapped(findMethod("pca"), makeSampleBtf(options), FitOptions::parse("components=5"));
    const MipLayout& mip = pca->mipLayout();
    ASSERT_EQ(mip.levelCount(), 4);
    const auto rectangle = [&](int l) {
        const MipLevel& r = mip.levels()[std::size_t(l)];
        return std::to_string(r.x) + " " + std::to_string(r.y) + " " + std::to_string(r.width) +
               " " + std::to_string(r.height);
    };
    ASSERT_EQ(rectangle(1), "8 0 4 4");
    ASSERT_EQ(rectangle(2), "8 4 2 2");
    ASSERT_EQ(rectangle(3), "8 6 1 1");
    const std::vector<float> folded = foldEnvironment(
        *pca, projectEnvironment(visibleEnvironment(randomMap(32, 16, 9), SurfaceFrame{}),
                                 DirectionInterpolator(pca->lights())));
    const glm::vec3 view = glm::normalize(glm::vec3(-0.3f, 0.2f, 0.9f));
    const auto texel = [&](int x, int y) { return evaluateFolded(*pca, folded, x, y, view); };
    const float u = 1.75f / 4, v = 3.25f / 4;
    const glm::vec3 level1 = 0.75f * 0.25f * texel(9, 2) + 0.25f * 0.25f * texel(10, 2) +
                             0.75f * 0.75f * texel(9, 3) + 0.25f * 0.75f * texel(10, 3);
    const glm::vec3 level2 = 0.625f * 0.875f * texel(8, 5) + 0.375f * 0.875f * texel(9, 5) +
                             0.625f * 0.125f * texel(8, 4) + 0.375f * 0.125f * texel(9, 4);
    const double scale = glm::length(level1);
    ASSERT_GT(scale, 1e-3);
    // The levels differ, so their blend shows.
    ASSERT_GT(glm::length(level1 - level2), 1e-3 * scale);
    expectClose(evaluateFoldedFiltered(*pca, folded, u, v, 1.25f, view),
                0.75f * level1 + 0.25f * level2, scale, 1e-6);
    // A whole lod reads that level alone; beyond the last level, the last (one texel).
    expectClose(evaluateFoldedFiltered(*pca, folded, u, v, 1.0f, view), level1, scale, 1e-6);
    expectClose(evaluateFoldedFiltered(*pca, folded, u, v, 2.0f, view), level2, scale, 1e-6);
    expectClose(evaluateFoldedFiltered(*pca, folded, u, v, 9.0f, view), texel(8, 6), scale, 1e-6);
    // Magnified (negative lod) or no derivative (NaN): the base level, whose texel (3, 6) has its
    // centre at (u, v).
    const glm::vec3 base = texel(3, 6);
    ASSERT_GT(glm::length(base - level1), 1e-3 * scale);
    for (float lod : {0.0f, -2.0f, std::nanf("")})
        expectClose(evaluateFoldedFiltered(*pca, folded, u, v, lod, view), base, scale, 1e-6);
}

TEST(Environment, FoldedFmfAndLpcaEqualTheProjectedSum) {
    // The exact CPU path (evaluateProjected: sum_i g_i BTF(x, v, l_i) through evaluate()) against
    // what the fmf and lpca environment shaders compute from their per-vertex data. fmf with the
    // cosine flag: evaluate() divides by cos(theta_i), which the fold puts into g_i.
    SampleOptions options;
    options.width = options.height = 4;
    const MeasuredBtf btf = makeSampleBtf(options);
    const osg::ref_ptr<FmfMaterial> fmf =
        FmfMaterial::fit(btf, FitOptions::parse("components=6 storage=float"));
    FactoredBtf withCosine = fmf->completeFactors();
    withCosine.cosine = true;
    const osg::ref_ptr<FmfMaterial> fmfCosine =
        FmfMaterial::fromFactors(withCosine, MaterialTexture::Float);
    const osg::ref_ptr<LpcaMaterial> lpca =
        LpcaMaterial::fit(btf, FitOptions::parse("clusters=2 components=3"));
    const std::vector<EnvironmentSample> samples =
        visibleEnvironment(randomMap(32, 16, 5), SurfaceFrame{});
    for (const Material* m :
         {static_cast<const Material*>(fmf.get()), static_cast<const Material*>(fmfCosine.get()),
          static_cast<const Material*>(lpca.get())}) {
        const std::vector<glm::vec3> g =
            projectEnvironment(samples, DirectionInterpolator(m->lights()));
        const std::vector<float> folded = foldEnvironment(*m, g);
        ASSERT_EQ(folded.size(), foldedStride(*m)) << m->methodName();
        for (const glm::vec3& view :
             {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(-0.4f, 0.5f, 0.6f))})
            for (int y : {0, 3}) {
                const glm::vec3 exact = evaluateProjected(*m, 1, y, view, g);
                // Float sums of 81 x (K or 3 c) products regrouped: ~1e-6 of the magnitude;
                // factor values of either sign can cancel, hence the margin of 100.
                EXPECT_GT(glm::length(exact), 1e-3f) << m->methodName();
                expectClose(evaluateFolded(*m, folded, 1, y, view), exact, glm::length(exact),
                            1e-4);
            }
    }
    FactoredBtf logValues = fmf->completeFactors();
    logValues.dynamicRangeReduction = 1;
    EXPECT_EQ(errorOf([&] {
                  foldEnvironment(*FmfMaterial::fromFactors(logValues, MaterialTexture::Float),
                                  std::vector<glm::vec3>(81));
              }),
              "environment: fmf with dynamic-range reduction (log values) is not linear in the "
              "light and has no folded environment lighting");
}

TEST(Environment, OccludedDirectionsContributeNothing) {
    // Everything below 30 degrees of elevation blocked: the weights sum to the cap's solid
    // angle 2 pi (1 - cos 60).
    const EnvironmentMap white = uniformMap(128, 64, glm::vec3(1.0f));
    const OcclusionTest lowBlocked = [](const glm::vec3&, const glm::vec3& d) {
        return d.z < 0.5f;
    };
    const std::vector<EnvironmentSample> samples =
        visibleEnvironment(white, SurfaceFrame{}, lowBlocked);
    // Rows are 2.8 degrees; the cut runs along row boundaries only to within a row.
    EXPECT_NEAR(sumOfSolidAngles(samples), kTwoPi * 0.5, kTwoPi * std::sin(3.14159 / 64));
}

namespace {

/** A smooth sky: a gradient around the azimuth and a bright sun lobe 30 degrees wide. */
EnvironmentMap smoothSky(int width) {
    EnvironmentMap map = uniformMap(width, width / 2, glm::vec3(0.0f));
    const glm::vec3 sun = glm::normalize(glm::vec3(0.6f, 0.2f, 0.5f));
    for (int r = 0; r < map.height; ++r)
        for (int c = 0; c < map.width; ++c) {
            const glm::vec3 d = map.direction(c + 0.5, r + 0.5);
            const float lobe = std::exp((glm::dot(d, sun) - 1.0f) / 0.14f);
            const glm::vec3 value(1.0f + 0.8f * d.x + 20.0f * lobe,
                                  1.0f + 0.5f * d.y + 15.0f * lobe,
                                  1.2f + 0.3f * d.z + 10.0f * lobe);
            float* p = map.rgb.data() + (std::size_t(r) * map.width + c) * 3;
            p[0] = value.x, p[1] = value.y, p[2] = value.z;
        }
    return map;
}

/** g of three tilted surface points for the sky turned by `degrees`, one vector. */
std::vector<float> projectedAt(const EnvironmentMap& sky, float degrees,
                               const DirectionInterpolator& lights) {
    static const DirectionTable table = lights.table(32, 1024);
    EnvironmentMap turned = sky;
    turned.rotationDegrees = degrees;
    std::vector<float> out;
    std::mt19937 rng(5);
    for (int v = 0; v < 3; ++v) {
        const SurfaceFrame frame = randomFrame(rng);
        for (const glm::vec3& g :
             projectEnvironment(visibleEnvironment(turned, frame), table, lights.directionCount()))
            out.insert(out.end(), {g.x, g.y, g.z});
    }
    return out;
}

double rms(const std::vector<float>& a, const std::vector<float>& b) {
    double sum = 0;
    for (std::size_t i = 0; i < a.size(); ++i) sum += double(a[i] - b[i]) * (a[i] - b[i]);
    return std::sqrt(sum / double(a.size()));
}

}  // namespace

TEST(IlluminationPca, ExactWithAllComponentsAndErrorFallsWithComponents) {
    const EnvironmentMap sky = smoothSky(32);
    const DirectionInterpolator lights(DirectionSet::bonn81());
    std::vector<std::vector<float>> direct;
    const int rotations = 12;
    for (int a = 0; a < rotations; ++a) direct.push_back(projectedAt(sky, 30.0f * a, lights));
    auto compute = [&](float degrees) { return direct[std::size_t(std::lround(degrees / 30.0f))]; };
    double scale = 0;
    for (float v : direct[0]) scale = std::max(scale, double(std::abs(v)));
    double previous = 1e30;
    for (int e = 1; e <= rotations; ++e) {
        const IlluminationPca pca = IlluminationPca::build(compute, rotations, e);
        double error = 0;
        for (int a = 0; a < rotations; ++a) error += rms(pca.reconstructSample(a), direct[a]);
        // Eckart-Young: the best rank-e fit's residual cannot grow with e (float rounding aside).
        EXPECT_LE(error, previous + 1e-6 * scale) << "e = " << e;
        previous = error;
        if (e == rotations - 1) {  // centred samples have rank A - 1 at most
            EXPECT_LE(error, 1e-5 * scale * rotations);
        }
    }
    EXPECT_EQ(errorOf([&] { IlluminationPca::build(compute, 1, 1); }),
              "illumination pca: at least 2 rotations needed");
}

TEST(IlluminationPca, InterpolatesBetweenSamples) {
    // The paper's defaults of Sattler et al. 2003 (30 rotations, 12 degrees apart, 5 components),
    // at rotations halfway between samples, against the direct computation there. reconstruct()
    // blends the two neighbouring samples' reconstructions R_a, R_b, so by the triangle inequality
    // its error is at most the mean of their truncation errors |R_a - D_a|, |R_b - D_b| plus the
    // error of blending the direct data themselves, |(D_a + D_b) / 2 - D|; the latter must beat
    // taking the nearest sample (the data are smooth in the rotation).
    const EnvironmentMap sky = smoothSky(16);
    const DirectionInterpolator lights(DirectionSet::bonn81());
    std::vector<std::vector<float>> direct;
    for (int a = 0; a < 30; ++a) direct.push_back(projectedAt(sky, 12.0f * a, lights));
    const IlluminationPca pca = IlluminationPca::build(
        [&](float degrees) { return direct[std::size_t(std::lround(degrees / 12.0f)) % 30]; });
    EXPECT_EQ(pca.rotations(), 30);
    EXPECT_EQ(pca.components(), 5);
    for (int a : {0, 7, 29}) {
        const float degrees = 12.0f * a + 6.0f;
        const std::size_t b = std::size_t(a + 1) % 30;
        const std::vector<float> truth = projectedAt(sky, degrees, lights);
        std::vector<float> blend(truth.size());
        for (std::size_t i = 0; i < blend.size(); ++i)
            blend[i] = 0.5f * (direct[std::size_t(a)][i] + direct[b][i]);
        const double error = rms(pca.reconstruct(degrees), truth);
        const double truncation = 0.5 * (rms(pca.reconstructSample(a), direct[std::size_t(a)]) +
                                         rms(pca.reconstructSample(int(b)), direct[b]));
        const double blending = rms(blend, truth);
        const double nearest = rms(direct[std::size_t(a)], truth);
        EXPECT_LE(error, truncation + blending + 1e-6);
        EXPECT_LT(blending, nearest);
        EXPECT_GT(error, 0.0);
        std::cout << "illumination pca at " << degrees << " deg: rms " << error << " (truncation "
                  << truncation << ", blending " << blending << ", nearest sample " << nearest
                  << ")\n";
    }
}

TEST(Environment, EveryMethodAgainstTheBruteForceIntegral) {
    // Which methods the projection onto measured lights renders exactly (their point-light
    // evaluation is linear in the light interpolation weights), and how far median-cut lights
    // (8 and 32) are from the integral for every method. Figures for the README; the sample is
    // 2 x 2 texels, quick fits, the smooth sky, surface facing +Z.
    SampleOptions options;
    options.width = options.height = 2;
    const MeasuredBtf btf = makeSampleBtf(options);
    const EnvironmentMap sky = smoothSky(32);
    const std::vector<EnvironmentSample> samples = visibleEnvironment(sky, SurfaceFrame{});
    const std::vector<RepresentativeLight> few = medianCutLights(sky, 8),
                                           more = medianCutLights(sky, 32);
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.9f));
    for (const std::string& name : methodNamesInOrder()) {
        const MethodInfo& method = findMethod(name);
        const osg::ref_ptr<Material> m = method.fit(btf, FitOptions::parse(method.quickFitOptions));
        const std::vector<glm::vec3> g =
            projectEnvironment(samples, DirectionInterpolator(m->lights()));
        const glm::vec3 brute = environmentReference(*m, 1, 0, view, samples);
        auto relative = [&](const glm::vec3& v) {
            return double(glm::length(v - brute) / glm::length(brute));
        };
        const double projected = relative(evaluateProjected(*m, 1, 0, view, g));
        const double cut8 = relative(evaluateRepresentative(*m, 1, 0, view, SurfaceFrame{}, few));
        const double cut32 = relative(evaluateRepresentative(*m, 1, 0, view, SurfaceFrame{}, more));
        std::cout << "environment " << name << ": projected " << projected << ", median cut 8 "
                  << cut8 << ", 32 " << cut32 << "\n";
        EXPECT_GT(glm::length(brute), 0.0f) << name;
        if (name == "pca" || name == "fmf" || name == "lpca") {
            EXPECT_LT(projected, 1e-4) << name;
        }
    }
}

TEST(Environment, MedianCutKeepsPowerAndPlacesLightsAtTheEnergy) {
    const EnvironmentMap sky = smoothSky(64);
    glm::dvec3 total(0.0);
    for (int r = 0; r < sky.height; ++r)
        for (int c = 0; c < sky.width; ++c)
            total += glm::dvec3(sky.texel(c, r)) * sky.solidAngle(r);
    for (int count : {1, 8, 16}) {
        const std::vector<RepresentativeLight> lights = medianCutLights(sky, count);
        ASSERT_EQ(int(lights.size()), count);
        glm::dvec3 sum(0.0);
        for (const RepresentativeLight& l : lights) {
            sum += glm::dvec3(l.power);
            EXPECT_NEAR(glm::length(l.direction), 1.0f, 1e-5f);
        }
        for (int ch = 0; ch < 3; ++ch) EXPECT_NEAR(sum[ch], total[ch], 1e-5 * total[ch]);
    }
    // One bright texel on a black map: the light of its region sits at its centre with its
    // power, whichever way the cuts fall.
    EnvironmentMap dark = uniformMap(64, 32, glm::vec3(0.0f));
    const glm::vec3 radiance(100.0f, 50.0f, 25.0f);
    for (int ch = 0; ch < 3; ++ch) dark.rgb[(std::size_t(20) * 64 + 9) * 3 + ch] = radiance[ch];
    bool found = false;
    for (const RepresentativeLight& l : medianCutLights(dark, 16)) {
        if (l.power.x == 0.0f) continue;
        found = true;
        EXPECT_NEAR(glm::dot(l.direction, dark.direction(9.5, 20.5)), 1.0f, 1e-6f);
        EXPECT_NEAR(l.power.x, radiance.x * dark.solidAngle(20), 1e-5 * radiance.x);
    }
    EXPECT_TRUE(found);
    EXPECT_EQ(errorOf([&] { medianCutLights(sky, 12); }),
              "environment: representative light count 12 is not a power of two between 1 and "
              "1024");
}

}  // namespace OSGBTF_TEST_FILE
