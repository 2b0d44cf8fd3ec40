// The built-in sample as the tests use it: at a chosen size, fitted by one method, and a small one
// for tests that start many processes or threads: 9 x 9 of the Bonn directions (every ninth, so
// the hemisphere is still spanned) instead of 81 x 81, which makes a UBO2003 zip of 81 members
// that loads and fits in a few milliseconds.
#pragma once

#include <string>
#include <vector>

#include "core/Directions.h"
#include "harness/sample/SampleBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "materials/MethodOptions.h"
#include "tests/TestUtil.h"

namespace osgBTF::test {

/** The built-in sample, all of its 81 x 81 directions, at width x height texels. */
inline MeasuredBtf sampleBtf(int width, int height) {
    SampleOptions options;
    options.width = width;
    options.height = height;
    return makeSampleBtf(options);
}

/** The message of the Error that fitting `btf` with `Method` and `options` throws (errorOf). */
template <class Method>
std::string fitError(const MeasuredBtf& btf, const std::string& options) {
    return errorOf([&] { Method::fit(btf, FitOptions::parse(options)); });
}

inline MeasuredBtf smallSampleBtf(int texels = 8) {
    std::vector<Direction> every9th;
    const DirectionSet bonn = DirectionSet::bonn81();
    const std::vector<Direction>& all = bonn.directions();
    for (std::size_t i = 0; i < all.size(); i += 9) every9th.push_back(all[i]);
    SampleOptions options;
    options.width = options.height = texels;
    options.views = options.lights = DirectionSet("bonn9", every9th);
    return makeSampleBtf(options);
}

/** smallSampleBtf written as a UBO2003 zip (PNG members); returns `path`. */
inline std::string writeSmallSampleZip(const std::string& path, int texels = 8) {
    writeUbo2003Zip(smallSampleBtf(texels), path, Ubo2003ImageFormat::Png);
    return path;
}

}  // namespace osgBTF::test
