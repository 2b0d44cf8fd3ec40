// osgBTF: a stand-in for a synthesised coordinate map: the output covered with square blocks,
// each a copy of a randomly placed block of the sample (wrapping around its edges). Block size 1
// gives a map of independent random texels (what the equivalence tests use); larger blocks look
// like a patchwork of the sample without its period. `btf synthesize` makes the real thing.
#pragma once

#include <cstdint>

#include "core/CoordinateMap.h"

namespace osgBTF {

/** A width x height map into a sampleWidth x sampleHeight sample, blocks of `block` texels
 *  (the last row and column of blocks cut off), offsets from std::mt19937(seed): the same map
 *  for the same arguments on every platform. Throws Error for sizes or a block below 1. */
CoordinateMap makeBlockCoordinateMap(int width, int height, int sampleWidth, int sampleHeight,
                                     int block, std::uint32_t seed);

}  // namespace osgBTF
