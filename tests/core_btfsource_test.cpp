// BtfSource: fitters read a MeasuredBtf in memory and a FactoredBtf decoded
// block by block through one interface. The factored reads must give what decoding the whole
// gives, subsampled errors must be the full computation's at those texels, and every method must
// fit factored input as well as the decoded data.
#include <algorithm>
#include <cmath>
#include <set>

#include <gtest/gtest.h>

#include "core/BtfSource.h"
#include "core/ErrorMetrics.h"
#include "core/FactoredBtf.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "materials/fmf/Fmf.h"
#include "tests/RandomFactors.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

float maxAbs(const std::vector<float>& values) {
    float m = 0;
    for (float v : values) m = std::max(m, std::abs(v));
    return m;
}

}  // namespace

TEST(BtfSource, MeasuredBtfReadsAreItsImagesAndAbrdfs) {
    for (Storage storage : {Storage::Float, Storage::Half}) {
        SampleOptions options;
        options.width = 5;
        options.height = 3;
        options.storage = storage;
        const MeasuredBtf btf = makeSampleBtf(options);
        const BtfSource& source = btf;
        ASSERT_EQ(source.imageCount(), 81u * 81u);
        const std::size_t values = source.texelCount() * 3;
        std::vector<float> images(3 * values);
        source.readImages(100, 3, images.data());
        for (std::size_t j = 0; j < 3; ++j) {
            const std::vector<float> expected = btf.image((100 + j) / 81, (100 + j) % 81);
            EXPECT_TRUE(std::equal(expected.begin(), expected.end(), images.begin() + j * values));
        }
        const std::vector<std::size_t> texels = {0, 7, 8, 14};
        std::vector<float> abrdfs(texels.size() * source.imageCount() * 3);
        source.readAbrdfs(texels.data(), texels.size(), abrdfs.data());
        for (std::size_t j = 0; j < texels.size(); ++j) {
            const std::vector<float> expected = btf.abrdf(texels[j]);
            EXPECT_TRUE(
                std::equal(expected.begin(), expected.end(), abrdfs.begin() + j * expected.size()))
                << "texel " << texels[j];
        }
    }
}

// Every factor layout and decoding step (colour models, exp of DRR, cosine division): block reads
// equal FactoredBtf::decode's values up to float rounding of differently shaped GEMMs.
TEST(BtfSource, FactoredReadsEqualTheDecodedWhole) {
    struct Variant {
        FactorModel model;
        std::array<int, 3> ranks;
        int colorModel;
        std::uint32_t drr;
        bool cosine;
    };
    for (const Variant& v : {Variant{FactorModel::Fmf, {4, 4, 4}, 0, 1, true},
                             Variant{FactorModel::Dfmf, {3, 5, 2}, 11, 0, true},
                             Variant{FactorModel::Dfmf, {2, 2, 6}, 3, 0, false}}) {
        FactoredBtf f = randomFactors(v.model, v.ranks, 7, 5, 3);
        setDecoding(f, v.colorModel, v.drr, v.cosine);
        const MeasuredBtf decoded = f.decode();
        const FactoredBtfSource source(f);
        EXPECT_FALSE(source.inMemory());
        EXPECT_EQ(source.width(), 7);
        EXPECT_EQ(source.height(), 5);
        EXPECT_EQ(source.source, "random.btf");
        EXPECT_EQ(source.decodedBytes(), f.decodedBytes());
        EXPECT_GE(source.abrdfBlockTexels(), 8u);

        const std::size_t values = source.texelCount() * 3;
        std::vector<float> got(5 * values), want(5 * values);
        source.readImages(6555, 5, got.data());  // the last images, across a view boundary
        decoded.readImages(6555, 5, want.data());
        const float tolerance = 1e-5f * maxAbs(want);
        for (std::size_t i = 0; i < got.size(); ++i) ASSERT_NEAR(got[i], want[i], tolerance) << i;

        const std::vector<std::size_t> texels = {34, 0, 12, 13};  // any order, bottom and top rows
        got.assign(texels.size() * source.imageCount() * 3, 0.0f);
        want = got;
        source.readAbrdfs(texels.data(), texels.size(), got.data());
        decoded.readAbrdfs(texels.data(), texels.size(), want.data());
        const float abrdfTolerance = 1e-5f * maxAbs(want);
        for (std::size_t i = 0; i < got.size(); ++i)
            ASSERT_NEAR(got[i], want[i], abrdfTolerance) << i;
    }
}

