// Method "rf" (materials/rf): options, parameter recovery, the built-in sample, save/load, memory.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/lambert/Lambert.h"
#include "materials/rf/Rf.h"
#include "tests/TestUtil.h"

using namespace osgBTF;

using osgBTF::test::errorOf;

namespace {

MeasuredBtf sample(int width, int height) {
    SampleOptions options;
    options.width = width;
    options.height = height;
    return makeSampleBtf(options);
}

/** The model's values at every measured (view, light) pair as a MeasuredBtf, plus noise. */
MeasuredBtf render(const RfMaterial& m, float noise, unsigned seed) {
    MeasuredBtf btf(m.width(), m.height(), m.views(), m.lights());
    std::mt19937 rng(seed);
    std::normal_distribution<float> gauss(0.0f, noise);
    const std::size_t n = m.views().size() * m.lights().size();
    std::vector<float> abrdf(n * 3);
    for (std::size_t t = 0; t < m.texelCount(); ++t) {
        m.evaluateMeasured(t, abrdf.data());
        for (std::size_t i = 0; i < n; ++i)
            for (int c = 0; c < 3; ++c)
                btf.setValue(i / m.lights().size(), i % m.lights().size(), t, c,
                             abrdf[i * 3 + c] + (noise > 0 ? gauss(rng) : 0.0f));
    }
    return btf;
}

/** A model with known, plausible parameters: a broad lobe near the normal and a glossy one near
 *  the mirror direction of each view, values within [0, 1]. */
osg::ref_ptr<RfMaterial> groundTruth(int width, int height) {
    const DirectionSet bonn = DirectionSet::bonn81();
    osg::ref_ptr<RfMaterial> m = RfMaterial::create(width, height, bonn, bonn, 2);
    const std::size_t texels = m->texelCount();
    for (std::size_t t = 0; t < texels; ++t) {
        for (int c = 0; c < 3; ++c) m->rhoD[t * 3 + c] = 0.02f + 0.01f * float((t + c) % 4);
        for (std::size_t v = 0; v < bonn.size(); ++v) {
            for (int c = 0; c < 3; ++c)
                m->rhoV[(v * texels + t) * 3 + c] = 0.35f + 0.1f * float((t + 2 * c + v) % 4);
            const glm::vec3 view = bonn.vector(v);
            const float n1 = 1.0f + 0.5f * float((t + v) % 3), n2 = 6.0f + 3.0f * float(t % 4);
            const glm::vec3 d1 = glm::normalize(
                glm::vec3(0.15f * std::sin(float(t + v)), 0.15f * std::cos(float(3 * t + v)), 1));
            const glm::vec3 d2 = glm::normalize(glm::vec3(-view.x, -view.y, view.z + 0.3f));
            const glm::vec3 a1 = std::pow(0.6f, 1.0f / n1) * d1,
                            a2 = std::pow(0.5f, 1.0f / n2) * d2;
            float* p = &m->lobes[((v * 2) * texels + t) * 4];
            float* q = &m->lobes[((v * 2 + 1) * texels + t) * 4];
            p[0] = a1.x, p[1] = a1.y, p[2] = a1.z, p[3] = n1;
            q[0] = a2.x, q[1] = a2.y, q[2] = a2.z, q[3] = n2;
        }
    }
    m->roundToStorage();
    return m;
}

bool allFinite(const std::vector<float>& v) {
    return std::all_of(v.begin(), v.end(), [](float x) { return std::isfinite(x); });
}

}  // namespace

TEST(RfOptions, InvalidOptionsAreRefusedWithExactMessages) {
    const MeasuredBtf btf = sample(2, 2);
    const auto fitWith = [&](const std::string& options) {
        return errorOf([&] { RfMaterial::fit(btf, FitOptions::parse(options)); });
    };
    EXPECT_EQ(fitWith("lobes=0"), "rf: option lobes must be an integer in 1..8, got 0");
    EXPECT_EQ(fitWith("lobes=9"), "rf: option lobes must be an integer in 1..8, got 9");
    EXPECT_EQ(fitWith("lobes=two"), "rf: option lobes must be an integer in 1..8, got two");
    EXPECT_EQ(fitWith("iterations=0"), "rf: option iterations must be an integer >= 1, got 0");
    EXPECT_EQ(fitWith("starts=4"), "rf: option starts must be an integer in 1..3, got 4");
    EXPECT_EQ(fitWith("max-exponent=0.5"),
              "rf: option max-exponent must be a number in 1..256, got 0.5");
    EXPECT_EQ(fitWith("max-exponent=nan"),
              "rf: option max-exponent must be a number in 1..256, got nan");
    EXPECT_EQ(fitWith("lobe=2"),
              "rf: option lobe is unknown (known: lobes, iterations, starts, max-exponent)");
    // The registry's entry point validates the same way.
    EXPECT_EQ(errorOf([&] { findMethod("rf").fit(btf, FitOptions::parse("lobes=0")); }),
              "rf: option lobes must be an integer in 1..8, got 0");
}

