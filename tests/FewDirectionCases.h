// The direction sets real captures have, for tests/materials_few_directions_test.cpp (CPU) and
// tests/gl/few_directions_test.cpp (GPU == CPU): one view (an RTI capture, a Bonn folder of one
// view), two views, three on one azimuth (one line of the disc map), five irregular views, and
// one view under 24 irregular lights.
#pragma once

#include <cctype>
#include <cmath>
#include <string>
#include <tuple>
#include <vector>

#include <gtest/gtest.h>

#include "core/Directions.h"

namespace osgBTF::test {

struct DirectionCase {
    std::string name;
    DirectionSet views, lights;
};

/** 24 lights from a spiral with uneven steps, none on the Bonn grid (a handheld RTI capture). */
inline DirectionSet irregularLights() {
    std::vector<Direction> lights;
    for (int i = 0; i < 24; ++i)
        lights.push_back({5.0f + 70.0f * float(i) / 23.0f,
                          std::fmod(137.5f * float(i) + 3.0f * float(i * i), 360.0f)});
    return DirectionSet("spiral24", lights);
}

inline std::vector<DirectionCase> directionCases() {
    return {
        {"oneView", DirectionSet("front", {{0, 0}}), DirectionSet::bonn81()},
        {"twoViews", DirectionSet("two", {{0, 0}, {45, 90}}), DirectionSet::bonn81()},
        {"viewsOnOneAzimuth", DirectionSet("azimuth0", {{0, 0}, {30, 0}, {60, 0}}),
         DirectionSet::bonn81()},
        {"irregularViews",
         DirectionSet("five", {{5, 10}, {25, 80}, {40, 200}, {55, 300}, {70, 140}}),
         DirectionSet::bonn81()},
        {"oneViewIrregularLights", DirectionSet("front", {{0, 0}}), irregularLights()},
    };
}

/** (method, index into directionCases()): what the per-method suites are parameterised by. */
using MethodAndDirections = std::tuple<std::string, int>;

/** "pca_oneView", "lpca_revised_twoViews": a test name for the pair. */
inline std::string methodAndDirectionsName(
    const ::testing::TestParamInfo<MethodAndDirections>& info) {
    std::string name =
        std::get<0>(info.param) + "_" + directionCases()[std::size_t(std::get<1>(info.param))].name;
    for (char& c : name)
        if (!std::isalnum(static_cast<unsigned char>(c))) c = '_';
    return name;
}

}  // namespace osgBTF::test
