#include <cmath>
#include <random>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "core/DirectionInterpolation.h"
#include "core/Directions.h"
#include "core/Error.h"
#include "tests/TestUtil.h"

using namespace osgBTF;

TEST(DirectionSetFile, MissingFileNamesTheFile) {
    try {
        DirectionSet::readFile("/nonexistent/dirs.txt");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "/nonexistent/dirs.txt: cannot open direction file");
    }
}

TEST(DirectionSetFile, MalformedLineIsReportedWithItsNumber) {
    test::TempDir dir;
    test::writeTextFile(dir.file("d.txt"), "# comment\n0 0\n15 abc\n");
    try {
        DirectionSet::readFile(dir.file("d.txt"));
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_EQ(std::string(e.what()),
                  dir.file("d.txt") + ": line 3: expected \"theta phi\" in degrees");
    }
    test::writeTextFile(dir.file("e.txt"), "95 0\n");
    EXPECT_THROW(DirectionSet::readFile(dir.file("e.txt")), Error);
    test::writeTextFile(dir.file("f.txt"), "# nothing\n");
    EXPECT_THROW(DirectionSet::readFile(dir.file("f.txt")), Error);
}

TEST(DirectionSet, Bonn81MatchesTheRingTable) {
    const DirectionSet set = DirectionSet::bonn81();
    ASSERT_EQ(set.size(), 81u);
    // formats.md 1.1: ring starts at indices 0, 1, 7, 19, 37, 57.
    EXPECT_EQ(set[0].theta, 0);
    EXPECT_EQ(set[1].theta, 15);
    EXPECT_EQ(set[7].theta, 30);
    EXPECT_EQ(set[19].theta, 45);
    EXPECT_EQ(set[37].theta, 60);
    EXPECT_EQ(set[57].theta, 75);
    EXPECT_FLOAT_EQ(set[56].phi, 342);  // the paper shows a view at theta 60, phi 342
    EXPECT_FLOAT_EQ(set[80].phi, 345);
    EXPECT_EQ(set.find(30, 30), 8);  // "00008 tl000 pl000 tv030 pv030": view index 8
    EXPECT_EQ(set.find(15, 60), 2);  // "00162 tl015 pl060 ...": 162 = 81 * 2 + 0
}

TEST(DirectionSet, Ubo2014Has151DirectionsIncludingTheReadmeExample) {
    const DirectionSet set = DirectionSet::ubo2014();
    ASSERT_EQ(set.size(), 151u);
    EXPECT_GE(set.find(60, 270), 0);
    EXPECT_GE(set.find(60, 135), 0);
}

TEST(DirectionSet, VectorRoundTripAndFrame) {
    const glm::vec3 x = Direction{90, 0}.toVector(), y = Direction{90, 90}.toVector();
    EXPECT_NEAR(x.x, 1, 1e-6);
    EXPECT_NEAR(y.y, 1, 1e-6);
    EXPECT_NEAR((Direction{0, 123}.toVector().z), 1, 1e-6);
    const DirectionSet set = DirectionSet::ubo2014();
    for (const Direction& d : set.directions()) {
        const Direction back = Direction::fromVector(d.toVector());
        EXPECT_NEAR(glm::dot(back.toVector(), d.toVector()), 1.0, 1e-6);
        if (d.theta > 0) {
            EXPECT_NEAR(back.phi, d.phi, 1e-3);
        }
    }
}

TEST(DirectionSet, FileAndStringRoundTrip) {
    test::TempDir dir;
    const DirectionSet set = DirectionSet::ubo2014();
    set.writeFile(dir.file("ubo.txt"));
    EXPECT_TRUE(DirectionSet::readFile(dir.file("ubo.txt")) == set);
    const DirectionSet back = DirectionSet::deserialize(set.serialize());
    EXPECT_TRUE(back == set);
    EXPECT_EQ(back.name(), "ubo2014");
}

TEST(DirectionInterpolation, TooFewDirectionsIsAnError) {
    EXPECT_THROW(DirectionInterpolator(DirectionSet("two", {{0, 0}, {30, 0}})), Error);
}

TEST(DirectionInterpolation, TriangulationHasEulerTriangleCount) {
    // A planar triangulation of n points with h on the hull has 2n - 2 - h triangles.
    EXPECT_EQ(DirectionInterpolator(DirectionSet::bonn81()).triangles().size(), 2u * 81 - 2 - 24);
    EXPECT_EQ(DirectionInterpolator(DirectionSet::ubo2014()).triangles().size(), 2u * 151 - 2 - 24);
}

class InterpolationOnSet : public ::testing::TestWithParam<DirectionSet> {};

namespace {
bool cellHoldsASample(const DirectionSet& set, const DirectionInterpolator::Baked& baked,
                      const glm::vec3& d) {
    const std::size_t cell = DirectionInterpolator::bakedCell(baked, d);
    for (std::size_t s = 0; s < set.size(); ++s)
        if (DirectionInterpolator::bakedCell(baked, set.vector(s)) == cell) return true;
    return false;
}
}  // namespace

