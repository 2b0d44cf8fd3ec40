// Data made from a fitted model, for tests that recover a model from its own data (laf, slaf):
// the model's values at its measured directions plus uniform noise, and a model's error on data.
#pragma once

#include <random>
#include <vector>

#include "core/ErrorMetrics.h"
#include "core/MeasuredBtf.h"
#include "materials/Material.h"

namespace osgBTF::test {

/** Data from a model (evaluateMeasured) plus uniform noise of +-amplitude. */
inline MeasuredBtf dataFromModel(const Material& model, float amplitude, unsigned seed) {
    MeasuredBtf btf(model.width(), model.height(), model.views(), model.lights());
    std::mt19937 random(seed);
    std::uniform_real_distribution<float> noise(-amplitude, amplitude);
    std::vector<float> abrdf(model.views().size() * model.lights().size() * 3);
    for (std::size_t t = 0; t < btf.texelCount(); ++t) {
        model.evaluateMeasured(t, abrdf.data());
        std::size_t i = 0;
        for (std::size_t v = 0; v < btf.viewCount(); ++v)
            for (std::size_t l = 0; l < btf.lightCount(); ++l)
                for (int c = 0; c < 3; ++c) btf.setValue(v, l, t, c, abrdf[i++] + noise(random));
    }
    return btf;
}

/** A model's error on data at the data's (its own) measured directions. */
inline ErrorSummary modelError(const MeasuredBtf& btf, const Material& model) {
    return computeError(btf, [&](std::size_t t, float* out) { model.evaluateMeasured(t, out); });
}

}  // namespace osgBTF::test
