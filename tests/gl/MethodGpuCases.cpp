#include "tests/gl/MethodGpuCases.h"

#include <map>

namespace osgBTF::test {

namespace {
std::map<std::string, std::vector<GpuCase>>& registry() {
    static std::map<std::string, std::vector<GpuCase>> cases;
    return cases;
}
}  // namespace

Bound fixedBound(double bound) {
    return [bound](const Material&, const glm::vec3&, const glm::vec3&) { return bound; };
}

Bound materialBound(std::function<double(const Material&)> bound) {
    return [bound](const Material& m, const glm::vec3&, const glm::vec3&) { return bound(m); };
}

std::vector<std::pair<glm::vec3, glm::vec3>> vectorPairs(
    const std::vector<std::pair<Direction, Direction>>& pairs) {
    std::vector<std::pair<glm::vec3, glm::vec3>> vectors;
    for (const auto& [view, light] : pairs) vectors.push_back({view.toVector(), light.toVector()});
    return vectors;
}

std::vector<std::pair<glm::vec3, glm::vec3>> bonnPairs(
    int measured, std::size_t a, std::size_t b, std::size_t m, std::size_t c, std::size_t d,
    const std::vector<std::pair<Direction, Direction>>& unmeasured) {
    const DirectionSet bonn = DirectionSet::bonn81();
    std::vector<std::pair<glm::vec3, glm::vec3>> pairs;
    for (std::size_t i = 0; i < std::size_t(measured); ++i)
        pairs.push_back({bonn[(i * a + b) % m].toVector(), bonn[(i * c + d) % 81].toVector()});
    for (const auto& pair : vectorPairs(unmeasured)) pairs.push_back(pair);
    return pairs;
}

std::vector<std::pair<glm::vec3, glm::vec3>> spreadPairs(int measured, int unmeasured) {
    std::vector<std::pair<Direction, Direction>> between = {{{31.7f, 77}, {52, 200}},
                                                            {{8, 10}, {67, 300}},
                                                            {{72, 181}, {12, 5}},
                                                            {{50, 250}, {50, 70}},
                                                            {{20, 130}, {80, 320}}};
    between.resize(std::size_t(unmeasured));
    return bonnPairs(measured, 37, 3, 81, 53, 11, between);
}

std::vector<std::pair<glm::vec3, glm::vec3>> innerViewPairs(
    int measured, const std::vector<std::pair<Direction, Direction>>& unmeasured) {
    return bonnPairs(measured, 9, 1, 57, 23, 5, unmeasured);
}

std::vector<std::pair<glm::vec3, glm::vec3>> clusterPairs() {
    return bonnPairs(20, 17, 0, 81, 29, 5,
                     {{{31.7f, 77}, {52, 200}},
                      {{10, 300}, {70, 10}},
                      {{55, 133}, {5, 45}},
                      {{80, 190}, {40, 271}},
                      {{22, 11}, {66, 333}}});
}

bool registerGpuCases(const std::string& name, std::vector<GpuCase> cases) {
    std::vector<GpuCase>& all = registry()[name];
    for (GpuCase& c : cases) all.push_back(std::move(c));
    return true;
}

const std::vector<GpuCase>& gpuCases(const std::string& name) {
    static const std::vector<GpuCase> none;
    const auto found = registry().find(name);
    return found == registry().end() ? none : found->second;
}

}  // namespace osgBTF::test
