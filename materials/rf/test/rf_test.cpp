// Method "rf" (materials/rf): options, parameter recovery, the built-in sample, save/load, memory.
#include <gtest/gtest.h>

#include <cmath>
#include <iostream>
#include <random>

#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/lambert/Lambert.h"
#include "materials/rf/Rf.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

using osgBTF::test::errorOf;

namespace {

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

/** Lobe `lobe` (index into the [layer][y][x] lobes) = (axis, exponent), rounded as stored. */
void setLobe(RfMaterial& m, std::size_t lobe, const glm::vec3& axis, float exponent) {
    const float values[] = {axis.x, axis.y, axis.z, exponent};
    m.lobes.write(lobe * 4, values, 4);
}

/** A model with known, plausible parameters: a broad lobe near the normal and a glossy one near
 *  the mirror direction of each view, values within [0, 1]. */
osg::ref_ptr<RfMaterial> groundTruth(int width, int height) {
    const DirectionSet bonn = DirectionSet::bonn81();
    osg::ref_ptr<RfMaterial> m = RfMaterial::create(width, height, bonn, bonn, 2);
    const std::size_t texels = m->texelCount();
    for (std::size_t t = 0; t < texels; ++t) {
        for (int c = 0; c < 3; ++c) m->rhoD.set(t * 3 + c, 0.02f + 0.01f * float((t + c) % 4));
        for (std::size_t v = 0; v < bonn.size(); ++v) {
            for (int c = 0; c < 3; ++c)
                m->rhoV.set((v * texels + t) * 3 + c, 0.35f + 0.1f * float((t + 2 * c + v) % 4));
            const glm::vec3 view = bonn.vector(v);
            const float n1 = 1.0f + 0.5f * float((t + v) % 3), n2 = 6.0f + 3.0f * float(t % 4);
            const glm::vec3 d1 = glm::normalize(
                glm::vec3(0.15f * std::sin(float(t + v)), 0.15f * std::cos(float(3 * t + v)), 1));
            const glm::vec3 d2 = glm::normalize(glm::vec3(-view.x, -view.y, view.z + 0.3f));
            const glm::vec3 a1 = std::pow(0.6f, 1.0f / n1) * d1,
                            a2 = std::pow(0.5f, 1.0f / n2) * d2;
            setLobe(*m, (v * 2) * texels + t, a1, n1);
            setLobe(*m, (v * 2 + 1) * texels + t, a2, n2);
        }
    }
    return m;
}

}  // namespace

TEST(RfOptions, InvalidOptionsAreRefusedWithExactMessages) {
    const MeasuredBtf btf = test::sampleBtf(2, 2);
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
              "rf: option lobe is unknown (known: lobes, iterations, starts, max-exponent, "
              "diffuse, colour)");
    // The registry's entry point validates the same way.
    EXPECT_EQ(errorOf([&] { findMethod("rf").fit(btf, FitOptions::parse("lobes=0")); }),
              "rf: option lobes must be an integer in 1..8, got 0");
}