TEST(RfOptions, DataTheModelCannotHoldIsRefused) {
    EXPECT_EQ(errorOf([] { RfMaterial::fit(MeasuredBtf(), {}); }), "rf: the measured BTF is empty");
    const DirectionSet two("two", {{0, 0}, {30, 0}});
    EXPECT_EQ(errorOf([&] { RfMaterial::create(2, 2, two, DirectionSet::bonn81(), 2); }),
              "rf: needs at least 3 measured views to interpolate");
    EXPECT_EQ(errorOf([] {
                  RfMaterial::create(2, 2, DirectionSet::ubo2014(), DirectionSet::bonn81(), 14);
              }),
              "rf: lobes must be between 1 and 8, got 14");
}

TEST(RfRegistry, RegisteredWithOptionDocs) {
    const MethodInfo& info = findMethod("rf");
    EXPECT_NE(info.description.find("reflectance fields"), std::string::npos);
    ASSERT_FALSE(info.options.empty());
    EXPECT_EQ(info.options[0].name, "lobes");
    EXPECT_EQ(info.options[0].defaultValue, "2");
}

// Seed 001 Table 2 at its standard configuration: Bonn 81 directions, 2 lobes, 256 x 256 texels.
// The numbers come from the sizes of the model's arrays and their declared storage kinds.
TEST(RfMemory, MatchesSeed001Table2) {
    const DirectionSet bonn = DirectionSet::bonn81();
    osg::ref_ptr<RfMaterial> m = RfMaterial::create(256, 256, bonn, bonn, 2);
    const MemoryFootprint f = m->memory();
    EXPECT_DOUBLE_EQ(f.valuesPerTexel, 894.0);
    EXPECT_DOUBLE_EQ(f.bytesPerTexel, 1785.0);
    EXPECT_EQ(f.totalBytes, std::uint64_t(1785) * 256 * 256);
    // And it follows the model's shape, not a table: 1 lobe = 3 + 81 x (3 + 4) values.
    const MemoryFootprint one = RfMaterial::create(4, 4, bonn, bonn, 1)->memory();
    EXPECT_DOUBLE_EQ(one.valuesPerTexel, 3.0 + 81 * 7);
    EXPECT_DOUBLE_EQ(one.bytesPerTexel, 3.0 + 2 * 81 * 7);
}

