// Method "ptm": the fragment shader (materials/ptm/ptm.frag) equals PtmMaterial::evaluate for both
// colour variants and both view models, at measured (view, light) pairs and between them.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include "harness/sample/SampleBtf.h"
#include "materials/ptm/Ptm.h"
#include "tests/gl/MaterialGpuCheck.h"

using namespace osgBTF;

namespace {

/** GPU and CPU run the same float operations; they may differ by the rounding of each (a GPU may
 *  fuse a multiply and an add): about 8 operations per polynomial, 3 blended views, and the view
 *  weights equal to rounding, so a few tens of u times the largest sum of |terms| (|a_k| times
 *  the colour; every monomial is at most 1). */
double tolerance(const PtmMaterial& m) {
    double largest = 0;
    for (std::size_t t = 0; t < m.texelCount(); ++t)
        for (int s = 0; s < m.slots(); ++s)
            for (int c = 0; c < 3; ++c) {
                double sum = 0;
                for (int k = 0; k < PtmMaterial::kTerms; ++k)
                    sum += std::abs(m.coefficient(t, s, k, c));
                if (m.shape().luminance)
                    sum *= std::abs(m.colour[(s * m.texelCount() + t) * 3 + c]);
                largest = std::max(largest, sum);
            }
    return 64 * std::ldexp(1.0, -24) * largest;
}

void expectGpuEqualsCpu(const std::string& options,
                        const std::vector<std::pair<Direction, Direction>>& pairs) {
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;  // not square: catches swapped axes
    const osg::ref_ptr<PtmMaterial> m =
        PtmMaterial::fit(makeSampleBtf(sample), FitOptions::parse(options));
    const double bound = tolerance(*m);
    double worst = 0;
    for (const auto& [v, l] : pairs) {
        const test::GpuCpuComparison r = test::compareGpuWithCpu(*m, v.toVector(), l.toVector());
        worst = std::max(worst, r.maxAbsDifference);
        EXPECT_GT(r.pixelsCompared, 48) << "view " << v.theta << "/" << v.phi;
        EXPECT_LE(r.maxAbsDifference, bound)
            << options << ": view " << v.theta << "/" << v.phi << " light " << l.theta << "/"
            << l.phi << ": " << r.worst;
    }
    std::cout << "ptm [" << options << "] GPU vs CPU: largest difference " << worst << " (bound "
              << bound << ") over " << pairs.size() << " (view, light) pairs\n";
}

}  // namespace

TEST(PtmGpu, RgbFrontViewMatchesCpu) {
    // The front model ignores the view: a few views, lights on every ring and between them.
    expectGpuEqualsCpu("", {{{0, 0}, {0, 0}},
                            {{30, 90}, {45, 20}},
                            {{52.5f, 171}, {75, 300}},
                            {{10, 33}, {68, 300}},
                            {{44, 333}, {82, 45}}});
}

TEST(PtmGpu, LuminancePerViewMatchesCpuAtMeasuredAndUnmeasuredDirections) {
    const DirectionSet bonn = DirectionSet::bonn81();
    std::vector<std::pair<Direction, Direction>> pairs;
    for (std::size_t i = 0; i < 6; ++i)
        pairs.push_back({bonn[(i * 9 + 1) % 57], bonn[(i * 23 + 5) % 81]});
    pairs.push_back({{31.7f, 77}, {52, 200}});
    pairs.push_back({{80, 10}, {20, 100}});  // beyond the outermost ring of views
    pairs.push_back({{66, 250}, {44, 135}});
    expectGpuEqualsCpu("colour=luminance views=all", pairs);
    // The per-view rgb branch, two pairs.
    expectGpuEqualsCpu("views=all", {{{31.7f, 77}, {52, 200}}, {{15, 60}, {45, 20}}});
}
