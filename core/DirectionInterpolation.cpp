#include "core/DirectionInterpolation.h"

#include <algorithm>
#include <cmath>
#include <map>

#include <glm/geometric.hpp>

#include "core/Error.h"

namespace osgBTF {

namespace {

double cross(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c) {
    return (b.x - a.x) * (c.y - a.y) - (b.y - a.y) * (c.x - a.x);
}

/** > 0 when d lies strictly inside the circumcircle of the counter-clockwise triangle abc. */
double inCircle(const glm::dvec2& a, const glm::dvec2& b, const glm::dvec2& c,
                const glm::dvec2& d) {
    const double adx = a.x - d.x, ady = a.y - d.y, bdx = b.x - d.x, bdy = b.y - d.y,
                 cdx = c.x - d.x, cdy = c.y - d.y;
    const double ad = adx * adx + ady * ady, bd = bdx * bdx + bdy * bdy, cd = cdx * cdx + cdy * cdy;
    return adx * (bdy * cd - bd * cdy) - ady * (bdx * cd - bd * cdx) + ad * (bdx * cdy - bdy * cdx);
}

/** Bowyer-Watson; the sets are small (81, 151), so the quadratic version is plenty. */
std::vector<std::array<int, 3>> delaunay(const std::vector<glm::dvec2>& input) {
    std::vector<glm::dvec2> pts = input;
    const int n = int(input.size());
    // A super-triangle far outside the unit disc.
    pts.push_back({-100.0, -100.0});
    pts.push_back({100.0, -100.0});
    pts.push_back({0.0, 100.0});
    std::vector<std::array<int, 3>> tris{{n, n + 1, n + 2}};
    // Cocircular samples (the Bonn rings) make in-circle tests exactly zero; a tolerance keeps
    // the choice consistent instead of depending on rounding.
    const double eps = 1e-12;
    for (int i = 0; i < n; ++i) {
        std::vector<std::array<int, 3>> keep;
        std::map<std::pair<int, int>, int> edgeCount;
        for (const auto& t : tris) {
            if (inCircle(pts[t[0]], pts[t[1]], pts[t[2]], pts[i]) > eps) {
                for (int e = 0; e < 3; ++e) {
                    int a = t[e], b = t[(e + 1) % 3];
                    edgeCount[{std::min(a, b), std::max(a, b)}]++;
                }
            } else {
                keep.push_back(t);
            }
        }
        std::vector<std::array<int, 3>> added;
        for (const auto& t : tris) {
            if (!(inCircle(pts[t[0]], pts[t[1]], pts[t[2]], pts[i]) > eps)) continue;
            for (int e = 0; e < 3; ++e) {
                int a = t[e], b = t[(e + 1) % 3];
                if (edgeCount[{std::min(a, b), std::max(a, b)}] == 1) added.push_back({a, b, i});
            }
        }
        if (added.empty())
            throw Error("direction set: duplicate direction at index " + std::to_string(i));
        tris = std::move(keep);
        tris.insert(tris.end(), added.begin(), added.end());
    }
    std::vector<std::array<int, 3>> result;
    for (auto t : tris) {
        if (t[0] >= n || t[1] >= n || t[2] >= n) continue;
        if (cross(pts[t[0]], pts[t[1]], pts[t[2]]) < 0) std::swap(t[1], t[2]);
        if (std::abs(cross(pts[t[0]], pts[t[1]], pts[t[2]])) < 1e-14) continue;  // sliver
        result.push_back(t);
    }
    return result;
}

}  // namespace

glm::vec2 directionToDisc(const glm::vec3& direction) {
    glm::vec3 d = direction;
    if (d.z < 0.0f) d.z = 0.0f;
    const float len = glm::length(d);
    if (!(len > 0.0f)) return {0.0f, 0.0f};
    d /= len;
    return {d.x / (1.0f + d.z), d.y / (1.0f + d.z)};
}

glm::vec3 discToDirection(const glm::vec2& p) {
    const float r2 = glm::dot(p, p);
    return glm::vec3(2.0f * p.x, 2.0f * p.y, 1.0f - r2) / (1.0f + r2);
}

DirectionInterpolator::DirectionInterpolator(const DirectionSet& directions) {
    if (directions.size() < 3)
        throw Error("direction set '" + directions.name() +
                    "': interpolation needs at least 3 directions, got " +
                    std::to_string(directions.size()));
    for (std::size_t i = 0; i < directions.size(); ++i) {
        _sampleDirections.push_back(directions.vector(i));
        const glm::dvec3 d = glm::dvec3(directions.vector(i));
        _points.push_back({d.x / (1.0 + d.z), d.y / (1.0 + d.z)});
    }
    _triangles = delaunay(_points);
    if (_triangles.empty())
        throw Error("direction set '" + directions.name() + "' is degenerate (all collinear)");
    // Hull edges: edges used by exactly one triangle.
    std::map<std::pair<int, int>, int> count;
    for (const auto& t : _triangles)
        for (int e = 0; e < 3; ++e)
            count[{std::min(t[e], t[(e + 1) % 3]), std::max(t[e], t[(e + 1) % 3])}]++;
    for (const auto& [edge, c] : count)
        if (c == 1) _hullEdges.push_back({edge.first, edge.second});
}

InterpolationWeights DirectionInterpolator::weights(const glm::vec3& direction) const {
    const glm::dvec2 p = glm::dvec2(directionToDisc(direction));
    InterpolationWeights best;
    double bestMin = -1e300;
    for (const auto& t : _triangles) {
        const glm::dvec2 &a = _points[t[0]], &b = _points[t[1]], &c = _points[t[2]];
        const double area = cross(a, b, c);
        const double w0 = cross(b, c, p) / area, w1 = cross(c, a, p) / area, w2 = 1.0 - w0 - w1;
        const double lowest = std::min({w0, w1, w2});
        if (lowest > bestMin) {
            bestMin = lowest;
            best.index = {t[0], t[1], t[2]};
            best.weight = {float(w0), float(w1), float(w2)};
        }
        if (lowest >= 0.0) break;
    }
    if (bestMin < -1e-9) {
        // Outside the hull: closest point on the boundary.
        double bestDist = 1e300;
        for (const auto& e : _hullEdges) {
            const glm::dvec2 &a = _points[e[0]], &b = _points[e[1]];
            const glm::dvec2 ab = b - a;
            const double t = std::clamp(glm::dot(p - a, ab) / glm::dot(ab, ab), 0.0, 1.0);
            const double dist = glm::length(a + t * ab - p);
            if (dist < bestDist) {
                bestDist = dist;
                best.index = {e[0], e[1], e[0]};
                best.weight = {float(1.0 - t), float(t), 0.0f};
            }
        }
        return best;
    }
    // Inside (up to rounding): clamp tiny negatives and renormalise so the contract holds.
    float sum = 0.0f;
    for (float& w : best.weight) sum += (w = std::max(w, 0.0f));
    for (float& w : best.weight) w /= sum;
    return best;
}

DirectionInterpolator::Baked DirectionInterpolator::bake(int resolution) const {
    if (resolution < 1) throw Error("interpolation table resolution must be positive");
    Baked baked;
    baked.resolution = resolution;
    baked.indices.resize(std::size_t(resolution) * resolution * 3);
    baked.weights.resize(baked.indices.size());
    for (int j = 0; j < resolution; ++j) {
        for (int i = 0; i < resolution; ++i) {
            glm::vec2 p((i + 0.5f) / resolution * 2.0f - 1.0f,
                        (j + 0.5f) / resolution * 2.0f - 1.0f);
            if (glm::length(p) > 1.0f) p = glm::normalize(p);
            const InterpolationWeights w = weights(discToDirection(p));
            const std::size_t o = (std::size_t(j) * resolution + i) * 3;
            for (int k = 0; k < 3; ++k) {
                baked.indices[o + k] = float(w.index[k]);
                baked.weights[o + k] = w.weight[k];
            }
        }
    }
    // Keep the table exact at the samples: the cell holding a measured direction returns it
    // alone, so a shader reproduces measured (view, light) pairs as the CPU reference does.
    for (std::size_t s = 0; s < _sampleDirections.size(); ++s) {
        const std::size_t o = bakedCell(baked, _sampleDirections[s]) * 3;
        baked.indices[o] = baked.indices[o + 1] = baked.indices[o + 2] = float(s);
        baked.weights[o] = 1.0f;
        baked.weights[o + 1] = baked.weights[o + 2] = 0.0f;
    }
    return baked;
}

std::size_t DirectionInterpolator::bakedCell(const Baked& baked, const glm::vec3& direction) {
    // Float arithmetic in the order the shader uses (shaders/common/directions.glsl).
    const glm::vec2 p = directionToDisc(direction);
    const int r = baked.resolution;
    const int i = std::clamp(int(std::floor((p.x + 1.0f) * 0.5f * float(r))), 0, r - 1);
    const int j = std::clamp(int(std::floor((p.y + 1.0f) * 0.5f * float(r))), 0, r - 1);
    return std::size_t(j) * r + i;
}

InterpolationWeights DirectionInterpolator::lookupBaked(const Baked& baked,
                                                        const glm::vec3& direction) {
    const std::size_t o = bakedCell(baked, direction) * 3;
    InterpolationWeights w;
    for (int k = 0; k < 3; ++k) {
        w.index[k] = int(baked.indices[o + k]);
        w.weight[k] = baked.weights[o + k];
    }
    return w;
}

}  // namespace osgBTF