// Data generated from the model (known parameters, rounded to storage) plus Gaussian noise of
// sigma 0.005 per channel: the fit must come back to the noise floor. The expected per-texel
// error of pure noise is E|N(0, sigma^2 I_3)| = 1.60 sigma = 0.008.
TEST(RfFit, RecoversAModelFromNoisyData) {
    osg::ref_ptr<RfMaterial> truth = groundTruth(4, 3);
    const MeasuredBtf clean = render(*truth, 0.0f, 1);
    const MeasuredBtf noisy = render(*truth, 0.005f, 2);
    osg::ref_ptr<RfMaterial> m = RfMaterial::fit(noisy, {});
    const ErrorSummary toNoisy =
        computeError(noisy, [&](std::size_t t, float* out) { m->evaluateMeasured(t, out); });
    const ErrorSummary toTruth =
        computeError(clean, [&](std::size_t t, float* out) { m->evaluateMeasured(t, out); });
    std::cout << "rf recovery: error to noisy data avg " << toNoisy.average << " max "
              << toNoisy.maximum << ", to the true model avg " << toTruth.average << " max "
              << toTruth.maximum << ", fit " << m->fitInfo["seconds"] << " s, "
              << m->fitInfo["iterations"] << " LM iterations per view\n";
    EXPECT_LT(toNoisy.average, 0.0095);
    EXPECT_LT(toTruth.average, 0.004);
    EXPECT_LT(toTruth.maximum, 0.006);
    // The parameters themselves: rho_d within a few 8-bit steps (the lobes may trade a little
    // of a constant with it), and the model between the measured lights and views.
    for (std::size_t i = 0; i < truth->rhoD.size(); ++i)
        EXPECT_NEAR(m->rhoD[i], truth->rhoD[i], 0.02) << i;
    double worst = 0, sum = 0;
    int count = 0;
    for (int y = 0; y < truth->height(); ++y)
        for (int x = 0; x < truth->width(); ++x)
            for (float vt = 5; vt < 75; vt += 17)
                for (float lt = 8; lt < 75; lt += 13)
                    for (float phi = 10; phi < 360; phi += 47) {
                        const glm::vec3 v = Direction{vt, phi}.toVector();
                        const glm::vec3 l = Direction{lt, 360 - phi * 0.7f}.toVector();
                        const float d =
                            glm::length(m->evaluate(x, y, v, l) - truth->evaluate(x, y, v, l));
                        worst = std::max(worst, double(d));
                        sum += d;
                        ++count;
                    }
    EXPECT_LT(sum / count, 0.01);
    EXPECT_LT(worst, 0.08);
}

// The built-in sample (woven cloth with parallax and self-shadowing): error reported and bounded,
// no NaN, no divergent texel, nothing blowing up between the measured directions.
TEST(RfFit, BuiltInSampleIsFittedWithoutDivergence) {
    const MeasuredBtf btf = sample(8, 8);
    osg::ref_ptr<RfMaterial> m = RfMaterial::fit(btf, {});
    ASSERT_TRUE(allFinite(m->rhoD) && allFinite(m->rhoV) && allFinite(m->lobes));
    for (std::size_t i = 3; i < m->lobes.size(); i += 4) {
        ASSERT_GE(m->lobes[i], RfMaterial::kMinExponent);
        ASSERT_LE(m->lobes[i], 64.0f);
    }
    const ErrorSummary rf =
        computeError(btf, [&](std::size_t t, float* out) { m->evaluateMeasured(t, out); });
    osg::ref_ptr<LambertMaterial> lambert = LambertMaterial::fit(btf, {});
    const ErrorSummary lit =
        computeError(btf, [&](std::size_t t, float* out) { lambert->evaluateMeasured(t, out); });
    std::cout << "rf on the 8x8 sample: error avg " << rf.average << " min " << rf.minimum
              << " max " << rf.maximum << " (lambert avg " << lit.average << "), fit "
              << m->fitInfo["seconds"] << " s, fallbacks " << m->fitInfo["fallbacks"] << "\n";
    RecordProperty("rf_error_avg", std::to_string(rf.average));
    EXPECT_EQ(rf.nonFiniteValues, 0u);
    // Per-view lobes contain the lit texture's rho * l_z (one lobe along +Z with n = 1) and
    // add what it cannot model (shadowing, gloss, parallax): below the Lambert baseline.
    EXPECT_LT(rf.average, lit.average);
    // No divergent texel: every texel beats its own mean colour, the trivial model whose error
    // is the spread of the texel's data.
    const std::size_t n = btf.viewCount() * btf.lightCount();
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        const std::vector<float> a = btf.abrdf(t);
        glm::dvec3 mean(0);
        for (std::size_t i = 0; i < n; ++i)
            mean += glm::dvec3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]);
        mean /= double(n);
        double spread = 0;
        for (std::size_t i = 0; i < n; ++i)
            spread += glm::length(glm::dvec3(a[i * 3], a[i * 3 + 1], a[i * 3 + 2]) - mean);
        spread /= double(n);
        EXPECT_LT(rf.perTexel[t], 0.5 * spread) << "texel " << t;
    }
    // Between the measured directions the model stays within the data's range (with margin).
    float dataMax = 0;
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        for (float v : btf.abrdf(t)) dataMax = std::max(dataMax, v);
    float modelMax = 0, modelMin = 1;
    for (int y = 0; y < btf.height(); ++y)
        for (int x = 0; x < btf.width(); ++x)
            for (float vt = 0; vt <= 85; vt += 8.5f)
                for (float lt = 0; lt <= 85; lt += 8.5f)
                    for (float phi = 0; phi < 360; phi += 33) {
                        const glm::vec3 value = m->evaluate(
                            x, y, Direction{vt, phi}.toVector(),
                            Direction{lt, std::fmod(phi * 2.3f + 40, 360.0f)}.toVector());
                        modelMax = std::max({modelMax, value.r, value.g, value.b});
                        modelMin = std::min({modelMin, value.r, value.g, value.b});
                    }
    EXPECT_LE(modelMax, 2.0f * dataMax + 0.05f);
    EXPECT_GE(modelMin, 0.0f);
}

