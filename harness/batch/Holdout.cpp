#include "harness/batch/Holdout.h"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <random>

#include "core/Error.h"

namespace osgBTF::batch {

namespace {

/** `leave` of [1, n) in a fixed pseudo-random choice; index 0 is always kept. */
std::vector<bool> chooseLeftOut(std::size_t n, std::size_t leave, unsigned seed) {
    std::vector<std::size_t> candidates(n - 1);
    std::iota(candidates.begin(), candidates.end(), std::size_t(1));
    // std::shuffle's algorithm is unspecified: a Fisher-Yates of our own gives the same choice
    // with every standard library.
    std::mt19937 random(seed);
    for (std::size_t i = candidates.size(); i > 1; --i)
        std::swap(candidates[i - 1], candidates[random() % i]);
    std::vector<bool> leftOut(n, false);
    for (std::size_t i = 0; i < leave; ++i) leftOut[candidates[i]] = true;
    return leftOut;
}

std::vector<std::size_t> kept(const std::vector<bool>& leftOut) {
    std::vector<std::size_t> indices;
    for (std::size_t i = 0; i < leftOut.size(); ++i)
        if (!leftOut[i]) indices.push_back(i);
    return indices;
}

}  // namespace

HoldoutSplit holdoutSplit(std::size_t views, std::size_t lights, double fraction) {
    if (!(fraction >= 0 && fraction <= 0.5))
        throw Error("held-out fraction " + std::to_string(fraction) + " is not in [0, 0.5]");
    HoldoutSplit split;
    split.viewLeftOut.assign(views, false);
    split.lightLeftOut.assign(lights, false);
    if (fraction > 0) {
        if (lights < 3)
            throw Error("cannot leave directions out of " + std::to_string(lights) +
                        " lights (fewer than three)");
        const bool bothAxes = views >= 3;
        const double perAxis = bothAxes ? 1 - std::sqrt(1 - fraction) : fraction;
        // At least one, and at least two kept besides: a fit needs directions to interpolate.
        const auto count = [&](std::size_t n) {
            return std::clamp<std::size_t>(std::size_t(std::lround(double(n) * perAxis)), 1, n - 2);
        };
        split.lightLeftOut = chooseLeftOut(lights, count(lights), 2014);
        if (bothAxes) split.viewLeftOut = chooseLeftOut(views, count(views), 2003);
    }
    split.keptViews = kept(split.viewLeftOut);
    split.keptLights = kept(split.lightLeftOut);
    for (std::size_t v = 0; v < views; ++v)
        for (std::size_t l = 0; l < lights; ++l)
            if (split.viewLeftOut[v] || split.lightLeftOut[l])
                split.leftOutPairs.push_back(v * lights + l);
    return split;
}

namespace {

DirectionSet subset(const DirectionSet& set, const std::vector<std::size_t>& indices) {
    std::vector<Direction> directions;
    for (const std::size_t i : indices) directions.push_back(set[i]);
    return DirectionSet(set.name() + " (held-out directions removed)", std::move(directions));
}

}  // namespace

DirectionSubsetSource::DirectionSubsetSource(const BtfSource& parent, const HoldoutSplit& split)
    : BtfSource(parent.width(), parent.height(), subset(parent.views(), split.keptViews),
                subset(parent.lights(), split.keptLights)),
      _parent(parent),
      _keptViews(split.keptViews),
      _keptLights(split.keptLights) {
    source = parent.source;
}

void DirectionSubsetSource::readImages(std::size_t first, std::size_t count, float* out) const {
    const std::size_t imageValues = texelCount() * 3;
    for (std::size_t i = 0; i < count; ++i) {
        const std::size_t image = first + i;
        const std::size_t view = _keptViews[image / _keptLights.size()];
        const std::size_t light = _keptLights[image % _keptLights.size()];
        _parent.readImages(view * _parent.lightCount() + light, 1, out + i * imageValues);
    }
}

void DirectionSubsetSource::readAbrdfs(const std::size_t* texels, std::size_t count,
                                       float* out) const {
    const std::size_t parentValues = _parent.imageCount() * 3, values = imageCount() * 3;
    std::vector<float> full(count * parentValues);
    _parent.readAbrdfs(texels, count, full.data());
    for (std::size_t t = 0; t < count; ++t) {
        const float* from = full.data() + t * parentValues;
        float* to = out + t * values;
        for (const std::size_t view : _keptViews)
            for (const std::size_t light : _keptLights) {
                const float* value = from + (view * _parent.lightCount() + light) * 3;
                to[0] = value[0];
                to[1] = value[1];
                to[2] = value[2];
                to += 3;
            }
    }
}

}  // namespace osgBTF::batch
