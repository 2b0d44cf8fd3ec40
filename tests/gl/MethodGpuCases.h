// The cases of the one GPU == CPU suite over every registered method (method_gpu_test.cpp,
// EveryMethod/MethodGpu.*): each method registers its own from its folder
// (materials/<m>/test/<m>_gl_test.cpp, osgbtf_method(... GL_TESTS ...)), so that adding a method
// adds its folder and nothing here. A check that only one method has (its programs per shape, its
// foreign files) stays a plain test in that file.
#pragma once

#include <functional>
#include <string>
#include <utility>
#include <vector>

#include <glm/vec3.hpp>

#include "core/Directions.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"

namespace osgBTF::test {

/** The largest |GPU - CPU| allowed for a material rendered from (view, light). */
using Bound =
    std::function<double(const Material& material, const glm::vec3& view, const glm::vec3& light)>;

/** One fit of the built-in sample, rendered through the GPU path from each (view, light) pair and
 *  compared with the CPU (compareGpuWithCpu). */
struct GpuCase {
    /** The fit's options (FitOptions::parse). */
    std::string options;
    /** The sample fitted: 8 x 6 texels (not square: catches swapped axes), Bonn directions. */
    SampleOptions sample = sampleOfSize(8, 6);
    /** (view, light), local unit vectors. */
    std::vector<std::pair<glm::vec3, glm::vec3>> pairs;
    /** The largest |GPU - CPU| allowed for the fitted material rendered from (view, light). */
    Bound bound;
    /** Each render covers more pixels than this; < 0: not checked. */
    int morePixelsThan = 48;

    static SampleOptions sampleOfSize(int width, int height) {
        SampleOptions s;
        s.width = width;
        s.height = height;
        return s;
    }
};

/** A fixed bound. */
Bound fixedBound(double bound);
/** A bound that depends on the material alone. */
Bound materialBound(std::function<double(const Material&)> bound);
/** Direction pairs as the local unit vectors GpuCase holds. */
std::vector<std::pair<glm::vec3, glm::vec3>> vectorPairs(
    const std::vector<std::pair<Direction, Direction>>& pairs);

/** `measured` (view, light) pairs of the Bonn set, view (a i + b) mod m and light (c i + d) mod 81
 *  for i < measured, then `unmeasured`. */
std::vector<std::pair<glm::vec3, glm::vec3>> bonnPairs(
    int measured, std::size_t a, std::size_t b, std::size_t m, std::size_t c, std::size_t d,
    const std::vector<std::pair<Direction, Direction>>& unmeasured);
/** `measured` (view, light) pairs of the Bonn set spread over its 81 x 81, grazing ones included
 *  (view (37 i + 3) mod 81, light (53 i + 11) mod 81), then the first `unmeasured` (up to 5) of
 *  five pairs between the measured directions. */
std::vector<std::pair<glm::vec3, glm::vec3>> spreadPairs(int measured, int unmeasured);
/** `measured` pairs with the view on the inner 57 of the Bonn set ((9 i + 1) mod 57, the views a
 *  per-view model blends between) and the light (23 i + 5) mod 81, then `unmeasured`. */
std::vector<std::pair<glm::vec3, glm::vec3>> innerViewPairs(
    int measured, const std::vector<std::pair<Direction, Direction>>& unmeasured);

/** lpca's and lpca-revised's: 20 measured pairs spread over the index range (view 17 i mod 81,
 *  light (29 i + 5) mod 81) and 5 unmeasured ones, one beyond the measured 75 degrees. */
std::vector<std::pair<glm::vec3, glm::vec3>> clusterPairs();

/** Registers `cases` for method `name` (its kMethod); returns true (for a static initialiser). */
bool registerGpuCases(const std::string& name, std::vector<GpuCase> cases);
/** The cases registered for a method; empty when it registered none. */
const std::vector<GpuCase>& gpuCases(const std::string& name);

}  // namespace osgBTF::test