TEST(RfFile, SaveLoadRoundTripIsExact) {
    test::TempDir dir;
    osg::ref_ptr<RfMaterial> m = RfMaterial::fit(sample(5, 3), FitOptions::parse("lobes=1"));
    saveMaterial(*m, dir.file("rf.exr"));
    osg::ref_ptr<Material> loaded = loadMaterial(dir.file("rf.exr"));
    ASSERT_EQ(loaded->methodName(), "rf");
    const RfMaterial& back = static_cast<const RfMaterial&>(*loaded);
    EXPECT_EQ(back.lobeCount(), 1);
    EXPECT_EQ(back.rhoD, m->rhoD);
    EXPECT_EQ(back.rhoV, m->rhoV);
    EXPECT_EQ(back.lobes, m->lobes);
    EXPECT_EQ(back.fitInfo.at("seconds"), m->fitInfo.at("seconds"));
    EXPECT_TRUE(back.views() == m->views() && back.lights() == m->lights());
    const glm::vec3 v = Direction{37, 110}.toVector(), l = Direction{22, 300}.toVector();
    EXPECT_EQ(back.evaluate(4, 2, v, l), m->evaluate(4, 2, v, l));
    EXPECT_EQ(back.memory().bytesPerTexel, m->memory().bytesPerTexel);
    const auto info = test::runCommand("oiiotool --info " + test::shellQuote(dir.file("rf.exr")));
    EXPECT_EQ(info.exitCode, 0) << info.output;

    // A file whose arrays do not match its declared shape is refused with the reason.
    FittedMaterial broken = m->toFittedMaterial();
    broken.parameters["lobes"] = "2";
    saveFittedMaterial(broken, dir.file("broken.exr"));
    EXPECT_EQ(errorOf([&] { loadMaterial(dir.file("broken.exr")); }),
              dir.file("broken.exr") +
                  ": texture 'lobes' must be 5x3, 162 layer(s) of 4 channels, stored as half");
}