TEST(BtfSource, InconsistentFactorsAreRefusedWhenOpened) {
    FactoredBtf f = randomFactors(FactorModel::Fmf, {3, 3, 3}, 4, 4, 1);
    f.width = 5;  // SxV has 16 rows
    EXPECT_NE(errorOf([&] { FactoredBtfSource source(f); }).find("random.btf: "),
              std::string::npos);
}

TEST(BtfSource, RandomTexelsAreDistinctSortedAndDeterministic) {
    const MeasuredBtf btf(10, 10, DirectionSet::bonn81(), DirectionSet("one", {{0, 0}}));
    const std::vector<std::size_t> a = randomTexels(btf, 30, 5);
    ASSERT_EQ(a.size(), 30u);
    EXPECT_TRUE(std::is_sorted(a.begin(), a.end()));
    EXPECT_EQ(std::set<std::size_t>(a.begin(), a.end()).size(), 30u);
    EXPECT_LT(a.back(), 100u);
    EXPECT_EQ(randomTexels(btf, 30, 5), a);
    EXPECT_NE(randomTexels(btf, 30, 6), a);
    EXPECT_EQ(randomTexels(btf, 1000, 5).size(), 100u);
}

// The documented default: everything in memory, 4096 texels of factored input (a 400x400 file
// has 160000); an explicit count is capped at the texel count, 0 means all.
TEST(BtfSource, ErrorTexelCountDefaultsByWhereTheDataLive) {
    const MeasuredBtf inMemory(100, 50, DirectionSet("one", {{0, 0}}),
                               DirectionSet("one", {{0, 0}}));
    EXPECT_EQ(errorTexelCount(inMemory, -1), 5000u);
    EXPECT_EQ(errorTexelCount(inMemory, 0), 5000u);
    EXPECT_EQ(errorTexelCount(inMemory, 17), 17u);
    EXPECT_EQ(errorTexelCount(inMemory, 99999), 5000u);
    const FactoredBtf largeFactors = randomFactors(FactorModel::Fmf, {2, 2, 2}, 80, 80, 1);
    const FactoredBtfSource large(largeFactors);
    EXPECT_EQ(errorTexelCount(large, -1), 4096u);
    EXPECT_EQ(errorTexelCount(large, 0), 6400u);
    const FactoredBtf smallFactors = randomFactors(FactorModel::Fmf, {2, 2, 2}, 8, 8, 1);
    const FactoredBtfSource small(smallFactors);
    EXPECT_EQ(errorTexelCount(small, -1), 64u);
}

