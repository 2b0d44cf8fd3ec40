#include <algorithm>
#include <array>
#include <cmath>
#include <iostream>
#include <map>
#include <random>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "core/DirectionInterpolation.h"
#include "core/Directions.h"
#include "core/Error.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

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

TEST(DirectionInterpolation, AnEmptySetIsAnErrorAndTwoDirectionsAChainOfOneSegment) {
    EXPECT_THROW(DirectionInterpolator(DirectionSet("none", {})), Error);
    const DirectionInterpolator two(DirectionSet("two", {{0, 0}, {30, 0}}));
    EXPECT_TRUE(two.triangles().empty());
    ASSERT_EQ(two.hullEdges().size(), 1u);
    EXPECT_EQ(two.hullEdges()[0], (std::array<int, 2>{0, 1}));
}

TEST(DirectionInterpolation, TriangulationHasEulerTriangleCount) {
    // A planar triangulation of n points with h on the hull has 2n - 2 - h triangles.
    EXPECT_EQ(DirectionInterpolator(DirectionSet::bonn81()).triangles().size(), 2u * 81 - 2 - 24);
    EXPECT_EQ(DirectionInterpolator(DirectionSet::ubo2014()).triangles().size(), 2u * 151 - 2 - 24);
}

class InterpolationOnSet : public ::testing::TestWithParam<DirectionSet> {};

namespace {

/** The weights as a map index -> summed weight (slots may repeat an index, e.g. at hull edges). */
std::map<int, float> byIndex(const InterpolationWeights& w) {
    std::map<int, float> m;
    for (int k = 0; k < 3; ++k)
        if (w.weight[k] != 0.0f) m[w.index[k]] += w.weight[k];
    return m;
}

/** Largest difference of the weight any direction index gets. */
float weightDifference(const InterpolationWeights& a, const InterpolationWeights& b) {
    std::map<int, float> ma = byIndex(a), mb = byIndex(b);
    float worst = 0;
    for (const auto& [i, w] : ma) worst = std::max(worst, std::abs(w - mb[i]));
    for (const auto& [i, w] : mb) worst = std::max(worst, std::abs(w - ma[i]));
    return worst;
}

/** The steepest barycentric weight in the disc map: 1 / the smallest triangle height. */
double steepestWeight(const DirectionInterpolator& interp) {
    double smallest = 1e300;
    for (const auto& t : interp.triangles())
        for (int k = 0; k < 3; ++k) {
            const glm::dvec2 a(interp.discPoints()[t[k]]), b(interp.discPoints()[t[(k + 1) % 3]]),
                c(interp.discPoints()[t[(k + 2) % 3]]);
            const double area = std::abs((b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x));
            smallest = std::min(smallest, area / glm::length(c - b));  // height from a
        }
    return 1.0 / smallest;
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

TEST_P(InterpolationOnSet, ShaderTableGivesTheExactWeights) {
    // The table is exact, not sampled: wherever the query lands (random points, the cell borders
    // of the grid where rounding may pick either cell, the samples, the midpoints of every
    // triangle edge, outside the hull) it gives the reference's weights, up to rounding.
    const DirectionSet set = GetParam();
    const DirectionInterpolator interp(set);
    const int grid = 32;
    const DirectionTable table = interp.table(grid, 1024);
    EXPECT_EQ(table.width, 1024);
    EXPECT_EQ(table.texels.size(), std::size_t(table.width) * table.height * 4);
    std::vector<glm::vec2> queries;
    std::mt19937 rng(11);
    std::uniform_real_distribution<float> uniform(-1, 1);
    while (queries.size() < 20000) {
        const glm::vec2 p(uniform(rng), uniform(rng));
        if (glm::length(p) <= 1.0f) queries.push_back(p);
    }
    for (int i = 0; i <= grid; ++i)
        for (int n = 0; n < 200; ++n) {
            const float border = -1.0f + 2.0f * float(i) / float(grid), along = uniform(rng);
            for (const glm::vec2 p : {glm::vec2(border, along), glm::vec2(along, border)})
                if (glm::length(p) <= 1.0f) queries.push_back(p);
        }
    for (const glm::vec2& p : interp.discPoints()) queries.push_back(p);
    for (const auto& t : interp.triangles())
        for (int k = 0; k < 3; ++k)
            queries.push_back(0.5f *
                              (interp.discPoints()[t[k]] + interp.discPoints()[t[(k + 1) % 3]]));
    float worst = 0;
    for (const glm::vec2& p : queries) {
        const glm::vec3 d = discToDirection(p);
        const float difference =
            weightDifference(interp.weights(d), DirectionInterpolator::lookupTable(table, d));
        worst = std::max(worst, difference);
        ASSERT_LT(difference, 1e-5f) << "disc point (" << p.x << ", " << p.y << ")";
    }
    std::cout << set.name() << ": table vs reference, largest weight difference " << worst
              << " over " << queries.size() << " queries; per lookup " << table.meanTrianglesTested
              << " triangles and " << table.meanEdgesTested
              << " hull edges tested on average, at most " << table.maxTriangleCandidates << " and "
              << table.maxEdgeCandidates << " candidates in a cell\n";
}

TEST_P(InterpolationOnSet, WeightsAreContinuous) {
    // Along a dense path (a great circle from horizon to horizon through triangles, vertices and
    // the region outside the hull) no weight changes by more than the steepest barycentric slope
    // allows for the step: the weights have no jumps.
    const DirectionSet set = GetParam();
    const DirectionInterpolator interp(set);
    const double slope = steepestWeight(interp);
    const DirectionTable table = interp.table(32, 1024);
    const int steps = 4000;
    InterpolationWeights previous, previousTable;
    glm::vec2 previousPoint(0);
    for (int n = 0; n <= steps; ++n) {
        const float angle = glm::radians(-89.0f + 178.0f * float(n) / steps);
        // Tilted so the path does not run along the rings' symmetry axes.
        const glm::vec3 d = glm::normalize(
            glm::vec3(std::sin(angle) * 0.93f, std::sin(angle) * 0.37f + 0.05f, std::cos(angle)));
        const InterpolationWeights w = interp.weights(d),
                                   t = DirectionInterpolator::lookupTable(table, d);
        const glm::vec2 p = directionToDisc(d);
        if (n > 0) {
            // Two weights change per step (slope each), plus float rounding.
            const float bound = float(2.0 * slope * glm::length(p - previousPoint)) + 1e-5f;
            ASSERT_LE(weightDifference(w, previous), bound) << "step " << n;
            ASSERT_LE(weightDifference(t, previousTable), bound) << "step " << n;
        }
        previous = w;
        previousTable = t;
        previousPoint = p;
    }
}

TEST(DirectionInterpolation, TableNeedsAPositiveGrid) {
    try {
        DirectionInterpolator(DirectionSet::bonn81()).table(0, 1024);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "direction table: grid and width must be positive, got 0 and 1024");
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

}  // namespace OSGBTF_TEST_FILE
