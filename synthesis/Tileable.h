// osgBTF: making a measured sample tile seamlessly by linear edge blending (Sattler et al. 2003
// section 3.2: "linear edgeblending is applied, which reduces the usual tiling artifacts"; the
// paper gives no formula, ours is in synthesis/README.md).
//
// Per image, channel and row, the jump e = I(W-1) - I(0) that tiling would show between the
// right and the left edge is spread linearly over the 2b+1 steps from texel W-1-b to texel b of
// the tiled row (b = border): texel x of the left band gains e/2 (b - x)/(b + 1/2), texel W-1-x
// of the right band loses as much. Every step inside the bands changes by e/(2b+1) and the edge
// step shrinks from -e to -e/(2b+1); texels with b <= x < W-b are untouched. Then the same on the
// columns (top/bottom edges) of the result.
#pragma once

#include "core/MeasuredBtf.h"

namespace osgBTF {

/** Throws Error "--border N: ..." unless 1 <= border <= half the smaller side. */
void validateTileBorder(int border, int width, int height);

/** The default border: an eighth of the smaller side, at least 1. */
int defaultTileBorder(int width, int height);

/** The blended copy of `sample` (same size, directions and storage; float arithmetic, the half
 *  storage rounds the result). Checks memoryLimit() for the copy. */
MeasuredBtf makeTileable(const MeasuredBtf& sample, int border);

}  // namespace osgBTF
