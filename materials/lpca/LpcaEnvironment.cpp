// The per-vertex environment lighting of lpca (materials/EnvironmentState.h): folding and its
// CPU reference, the math of lpca_environment.frag.
#include "materials/lpca/Lpca.h"

#include "core/Error.h"
#include "materials/EnvironmentLighting.h"

namespace osgBTF {

std::vector<float> foldLpca(const LpcaMaterial& material, const std::vector<glm::vec3>& g) {
    checkProjected(material, g);
    std::vector<float> folded;
    folded.reserve(g.size() * 3);
    for (const glm::vec3& v : g) folded.insert(folded.end(), {v.x, v.y, v.z});
    return folded;
}

glm::vec3 evaluateFoldedLpca(const LpcaMaterial& material, const std::vector<float>& folded, int x,
                             int y, const glm::vec3& view) {
    const std::size_t lights = material.lights().size();
    if (folded.size() != lights * 3) throw Error("environment: folded lpca data of the wrong size");
    const std::size_t t = std::size_t(y) * std::size_t(material.width()) + std::size_t(x);
    const int cluster = material.clusterOf[t];
    const int components = material.components();
    const InterpolationWeights wv = material.viewLookup().weights(view);
    glm::vec3 sum(0.0f);
    for (int m = 0; m < 3; ++m) {
        if (!(wv.weight[m] > 0.0f)) continue;
        glm::vec3 value(0.0f);
        for (int q = 0; q < components; ++q) {
            const std::size_t e = material.eigenBrdfRun(cluster, q, std::size_t(wv.index[m]));
            const StoredValues& E = material.eigenBrdfs;
            glm::vec3 folded_q(0.0f);
            for (std::size_t i = 0; i < lights; ++i)
                folded_q += glm::vec3(folded[i * 3], folded[i * 3 + 1], folded[i * 3 + 2]) *
                            glm::vec3(E[e + i * 3], E[e + i * 3 + 1], E[e + i * 3 + 2]);
            value += material.weight(t, q) * folded_q;
        }
        sum += wv.weight[m] * value;
    }
    return sum;
}

}  // namespace osgBTF