TEST(RfOptions, DataTheModelCannotHoldIsRefused) {
    EXPECT_EQ(errorOf([] { RfMaterial::fit(MeasuredBtf(), {}); }), "rf: the measured BTF is empty");
    const DirectionSet none("none", {});
    EXPECT_EQ(errorOf([&] { RfMaterial::create(2, 2, none, DirectionSet::bonn81(), 2); }),
              "rf: needs at least one measured view");
    // One or two views are interpolated along them (DirectionInterpolator), not refused.
    const DirectionSet two("two", {{0, 0}, {30, 0}});
    EXPECT_EQ(RfMaterial::create(2, 2, two, DirectionSet::bonn81(), 2)->views().size(), 2u);
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

// Meseth et al. 2003 Table 2 at its standard configuration: Bonn 81 directions, 2 lobes, 256 x 256
// texels. The numbers come from the sizes of the model's arrays and their declared storage kinds.
TEST(RfMemory, MatchesMeseth2003Table2) {
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
    const MeasuredBtf btf = test::sampleBtf(8, 8);
    osg::ref_ptr<RfMaterial> m = RfMaterial::fit(btf, {});
    ASSERT_TRUE(m->rhoD.allFinite() && m->rhoV.allFinite() && m->lobes.allFinite());
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
    osg::ref_ptr<RfMaterial> m =
        RfMaterial::fit(test::sampleBtf(5, 3), FitOptions::parse("lobes=1"));
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

// The lobes are stored as half floats (Meseth et al. 2003 Table 2's 1785 bytes per texel) with
// exponents up to 256, so rounding is amplified: a base b = (a, b, c) . l off by Db changes b^n by
// about n b^(n-1) Db. This derives the bound from half precision (round to nearest: relative error
// at most u = 2^-11 per stored value) and checks that rounding the lobes of lobe fields with
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
    for (std::size_t i = 0; i < exact->rhoV.size(); ++i)
        exact->rhoV.set(i, std::round(unit(rng) * 1024.0f) / 1024.0f);
    for (std::size_t i = 0; i < exact->rhoD.size(); ++i)
        exact->rhoD.set(i, std::round(unit(rng) * 255.0f) / 255.0f);
    // The exact lobes as floats (the model reads any precision); `stored` gets them as half.
    exact->lobes = StoredValues(MaterialTexture::Float, exact->lobes.size());
    const float exponents[] = {1.0f, 7.3f, 33.7f, 64.0f, 129.9f, 255.8f};
    for (std::size_t layer = 0; layer < views * kLobes; ++layer)
        for (std::size_t t = 0; t < texels; ++t) {
            // An axis in the upper hemisphere; magnitude near 1, as the fitter leaves it (the lobe
            // sum peaks at 1 over the measured lights), so the base reaches 1 and a little more.
            const Direction axis{unit(rng) * 80.0f, unit(rng) * 360.0f};
            const glm::vec3 a = axis.toVector() * (0.95f + 0.1f * unit(rng));
            setLobe(*exact, layer * texels + t, a, exponents[(layer + t) % 6]);
        }
    osg::ref_ptr<RfMaterial> stored = new RfMaterial(*exact);
    stored->lobes = StoredValues(MaterialTexture::Half, exact->lobes.size());
    std::size_t rounded = 0;
    for (std::size_t i = 0; i < exact->lobes.size(); ++i) {
        stored->lobes.set(i, exact->lobes[i]);
        rounded += stored->lobes[i] != exact->lobes[i];
    }
    ASSERT_GT(rounded, exact->lobes.size() / 2);

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
                    float p[4];
                    exact->lobes.read(((v * kLobes + i) * texels + t) * 4, 4, p);
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

// ---- Boßerhoff and Nicoll 2003's per-view Lafortune BTF: options diffuse=0 and colour=rgb
// -----------------------

namespace {

/** Five of the Bonn views (zenith, two rings, two azimuths): the variants' fits are per view, so
 *  a few views test them as well as 81 at a fraction of the time; all 81 lights constrain the
 *  lobes as in a real fit. */
DirectionSet fewViews() {
    const DirectionSet bonn = DirectionSet::bonn81();
    return DirectionSet("bonn81-5", {bonn[0], bonn[3], bonn[10], bonn[30], bonn[60]});
}

/** A model of the variant with known lobes: per view a broad lobe near the normal and a glossy
 *  one near the mirror direction. With rgb the channels get lobes of different shapes (red
 *  glossy and sharp, green broad and tilted the other way, blue nearly Lambertian), so their
 *  ratio changes with the light, which luminance lobes times a colour cannot follow. */
osg::ref_ptr<RfMaterial> variantTruth(int width, int height, RfMaterial::Variant variant) {
    const DirectionSet views = fewViews(), lights = DirectionSet::bonn81();
    osg::ref_ptr<RfMaterial> m = RfMaterial::create(width, height, views, lights, 2, variant);
    const std::size_t texels = m->texelCount();
    const int channels = m->lobeChannels();
    for (std::size_t t = 0; t < texels; ++t) {
        for (std::size_t i = 0; i < m->rhoD.size() / texels; ++i)
            m->rhoD.set(t * 3 + i, 0.03f + 0.01f * float((t + i) % 3));
        for (std::size_t v = 0; v < views.size(); ++v) {
            for (int c = 0; c < 3; ++c)
                m->rhoV.set((v * texels + t) * 3 + c, 0.35f + 0.1f * float((t + 2 * c + v) % 4));
            const glm::vec3 view = views.vector(v);
            for (int c = 0; c < channels; ++c) {
                const float tilt = channels == 1 ? 0.15f : 0.3f * float(1 - c);
                const float n1 = (channels == 1 ? 1.0f : 1.0f + 1.5f * float(c == 1)) +
                                 0.5f * float((t + v) % 2);
                const float n2 = channels == 1 ? 6.0f + 3.0f * float(t % 3)
                                               : (c == 0   ? 14.0f
                                                  : c == 1 ? 4.0f
                                                           : 2.0f);
                const float w2 = channels == 1 ? 0.5f : (c == 0 ? 0.8f : c == 1 ? 0.2f : 0.05f);
                const glm::vec3 d1 = glm::normalize(
                    glm::vec3(tilt * std::sin(float(t + v)), tilt * std::cos(float(3 * t + v)), 1));
                const glm::vec3 d2 =
                    glm::normalize(glm::vec3(-view.x, -view.y, view.z + (c == 1 ? 0.8f : 0.3f)));
                const glm::vec3 a1 = std::pow(0.6f, 1.0f / n1) * d1,
                                a2 = std::pow(w2, 1.0f / n2) * d2;
                const std::size_t first = (v * channels + c) * 2;
                setLobe(*m, first * texels + t, a1, n1);
                setLobe(*m, (first + 1) * texels + t, a2, n2);
            }
        }
    }
    return m;
}

ErrorSummary errorTo(const MeasuredBtf& btf, const RfMaterial& m) {
    return computeError(btf, [&](std::size_t t, float* out) { m.evaluateMeasured(t, out); });
}

/** The relative rms residual sqrt(sum r^2 / sum y^2) of the model at the measured pairs. */
double relativeRms(const MeasuredBtf& btf, const RfMaterial& m) {
    double rr = 0, yy = 0;
    std::vector<float> model(btf.viewCount() * btf.lightCount() * 3);
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        const std::vector<float> data = btf.abrdf(t);
        m.evaluateMeasured(t, model.data());
        for (std::size_t i = 0; i < data.size(); ++i) {
            rr += double(model[i] - data[i]) * double(model[i] - data[i]);
            yy += double(data[i]) * double(data[i]);
        }
    }
    return std::sqrt(rr / yy);
}

}  // namespace

TEST(RfVariants, OptionsAndShapesAreValidatedWithExactMessages) {
    const MeasuredBtf btf = test::sampleBtf(2, 2);
    const auto fitWith = [&](const std::string& options) {
        return errorOf([&] { RfMaterial::fit(btf, FitOptions::parse(options)); });
    };
    EXPECT_EQ(fitWith("diffuse=2"), "rf: option diffuse must be 0 or 1, got 2");
    EXPECT_EQ(fitWith("diffuse=off"), "rf: option diffuse must be 0 or 1, got off");
    EXPECT_EQ(fitWith("colour=grey"), "rf: option colour must be one of luminance, rgb, got grey");
    EXPECT_EQ(fitWith("color=rgb"),
              "rf: option color is unknown (known: lobes, iterations, starts, max-exponent, "
              "diffuse, colour)");
    // The lobe count stays 1..8 in every variant (lobes per channel with rgb; Boßerhoff and Nicoll
    // 2003's luminance model goes up to 7).
    EXPECT_EQ(fitWith("colour=rgb lobes=9"), "rf: option lobes must be an integer in 1..8, got 9");
    // rgb triples the lobe layers: 151 UBO2014 views take at most 4 lobes per channel.
    const DirectionSet ubo = DirectionSet::ubo2014(), lights = fewViews();
    EXPECT_EQ(errorOf([&] {
                  RfMaterial::create(2, 2, ubo, lights, 5, {false, true});
              }),
              "rf: 151 views x 3 colour channels (colour=rgb) x 5 lobes need 2265 texture "
              "layers, more than the 2048 OpenGL guarantees");
    EXPECT_EQ(RfMaterial::create(2, 2, ubo, lights, 4, {false, true})->lobeCount(), 4);
    EXPECT_EQ(RfMaterial::create(2, 2, ubo, lights, 8, {false, false})->lobeCount(), 8);
    // The fit refuses such data before any work, with the same message.
    const MeasuredBtf wide(2, 1, ubo, lights);
    EXPECT_EQ(errorOf([&] { RfMaterial::fit(wide, FitOptions::parse("colour=rgb lobes=5")); }),
              "rf: 151 views x 3 colour channels (colour=rgb) x 5 lobes need 2265 texture "
              "layers, more than the 2048 OpenGL guarantees");
}

// Boßerhoff and Nicoll 2003's luminance model without a diffuse term, from data generated by known
// lobes: the fit returns to the data. Its tolerance: the fitter stops trying starts for a (texel,
// view) once the relative rms residual is 1 % (README, Fit step 2), which is above what storing the
// lobes in half costs (n u = 14 x 2^-11 = 0.7 % at the largest exponent here, before rho_v absorbs
// it).
TEST(RfVariants, LuminanceWithoutDiffuseRecoversItsModel) {
    osg::ref_ptr<RfMaterial> truth = variantTruth(3, 2, {false, false});
    const MeasuredBtf data = render(*truth, 0.0f, 1);
    osg::ref_ptr<RfMaterial> m = RfMaterial::fit(data, FitOptions::parse("diffuse=0"));
    EXPECT_FALSE(m->hasDiffuse());
    EXPECT_EQ(m->lobeChannels(), 1);
    EXPECT_TRUE(m->rhoD.empty());
    EXPECT_EQ(m->fitInfo.at("diffuse"), "0");
    EXPECT_EQ(m->fitInfo.at("colour"), "luminance");
    const double residual = relativeRms(data, *m);
    const ErrorSummary e = errorTo(data, *m);
    std::cout << "rf diffuse=0: relative rms residual " << residual << ", error avg " << e.average
              << " max " << e.maximum << ", fit " << m->fitInfo["seconds"] << " s\n";
    EXPECT_LT(residual, 0.01);
}

// The RGB model (2 lobes per channel) on data whose channels have lobes of different shapes: it
// recovers them to the fitter's 1 % (as above), where the luminance model (the same lobes for
// every channel times a colour) cannot follow the colour changing with the light.
TEST(RfVariants, RgbFitsPerChannelLobesThatLuminanceCannot) {
    osg::ref_ptr<RfMaterial> truth = variantTruth(3, 2, {false, true});
    const MeasuredBtf data = render(*truth, 0.0f, 1);
    osg::ref_ptr<RfMaterial> rgb = RfMaterial::fit(data, FitOptions::parse("diffuse=0 colour=rgb"));
    osg::ref_ptr<RfMaterial> luminance = RfMaterial::fit(data, FitOptions::parse("diffuse=0"));
    EXPECT_EQ(rgb->lobeChannels(), 3);
    const double rgbResidual = relativeRms(data, *rgb);
    const double luminanceResidual = relativeRms(data, *luminance);
    std::cout << "rf colour=rgb on per-channel lobes: relative rms residual " << rgbResidual
              << " (luminance " << luminanceResidual << "), fit " << rgb->fitInfo["seconds"]
              << " s (luminance " << luminance->fitInfo["seconds"] << " s)\n";
    EXPECT_LT(rgbResidual, 0.01);
    // The channels' ratio changes by a factor of several over the lights: a common lobe shape
    // leaves much more than the fitter's tolerance.
    EXPECT_GT(luminanceResidual, 5 * 0.01);
    // With more lobes luminance still cannot: the shapes differ, not their number.
    osg::ref_ptr<RfMaterial> more =
        RfMaterial::fit(data, FitOptions::parse("diffuse=0 lobes=6 starts=1"));
    const double moreResidual = relativeRms(data, *more);
    std::cout << "  luminance with 6 lobes: " << moreResidual << "\n";
    EXPECT_GT(moreResidual, 2 * 0.01);
}

// Without the diffuse term a constant offset in the data has no term to go to: the same data
// plus 0.1 are fitted to the noise floor by the default model (rho_d takes the 0.1), not by the
// lobes-only model, whose lobes must bend to imitate a constant.
TEST(RfVariants, WithoutDiffuseAConstantOffsetIsNotRepresented) {
    osg::ref_ptr<RfMaterial> truth = variantTruth(3, 2, {false, false});
    MeasuredBtf data = render(*truth, 0.0f, 1);
    const float offset = 0.1f;
    for (std::size_t v = 0; v < data.viewCount(); ++v)
        for (std::size_t l = 0; l < data.lightCount(); ++l)
            for (std::size_t t = 0; t < data.texelCount(); ++t)
                for (int c = 0; c < 3; ++c)
                    data.setValue(v, l, t, c, data.value(v, l, t, c) + offset);
    osg::ref_ptr<RfMaterial> withFloor = RfMaterial::fit(data, {});
    osg::ref_ptr<RfMaterial> without = RfMaterial::fit(data, FitOptions::parse("diffuse=0"));
    const double a = relativeRms(data, *withFloor), b = relativeRms(data, *without);
    std::cout << "rf on lobes + 0.1: relative rms residual with rho_d " << a << ", without " << b
              << "\n";
    EXPECT_LT(a, 0.01);
    for (std::size_t i = 0; i < withFloor->rhoD.size(); ++i)
        EXPECT_NEAR(withFloor->rhoD[i], offset, 0.02);
    EXPECT_GT(b, 2 * a);
    EXPECT_GT(b, 0.01);
}

TEST(RfVariants, SaveLoadRoundTripIsExactAndOldFilesLoadAsTheDefault) {
    test::TempDir dir;
    osg::ref_ptr<RfMaterial> m = variantTruth(3, 2, {false, true});
    saveMaterial(*m, dir.file("rgb.exr"));
    osg::ref_ptr<Material> loaded = loadMaterial(dir.file("rgb.exr"));
    const RfMaterial& back = static_cast<const RfMaterial&>(*loaded);
    EXPECT_FALSE(back.hasDiffuse());
    EXPECT_EQ(back.lobeChannels(), 3);
    EXPECT_TRUE(back.rhoD.empty());
    EXPECT_EQ(back.rhoV, m->rhoV);
    EXPECT_EQ(back.lobes, m->lobes);
    const glm::vec3 v = Direction{37, 110}.toVector(), l = Direction{22, 300}.toVector();
    EXPECT_EQ(back.evaluate(2, 1, v, l), m->evaluate(2, 1, v, l));
    // No rhoD part is written.
    const FittedMaterial file = m->toFittedMaterial();
    EXPECT_EQ(file.findTexture("rhoD"), nullptr);
    EXPECT_EQ(file.texture("lobes").depth, 5 * 3 * 2);

    // A file from before the options (no "diffuse", no "colour") is the default model.
    FittedMaterial old =
        RfMaterial::fit(test::sampleBtf(3, 2), FitOptions::parse("lobes=1 starts=1"))
            ->toFittedMaterial();
    old.parameters.erase("diffuse");
    old.parameters.erase("colour");
    saveFittedMaterial(old, dir.file("old.exr"));
    osg::ref_ptr<Material> oldLoaded = loadMaterial(dir.file("old.exr"));
    const RfMaterial& o = static_cast<const RfMaterial&>(*oldLoaded);
    EXPECT_TRUE(o.hasDiffuse());
    EXPECT_EQ(o.lobeChannels(), 1);

    FittedMaterial broken = file;
    broken.parameters["colour"] = "grey";
    saveFittedMaterial(broken, dir.file("grey.exr"));
    EXPECT_EQ(errorOf([&] { loadMaterial(dir.file("grey.exr")); }),
              dir.file("grey.exr") + ": parameter 'colour' must be luminance or rgb, got grey");
    broken = file;
    broken.parameters["diffuse"] = "yes";
    saveFittedMaterial(broken, dir.file("yes.exr"));
    EXPECT_EQ(errorOf([&] { loadMaterial(dir.file("yes.exr")); }),
              dir.file("yes.exr") + ": parameter 'diffuse' must be 0 or 1, got yes");
    // rgb declared, luminance-sized lobes: the shape check names the texture.
    broken = file;
    broken.parameters["colour"] = "luminance";
    saveFittedMaterial(broken, dir.file("lum.exr"));
    EXPECT_EQ(errorOf([&] { loadMaterial(dir.file("lum.exr")); }),
              dir.file("lum.exr") +
                  ": texture 'lobes' must be 3x2, 10 layer(s) of 4 channels, stored as half");
}

// Boßerhoff and Nicoll 2003 Table 2 lists "LaF.-Lum-2 Lobes, 256x256, 2.8 MB" for one view slot: 8
// lobe values and a 3-value base colour, 11 32-bit floats per texel (256 x 256 x 44 bytes = 2.75
// MiB). Ours per view: the same 11 values, in half; rgb: 24 lobe values (the paper's 24
// coefficients) and the 3 per-channel scales. From the arrays' sizes and storage kinds (memory()).
TEST(RfMemory, VariantsMatchBosserhoff2003PerView) {
    const DirectionSet bonn = DirectionSet::bonn81();
    // A small model: the footprint per texel does not depend on the size (the README scales it
    // to 256 x 256), and a 256 x 256 rgb model would take 570 MB of floats in a unit test.
    const MemoryFootprint lum = RfMaterial::create(4, 4, bonn, bonn, 2, {false, false})->memory();
    EXPECT_DOUBLE_EQ(lum.valuesPerTexel, 81 * 11.0);
    EXPECT_DOUBLE_EQ(lum.bytesPerTexel, 81 * 22.0);
    EXPECT_EQ(lum.totalBytes, std::uint64_t(81 * 22) * 4 * 4);
    const MemoryFootprint rgb = RfMaterial::create(4, 4, bonn, bonn, 2, {false, true})->memory();
    EXPECT_DOUBLE_EQ(rgb.valuesPerTexel, 81 * (24.0 + 3));
    EXPECT_DOUBLE_EQ(rgb.bytesPerTexel, 81 * 54.0);
    const MemoryFootprint seven = RfMaterial::create(4, 4, bonn, bonn, 7, {false, false})->memory();
    EXPECT_DOUBLE_EQ(seven.valuesPerTexel, 81 * (28.0 + 3));
    // With the floor: Meseth et al. 2003's 3 bytes of rho_d on top.
    const MemoryFootprint rgbFloor =
        RfMaterial::create(4, 4, bonn, bonn, 2, {true, true})->memory();
    EXPECT_DOUBLE_EQ(rgbFloor.valuesPerTexel, 3 + 81 * 27.0);
    EXPECT_DOUBLE_EQ(rgbFloor.bytesPerTexel, 3 + 81 * 54.0);
}

}  // namespace OSGBTF_TEST_FILE
