// osgBTF batch: held-out directions, to score how a method interpolates between the measured
// directions and not only how it stores them.
//
// Every method here tabulates or fits per measured direction, so a single left-out (view,
// light) pair cannot be left out of a fit on its own: what is left out is whole directions. A
// fraction a of the views and a of the lights are left out with a = 1 - sqrt(1 - f), so that the
// left-out pairs (those with a left-out view or light) are a fraction f of all pairs; with fewer
// than three views, only lights are left out (a = f). The choice is a fixed pseudo-random one
// (the same for every method and run), never the first direction (the zenith of the Bonn and
// UBO2014 sets, which the interpolation of the others needs).
#pragma once

#include <cstddef>
#include <vector>

#include "core/BtfSource.h"

namespace osgBTF::batch {

struct HoldoutSplit {
    std::vector<std::size_t> keptViews, keptLights;  ///< ascending indices
    std::vector<bool> viewLeftOut, lightLeftOut;
    /** Image indices (view * lights + light) with a left-out view or light, ascending. */
    std::vector<std::size_t> leftOutPairs;
};

/** Throws Error when fraction is outside [0, 0.5] or the sets are too small to leave any out
 *  (fewer than three lights). fraction 0: nothing left out. */
HoldoutSplit holdoutSplit(std::size_t views, std::size_t lights, double fraction);

/** The kept directions of `parent` only (it must outlive this). */
class DirectionSubsetSource : public BtfSource {
public:
    DirectionSubsetSource(const BtfSource& parent, const HoldoutSplit& split);

    void readImages(std::size_t first, std::size_t count, float* out) const override;
    void readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const override;
    std::size_t abrdfBlockTexels() const override { return _parent.abrdfBlockTexels(); }
    std::size_t imageBlock() const override { return 1; }
    bool inMemory() const override { return _parent.inMemory(); }
    std::uint64_t residentBytes() const override { return _parent.residentBytes(); }

private:
    const BtfSource& _parent;
    std::vector<std::size_t> _keptViews, _keptLights;
};

}  // namespace osgBTF::batch