// The subsample's statistics are those of the full computation restricted to its texels.
TEST(BtfSource, SubsampledErrorIsTheFullErrorAtThoseTexels) {
    SampleOptions options;
    options.width = 6;
    options.height = 4;
    const MeasuredBtf btf = makeSampleBtf(options);
    // A model that is off by a texel-dependent amount: (1 + t) / 100 in every value.
    const AbrdfEvaluator model = [&](std::size_t t, float* out) {
        btf.abrdf(t, out);
        for (std::size_t i = 0; i < btf.imageCount() * 3; ++i) out[i] += float(1 + t) / 100;
    };
    const ErrorSummary all = computeError(btf, model);
    EXPECT_EQ(all.texelsCompared, 24u);
    const std::vector<std::size_t> subset = {1, 5, 6, 20};
    const ErrorSummary part = computeError(btf, model, &subset);
    EXPECT_EQ(part.texelsCompared, 4u);
    double sum = 0;
    for (std::size_t t = 0; t < 24; ++t) {
        const bool in = std::find(subset.begin(), subset.end(), t) != subset.end();
        if (in) {
            // |(d, d, d)| = sqrt(3) d in every pair.
            EXPECT_NEAR(part.perTexel[t], std::sqrt(3.0) * (1 + t) / 100, 1e-6);
            EXPECT_EQ(part.perTexel[t], all.perTexel[t]);
            sum += part.perTexel[t];
        } else {
            EXPECT_TRUE(std::isnan(part.perTexel[t])) << t;
        }
    }
    EXPECT_DOUBLE_EQ(part.average, sum / 4);
    EXPECT_NEAR(part.minimum, std::sqrt(3.0) * 2 / 100, 1e-6);
    EXPECT_NEAR(part.maximum, std::sqrt(3.0) * 21 / 100, 1e-6);
    double squares = 0;
    for (std::size_t t : subset) squares += std::pow((1 + t) / 100.0, 2);
    EXPECT_NEAR(part.rmse, std::sqrt(squares / 4), 1e-6);
}

// Every method fitted from factors gives the same error as its fit of the decoded data (within
// 1 %: the two differ only by the rounding of differently shaped decoding GEMMs, which iterative
// fits may follow along slightly different paths; 5 % for a method trained by stochastic gradient
// descent, one with a `seed` option, where such differences grow along the steps).
class FitFromFactors : public ::testing::TestWithParam<std::string> {
protected:
    static const FactoredBtf& factors() {
        static const FactoredBtf f = [] {
            SampleOptions options;
            options.width = 12;
            options.height = 12;
            const MeasuredBtf sample = makeSampleBtf(options);
            FitOptions fit;
            fit.set("components", "24");
            fit.set("storage", "float");
            osg::ref_ptr<FmfMaterial> m = FmfMaterial::fit(sample, fit);
            FactoredBtf factored = m->completeFactors();
            factored.source = "sample-fmf24";
            return factored;
        }();
        return f;
    }
};

TEST_P(FitFromFactors, GivesTheErrorOfTheFitOfTheDecodedData) {
    const MethodInfo& method = findMethod(GetParam());
    FitOptions options;
    for (const auto& [key, value] : std::map<std::string, std::string>{{"components", "3"},
                                                                       {"clusters", "4"},
                                                                       {"lobes", "1"},
                                                                       {"iterations", "10"},
                                                                       {"steps", "400"}}) {
        for (const OptionSpec& spec : method.options)
            if (spec.name == key) options.set(key, value);
    }
    const FactoredBtf& f = factors();
    const MeasuredBtf decoded = f.decode();
    const FactoredBtfSource source(f);
    const osg::ref_ptr<Material> fromFactors = method.fit(source, options);
    const osg::ref_ptr<Material> fromDecoded = method.fit(decoded, options);
    auto error = [&](const Material& m) {
        return computeError(decoded, [&](std::size_t t, float* out) { m.evaluateMeasured(t, out); })
            .average;
    };
    const double a = error(*fromFactors), b = error(*fromDecoded);
    const bool stochastic = std::any_of(method.options.begin(), method.options.end(),
                                        [](const OptionSpec& s) { return s.name == "seed"; });
    EXPECT_GT(b, 0.0);
    EXPECT_NEAR(a, b, (stochastic ? 0.05 : 0.01) * b + 1e-7) << method.name;
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, FitFromFactors, ::testing::ValuesIn(methodNamesInOrder()),
                         [](const auto& info) {
                             std::string name = info.param;
                             std::replace(name.begin(), name.end(), '-', '_');
                             return name;
                         });

}  // namespace OSGBTF_TEST_FILE