// The lobes are stored as half floats (seed 001 Table 2's 1785 bytes per texel) with exponents up
// to 256, so rounding is amplified: a base b = (a, b, c) . l off by Db changes b^n by about
// n b^(n-1) Db. This derives the bound from half precision (round to nearest: relative error at
// most u = 2^-11 per stored value) and checks that rounding the lobes of lobe fields with
// exponents from 1 to 256 never changes a reflectance field by more than it, at every measured
// light. What the rounding does to a fit's error is measured in materials/rf/README.md.
TEST(RfHalfLobes, RoundingStaysWithinTheBoundDerivedFromHalfPrecision) {
    const DirectionSet bonn = DirectionSet::bonn81();
    constexpr int kLobes = 2, kSize = 4;
    osg::ref_ptr<RfMaterial> exact = RfMaterial::create(kSize, kSize, bonn, bonn, kLobes);
    std::mt19937 rng(12);
    std::uniform_real_distribution<float> unit(0.0f, 1.0f);
    const std::size_t texels = exact->texelCount();
    const std::size_t views = bonn.size();
    // rho_v on a 1/1024 grid and rho_d on 1/255: exact in their storage, so only lobes round.
    for (float& v : exact->rhoV) v = std::round(unit(rng) * 1024.0f) / 1024.0f;
    for (float& v : exact->rhoD) v = std::round(unit(rng) * 255.0f) / 255.0f;
    const float exponents[] = {1.0f, 7.3f, 33.7f, 64.0f, 129.9f, 255.8f};
    for (std::size_t layer = 0; layer < views * kLobes; ++layer)
        for (std::size_t t = 0; t < texels; ++t) {
            float* p = &exact->lobes[(layer * texels + t) * 4];
            // An axis in the upper hemisphere; magnitude near 1, as the fitter leaves it (the lobe
            // sum peaks at 1 over the measured lights), so the base reaches 1 and a little more.
            const Direction axis{unit(rng) * 80.0f, unit(rng) * 360.0f};
            const glm::vec3 a = axis.toVector() * (0.95f + 0.1f * unit(rng));
            p[0] = a.x;
            p[1] = a.y;
            p[2] = a.z;
            p[3] = exponents[(layer + t) % 6];
        }
    osg::ref_ptr<RfMaterial> stored = new RfMaterial(*exact);
    stored->lobes = exact->lobes;
    stored->roundToStorage();
    ASSERT_EQ(stored->rhoV, exact->rhoV);
    ASSERT_EQ(stored->rhoD, exact->rhoD);
    ASSERT_NE(stored->lobes, exact->lobes);

    const double u = std::ldexp(1.0, -11);
    double worstRatio = 0, worstAt256 = 0;
    for (std::size_t t = 0; t < texels; ++t)
        for (std::size_t v = 0; v < views; ++v)
            for (std::size_t l = 0; l < bonn.size(); ++l) {
                const glm::vec3 light = bonn.vector(l);
                // Bound of |sum_i stored lobe_i - exact lobe_i| in double, per lobe:
                //  base: |Db| <= u m with m = sum_j |a_j l_j|; by the mean value theorem the
                //        lobe moves by at most n' B^(n'-1) |Db|, B = b + |Db|, n' = n (1 + u) (or
                //        n (1 - u) where B < 1: the larger of the two powers);
                //  exponent: |Dn| <= u n moves b^n by at most max |b^(n (1 +- u)) - b^n|.
                double bound = 0;
                for (int i = 0; i < kLobes; ++i) {
                    const float* p = &exact->lobes[((v * kLobes + i) * texels + t) * 4];
                    const double b =
                        double(p[0]) * light.x + double(p[1]) * light.y + double(p[2]) * light.z;
                    const double m = std::abs(double(p[0]) * light.x) +
                                     std::abs(double(p[1]) * light.y) +
                                     std::abs(double(p[2]) * light.z);
                    // Below 2^-14 half is subnormal: an absolute error of up to 2^-25 instead.
                    const double db =
                        u * m + std::ldexp(1.0, -25) *
                                    (std::abs(light.x) + std::abs(light.y) + std::abs(light.z));
                    const double n = p[3], hi = b + db;
                    if (hi <= 0) continue;  // both the exact and the rounded lobe are 0 here
                    const double power = hi >= 1 ? n * (1 + u) : n * (1 - u);
                    bound += n * (1 + u) * std::pow(hi, power - 1) * db;
                    if (b > 0)
                        bound += std::max(std::abs(std::pow(b, n * (1 + u)) - std::pow(b, n)),
                                          std::abs(std::pow(b, n * (1 - u)) - std::pow(b, n)));
                }
                // Float evaluation of both sums (pow and the dot product): a few ulp of each.
                const double exactSum = exact->lobeSum(t, v, light);
                const double storedSum = stored->lobeSum(t, v, light);
                const double slack = 8 * std::ldexp(1.0, -24) * (1 + std::abs(exactSum));
                const double difference = std::abs(storedSum - exactSum);
                ASSERT_LE(difference, bound + slack)
                    << "texel " << t << " view " << v << " light " << l << ": exact " << exactSum
                    << " stored " << storedSum;
                if (bound > 1e-4) worstRatio = std::max(worstRatio, difference / bound);
                for (int i = 0; i < kLobes; ++i)
                    if (exact->lobes[((v * kLobes + i) * texels + t) * 4 + 3] > 255.0f)
                        worstAt256 = std::max(worstAt256, difference / (1 + exactSum));
            }
    // The bound is not loose by orders of magnitude: rounding reaches a good part of it.
    EXPECT_GT(worstRatio, 0.05);
    std::cout << "rf half lobes: largest change of a lobe sum " << worstAt256
              << " (relative to 1 + sum) where n = 256; largest change / bound " << worstRatio
              << "\n";
}
