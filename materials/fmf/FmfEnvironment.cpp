// The per-vertex environment lighting of fmf (materials/EnvironmentState.h): folding and its
// CPU reference, the math of fmf_environment.frag.
#include "materials/fmf/Fmf.h"

#include <algorithm>

#include "core/Error.h"
#include "materials/EnvironmentLighting.h"

namespace osgBTF {

bool fmfFoldable(const FmfMaterial& material) {
    return material.factors().model == FactorModel::Fmf && !material.factors().drr();
}

std::vector<float> foldFmf(const FmfMaterial& material, const std::vector<glm::vec3>& g) {
    const FactoredBtf& f = material.factors();
    if (f.model != FactorModel::Fmf)
        throw Error(
            "environment: dfmf (a colour model per channel) has no folded environment "
            "lighting, only plain fmf");
    if (f.drr())
        throw Error(
            "environment: fmf with dynamic-range reduction (log values) is not linear "
            "in the light and has no folded environment lighting");
    checkProjected(material, g);
    const std::size_t lights = material.lights().size(), views = material.views().size();
    const std::size_t k = std::size_t(f.components(0));
    // evaluate() at a measured light l_i divides by its cosine when the data hold it: a constant
    // per light, so it scales g_i.
    std::vector<glm::dvec3> scaled(lights);
    for (std::size_t i = 0; i < lights; ++i)
        scaled[i] = glm::dvec3(g[i]) * double(f.cosineScale(material.lights().vector(i).z));
    std::vector<float> folded(views * k * 3, 0.0f);
    std::vector<double> sum(k * 3);
    std::vector<float> row(k);
    for (std::size_t j = 0; j < views; ++j) {
        std::fill(sum.begin(), sum.end(), 0.0);
        for (std::size_t i = 0; i < lights; ++i)
            for (int c = 0; c < 3; ++c) {
                if (scaled[i][c] == 0.0) continue;
                material.uRow(j * lights + i, c, row.data());
                for (std::size_t q = 0; q < k; ++q)
                    sum[q * 3 + std::size_t(c)] += scaled[i][c] * row[q];
            }
        for (std::size_t q = 0; q < k * 3; ++q) folded[j * k * 3 + q] = float(sum[q]);
    }
    return folded;
}

glm::vec3 evaluateFoldedFmf(const FmfMaterial& material, const std::vector<float>& folded, int x,
                            int y, const glm::vec3& view) {
    const FactoredBtf& f = material.factors();
    const std::size_t k = std::size_t(f.components(0));
    if (folded.size() != material.views().size() * k * 3)
        throw Error("environment: folded fmf data of the wrong size");
    std::vector<float> s(k);
    material.sxvRow(0, f.factorRow(x, y), s.data());
    const InterpolationWeights wv = material.viewLookup().weights(view);
    glm::vec3 sum(0.0f);
    for (int m = 0; m < 3; ++m) {
        if (!(wv.weight[m] > 0.0f)) continue;
        const float* u = folded.data() + std::size_t(wv.index[m]) * k * 3;
        glm::vec3 value(0.0f);
        for (std::size_t q = 0; q < k; ++q)
            value += glm::vec3(u[q * 3], u[q * 3 + 1], u[q * 3 + 2]) * s[q];
        sum += wv.weight[m] * value;
    }
    return sum;
}

}  // namespace osgBTF
