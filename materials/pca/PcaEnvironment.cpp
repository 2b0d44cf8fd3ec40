// The per-vertex environment lighting of pca (materials/EnvironmentState.h): folding and its
// CPU reference, the math of pca_environment.frag.
#include "materials/pca/Pca.h"

#include "core/Error.h"
#include "materials/EnvironmentLighting.h"

namespace osgBTF {

std::vector<float> foldPca(const PcaMaterial& material, const std::vector<glm::vec3>& g) {
    checkProjected(material, g);
    const std::size_t lights = material.lights().size(), views = material.views().size();
    const int slots = material.components() + 1;
    std::vector<float> folded(views * std::size_t(slots) * 3, 0.0f);
    for (std::size_t j = 0; j < views; ++j)
        for (int k = 0; k < slots; ++k) {
            glm::dvec3 sum(0.0);
            for (std::size_t i = 0; i < lights; ++i) {
                const float* w = material.weights.data.data() + material.weightIndex(j, i, k);
                sum += glm::dvec3(g[i]) * glm::dvec3(w[0], w[1], w[2]);
            }
            float* out = folded.data() + (j * std::size_t(slots) + std::size_t(k)) * 3;
            for (int ch = 0; ch < 3; ++ch) out[ch] = float(sum[ch]);
        }
    return folded;
}

glm::vec3 evaluateFoldedPca(const PcaMaterial& material, const std::vector<float>& folded, int x,
                            int y, const glm::vec3& view) {
    const int c = material.components();
    const std::size_t slots = std::size_t(c + 1);
    if (folded.size() != material.views().size() * slots * 3)
        throw Error("environment: folded pca data of the wrong size");
    const InterpolationWeights wv = material.viewLookup().weights(view);
    glm::vec3 sum(0.0f);
    for (int m = 0; m < 3; ++m) {
        if (!(wv.weight[m] > 0.0f)) continue;
        const std::size_t j = std::size_t(wv.index[m]);
        const float* gamma = folded.data() + j * slots * 3;
        glm::vec3 value(gamma[c * 3], gamma[c * 3 + 1], gamma[c * 3 + 2]);
        for (int k = 0; k < c; ++k)
            value += glm::vec3(gamma[k * 3], gamma[k * 3 + 1], gamma[k * 3 + 2]) *
                     material.eigenTexel(j, k, x, y);
        sum += wv.weight[m] * value;
    }
    return sum;
}

}  // namespace osgBTF
