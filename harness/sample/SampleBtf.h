// osgBTF: the built-in sample material, a small synthetic BTF.
//
// A woven cloth-like height field (two thread colours in a basket weave) lit with a Lambertian
// term, a glossy Blinn-Phong lobe and self-shadowing found by ray marching the height field
// toward the light; each view sees the surface point its eye ray hits first (parallax, masking).
// Values include the cosine foreshortening (as measured BTFs do) and stay in
// [0, 1] so the 8-bit UBO2003 formats hold them. It is the default input of the tools and the
// tests: structured (so view- and light-dependent effects matter), deterministic, and fast.
#pragma once

#include "core/MeasuredBtf.h"

namespace osgBTF {

struct SampleOptions {
    int width = 64;
    int height = 64;
    DirectionSet views = DirectionSet::bonn81();
    DirectionSet lights = DirectionSet::bonn81();
    Storage storage = Storage::Float;
    int threadsPerTile = 2;  ///< weave repeats across the sample
    /** 0: every weave cell identical (the sample is periodic within itself). Above 0: each cell
     *  gets its own tint and thread height, up to +-35 % and +-30 % of them at 1 (a hash of the
     *  cell, the same on every run), so the sample holds no repeat of its own: tiling it shows
     *  the sample's period, which synthesis (`btf synthesize`) is meant to hide. */
    float variation = 0.0f;
};

MeasuredBtf makeSampleBtf(const SampleOptions& options = {});

}  // namespace osgBTF
