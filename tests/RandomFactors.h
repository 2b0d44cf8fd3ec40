// Random DFMF/FMF factors for the fmf tests (CPU and GPU): the same generator on both sides, so a
// seed names the same material in materials/fmf/test/fmf_test.cpp and
// materials/fmf/test/fmf_gl_test.cpp.
#pragma once

#include <array>
#include <random>

#include "core/Directions.h"
#include "core/FactoredBtf.h"

namespace osgBTF::test {

/** Factors of the given layout on the Bonn directions: U in [-0.5, 0.5], SxV in [0, 1], S = 1;
 *  colour model 0 (callers set the model, mean and matrix they test). Source "random.btf". */
inline FactoredBtf randomFactors(FactorModel model, std::array<int, 3> ranks, int width, int height,
                                 unsigned seed) {
    FactoredBtf f;
    f.model = model;
    f.source = "random.btf";
    f.views = f.lights = DirectionSet::bonn81();
    f.width = width;
    f.height = height;
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    const int count = model == FactorModel::Fmf ? 1 : 3;
    f.factors.resize(std::size_t(count));
    const Eigen::Index images = Eigen::Index(f.imageCount());
    for (int i = 0; i < count; ++i) {
        BtfFactor& factor = f.factors[std::size_t(i)];
        const int k = ranks[std::size_t(i)];
        factor.S = Eigen::VectorXf::Ones(k);
        factor.U.resize(model == FactorModel::Fmf ? images * 3 : images, k);
        factor.SxV.resize(Eigen::Index(f.texelCount()), k);
        for (Eigen::Index j = 0; j < factor.U.size(); ++j) factor.U.data()[j] = uniform(rng) - 0.5f;
        for (Eigen::Index j = 0; j < factor.SxV.size(); ++j) factor.SxV.data()[j] = uniform(rng);
    }
    return f;
}

/** The decoding steps of a test variant on top of randomFactors: colour model (with a fixed mean
 *  and a non-orthogonal matrix, which model 3 uses), dynamic-range reduction and cosine flag. */
inline void setDecoding(FactoredBtf& f, int colorModel, std::uint32_t drr, bool cosine) {
    f.colorModel = colorModel;
    f.dynamicRangeReduction = drr;
    f.cosine = cosine;
    f.colorMean = {0.1f, 0.2f, 0.3f};
    f.colorMatrix = {0.5f, 0.2f, 0.1f, -0.3f, 0.6f, 0.2f, 0.1f, -0.2f, 0.7f};
}

}  // namespace osgBTF::test