TEST_P(InterpolationOnSet, ExactAtSamples) {
    const DirectionSet set = GetParam();
    DirectionInterpolator interp(set);
    for (std::size_t i = 0; i < set.size(); ++i) {
        const InterpolationWeights w = interp.weights(set.vector(i));
        float atSample = 0;
        for (int k = 0; k < 3; ++k)
            if (w.index[k] == int(i)) atSample += w.weight[k];
        EXPECT_NEAR(atSample, 1.0f, 1e-5) << "direction " << i;
    }
}

TEST_P(InterpolationOnSet, WeightsAreConvexAndReproduceTheDirection) {
    // Barycentric weights of the disc-map triangle reproduce the query's disc position exactly
    // inside the hull, and are a convex combination everywhere.
    const DirectionSet set = GetParam();
    DirectionInterpolator interp(set);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> theta(0, 89.9f), phi(0, 360);
    for (int n = 0; n < 2000; ++n) {
        const Direction d{theta(rng), phi(rng)};
        const InterpolationWeights w = interp.weights(d.toVector());
        float sum = 0;
        glm::vec2 p(0);
        for (int k = 0; k < 3; ++k) {
            ASSERT_GE(w.weight[k], 0.0f);
            ASSERT_GE(w.index[k], 0);
            ASSERT_LT(w.index[k], int(set.size()));
            sum += w.weight[k];
            p += w.weight[k] * directionToDisc(set.vector(w.index[k]));
        }
        ASSERT_NEAR(sum, 1.0f, 1e-5);
        if (d.theta < 74.0f) {
            EXPECT_LT(glm::length(p - directionToDisc(d.toVector())), 1e-5);
        }
    }
}

TEST_P(InterpolationOnSet, OutsideTheHullBlendsTheNearestBoundarySamples) {
    const DirectionSet set = GetParam();
    DirectionInterpolator interp(set);
    // At the horizon straight above a theta-75 sample, that sample gets all the weight.
    const int last = int(set.size()) - 1;
    const InterpolationWeights w = interp.weights(Direction{89.0f, set[last].phi}.toVector());
    float atSample = 0;
    for (int k = 0; k < 3; ++k)
        if (w.index[k] == last) atSample += w.weight[k];
    EXPECT_NEAR(atSample, 1.0f, 1e-4);
    // Below the horizon is clamped to it instead of failing.
    const InterpolationWeights below = interp.weights(glm::vec3(1, 0, -0.5f));
    EXPECT_NEAR(below.weight[0] + below.weight[1] + below.weight[2], 1.0f, 1e-5);
}

TEST_P(InterpolationOnSet, BakedTableAgreesWithExactWeightsAtCellCentres) {
    const DirectionSet set = GetParam();
    DirectionInterpolator interp(set);
    const auto baked = interp.bake(32);
    ASSERT_EQ(baked.indices.size(), 32u * 32 * 3);
    for (int j = 0; j < 32; ++j)
        for (int i = 0; i < 32; ++i) {
            const glm::vec2 p((i + 0.5f) / 16 - 1, (j + 0.5f) / 16 - 1);
            if (glm::length(p) > 0.99f) continue;
            const glm::vec3 d = discToDirection(p);
            if (cellHoldsASample(set, baked, d)) continue;
            const InterpolationWeights a = interp.weights(d),
                                       b = DirectionInterpolator::lookupBaked(baked, d);
            for (int k = 0; k < 3; ++k) {
                EXPECT_EQ(a.index[k], b.index[k]);
                EXPECT_FLOAT_EQ(a.weight[k], b.weight[k]);
            }
        }
}

TEST_P(InterpolationOnSet, BakedTableIsExactAtSamples) {
    const DirectionSet set = GetParam();
    const auto baked = DirectionInterpolator(set).bake(64);
    for (std::size_t s = 0; s < set.size(); ++s) {
        const InterpolationWeights w = DirectionInterpolator::lookupBaked(baked, set.vector(s));
        EXPECT_EQ(w.index[0], int(s));
        EXPECT_EQ(w.weight[0], 1.0f);
    }
}

INSTANTIATE_TEST_SUITE_P(Sets, InterpolationOnSet,
                         ::testing::Values(DirectionSet::bonn81(), DirectionSet::ubo2014()),
                         [](const auto& info) { return info.param.name(); });

TEST(DiscMap, InverseIsExact) {
    const DirectionSet set = DirectionSet::ubo2014();
    for (const Direction& d : set.directions()) {
        const glm::vec3 back = discToDirection(directionToDisc(d.toVector()));
        EXPECT_LT(glm::length(back - d.toVector()), 1e-6);
    }
}
