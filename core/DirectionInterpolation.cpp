#include "core/DirectionInterpolation.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <string>

#include <glm/common.hpp>
#include <glm/ext/scalar_constants.hpp>
#include <glm/geometric.hpp>
#include <glm/vec4.hpp>

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

// Beyond this (in barycentric units) below zero a point counts as outside the triangulation;
// float rounding on an interior edge stays far below it, and just outside a hull edge the
// clamped triangle weights and the edge projection differ by less. Also in directions.glsl.
constexpr float kOutsideHull = 1e-5f;

// The float kernels below are written as shaders/common/directions.glsl writes them, operation
// for operation, so the CPU reference and the GPU round alike.
float cross2(const glm::vec2& u, const glm::vec2& v) {
    return u.x * v.y - u.y * v.x;
}

glm::vec3 barycentric(const glm::vec2& a, const glm::vec2& b, const glm::vec2& c, float inverseArea,
                      const glm::vec2& p) {
    const float w0 = cross2(c - b, p - b) * inverseArea;
    const float w1 = cross2(a - c, p - c) * inverseArea;
    return {w0, w1, 1.0f - w0 - w1};
}

/** Closest point of segment ab to p: its parameter t along ab and the squared distance. A
 *  segment of length 0 (a set of one direction) is its point, t = 0. */
glm::vec2 projectOnEdge(const glm::vec2& a, const glm::vec2& b, const glm::vec2& p) {
    const glm::vec2 e = b - a;
    const float length2 = glm::dot(e, e);
    const float t = length2 > 0.0f ? std::clamp(glm::dot(p - a, e) / length2, 0.0f, 1.0f) : 0.0f;
    const glm::vec2 q = a + t * e - p;
    return {t, glm::dot(q, q)};
}

/** The grid cell along one axis of disc coordinate x, as directions.glsl computes it. */
int gridCell(float x, int grid) {
    return std::clamp(int(std::floor((x + 1.0f) * (0.5f * float(grid)))), 0, grid - 1);
}

glm::vec3 clampAndNormalise(glm::vec3 w) {
    w = glm::max(w, glm::vec3(0.0f));
    return w / (w.x + w.y + w.z);
}

InterpolationWeights toWeights(const glm::vec3& w, int i0, int i1, int i2) {
    InterpolationWeights out;
    out.index = {i0, i1, i2};
    out.weight = {w.x, w.y, w.z};
    return out;
}

// ---- table construction (double, conservative) ------------------------------------------------

struct Rect {
    glm::dvec2 lo, hi;
};

double pointRectDistance(const glm::dvec2& p, const Rect& r) {
    const glm::dvec2 d = glm::max(glm::max(r.lo - p, p - r.hi), glm::dvec2(0.0));
    return glm::length(d);
}

double pointSegmentDistance(const glm::dvec2& p, const glm::dvec2& a, const glm::dvec2& b) {
    const glm::dvec2 e = b - a;
    const double length2 = glm::dot(e, e);
    const double t = length2 > 0.0 ? std::clamp(glm::dot(p - a, e) / length2, 0.0, 1.0) : 0.0;
    return glm::length(a + t * e - p);
}

/** Separating-axis test of a convex polygon (2 or 3 vertices) against a rectangle: the axes are
 *  the rectangle's and the polygon's edge normals. */
bool overlaps(const std::vector<glm::dvec2>& poly, const Rect& r) {
    glm::dvec2 lo(1e300), hi(-1e300);
    for (const auto& v : poly) lo = glm::min(lo, v), hi = glm::max(hi, v);
    if (hi.x < r.lo.x || lo.x > r.hi.x || hi.y < r.lo.y || lo.y > r.hi.y) return false;
    const glm::dvec2 corners[4] = {r.lo, {r.hi.x, r.lo.y}, r.hi, {r.lo.x, r.hi.y}};
    for (std::size_t e = 0; e < poly.size(); ++e) {
        const glm::dvec2 a = poly[e], b = poly[(e + 1) % poly.size()];
        const glm::dvec2 n(b.y - a.y, a.x - b.x);  // either side will do
        double polyLo = 1e300, polyHi = -1e300, rectLo = 1e300, rectHi = -1e300;
        for (const auto& v : poly) {
            polyLo = std::min(polyLo, glm::dot(n, v));
            polyHi = std::max(polyHi, glm::dot(n, v));
        }
        for (const auto& c : corners) {
            rectLo = std::min(rectLo, glm::dot(n, c));
            rectHi = std::max(rectHi, glm::dot(n, c));
        }
        if (polyHi < rectLo || rectHi < polyLo) return false;
    }
    return true;
}

double segmentRectDistance(const glm::dvec2& a, const glm::dvec2& b, const Rect& r) {
    if (overlaps({a, b}, r)) return 0.0;
    double d = std::min(pointRectDistance(a, r), pointRectDistance(b, r));
    const glm::dvec2 corners[4] = {r.lo, {r.hi.x, r.lo.y}, r.hi, {r.lo.x, r.hi.y}};
    for (const auto& c : corners) d = std::min(d, pointSegmentDistance(c, a, b));
    return d;
}

/** The segments joining points that all lie on one line (or are one point), in their order
 *  along it: (0, 0) for a single point. Throws Error for two equal points. */
std::vector<std::array<int, 2>> chainEdges(const std::vector<glm::dvec2>& points,
                                           const std::string& name) {
    const int n = int(points.size());
    if (n == 1) return {{0, 0}};
    // The line's direction: the farthest pair (the sets are small).
    int first = 0, last = 1;
    double widest = -1;
    for (int i = 0; i < n; ++i)
        for (int j = i + 1; j < n; ++j) {
            const double d = glm::length(points[j] - points[i]);
            if (d > widest) widest = d, first = i, last = j;
        }
    const glm::dvec2 axis = points[last] - points[first];
    std::vector<int> order(std::size_t(n), 0);
    for (int i = 0; i < n; ++i) order[std::size_t(i)] = i;
    std::sort(order.begin(), order.end(), [&](int a, int b) {
        return glm::dot(points[a] - points[first], axis) <
               glm::dot(points[b] - points[first], axis);
    });
    std::vector<std::array<int, 2>> edges;
    for (std::size_t k = 1; k < order.size(); ++k) {
        const int a = order[k - 1], b = order[k];
        if (glm::length(points[b] - points[a]) < 1e-12)
            throw Error("direction set '" + name + "': duplicate direction at index " +
                        std::to_string(std::max(a, b)));
        edges.push_back({a, b});
    }
    return edges;
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
    if (directions.size() == 0)
        throw Error("direction set '" + directions.name() + "': no directions to interpolate");
    for (std::size_t i = 0; i < directions.size(); ++i) {
        const glm::dvec3 d = glm::dvec3(directions.vector(i));
        _points.push_back({d.x / (1.0 + d.z), d.y / (1.0 + d.z)});
        // The float map of the sample itself, so a query at a measured direction lands on the
        // vertex bit for bit and gets weight 1 there up to the rounding of 1 / area.
        _discPoints.push_back(directionToDisc(directions.vector(i)));
    }
    if (_points.size() >= 3) _triangles = delaunay(_points);
    if (_triangles.empty()) {
        // One direction, two, or all on one line of the disc map: no triangle, and the chain of
        // segments joining them takes the hull's place. Every query then gets the closest point
        // of the chain, as it gets the closest point of the hull outside a triangulation: a
        // single direction is constant, two blend along the segment between them (in the disc
        // map, where it is close to their great arc) and beyond its ends take the nearer one.
        _hullEdges = chainEdges(_points, directions.name());
        return;
    }
    for (const auto& t : _triangles) {
        const glm::dvec2 a(_discPoints[t[0]]), b(_discPoints[t[1]]), c(_discPoints[t[2]]);
        _inverseArea.push_back(float(1.0 / cross(a, b, c)));
    }
    // Hull edges: edges used by exactly one triangle.
    std::map<std::pair<int, int>, int> count;
    for (const auto& t : _triangles)
        for (int e = 0; e < 3; ++e)
            count[{std::min(t[e], t[(e + 1) % 3]), std::max(t[e], t[(e + 1) % 3])}]++;
    for (const auto& [edge, c] : count)
        if (c == 1) _hullEdges.push_back({edge.first, edge.second});
}

InterpolationWeights DirectionInterpolator::weights(const glm::vec3& direction) const {
    const glm::vec2 p = directionToDisc(direction);
    float bestLowest = -3.0e38f;
    glm::vec3 best(0.0f);
    std::size_t bestTriangle = 0;
    for (std::size_t i = 0; i < _triangles.size(); ++i) {
        const auto& t = _triangles[i];
        const glm::vec3 w = barycentric(_discPoints[t[0]], _discPoints[t[1]], _discPoints[t[2]],
                                        _inverseArea[i], p);
        const float lowest = std::min(std::min(w.x, w.y), w.z);
        if (lowest > bestLowest) {
            bestLowest = lowest;
            best = w;
            bestTriangle = i;
        }
        if (lowest >= 0.0f) break;
    }
    if (bestLowest < -kOutsideHull) {
        // Outside the triangulation: the closest point of its boundary.
        float bestDistance = 3.0e38f;
        InterpolationWeights out;
        for (const auto& e : _hullEdges) {
            const glm::vec2 q = projectOnEdge(_discPoints[e[0]], _discPoints[e[1]], p);
            if (q.y < bestDistance) {
                bestDistance = q.y;
                out = toWeights({1.0f - q.x, q.x, 0.0f}, e[0], e[1], e[0]);
            }
        }
        return out;
    }
    const auto& t = _triangles[bestTriangle];
    return toWeights(clampAndNormalise(best), t[0], t[1], t[2]);
}

DirectionTable DirectionInterpolator::table(int grid, int width) const {
    if (grid < 1 || width < 1)
        throw Error("direction table: grid and width must be positive, got " +
                    std::to_string(grid) + " and " + std::to_string(width));
    // Cells are widened by this margin (disc units) before the overlap tests, so a point that
    // float rounding puts into a neighbouring cell still finds its triangle there.
    const double margin = 1e-4;
    DirectionTable table;
    table.grid = grid;
    std::vector<glm::dvec2> points;
    for (const auto& p : _discPoints) points.emplace_back(p);
    std::vector<glm::vec4> texels(std::size_t(grid) * grid);
    auto recordTriangle = [&](std::size_t i) {
        const auto& t = _triangles[i];
        const glm::vec2 &a = _discPoints[t[0]], &b = _discPoints[t[1]], &c = _discPoints[t[2]];
        texels.emplace_back(a.x, a.y, b.x, b.y);
        texels.emplace_back(c.x, c.y, _inverseArea[i], 0.0f);
        texels.emplace_back(float(t[0]), float(t[1]), float(t[2]), 0.0f);
    };
    auto recordEdge = [&](std::size_t i) {
        const auto& e = _hullEdges[i];
        const glm::vec2 &a = _discPoints[e[0]], &b = _discPoints[e[1]];
        texels.emplace_back(a.x, a.y, b.x, b.y);
        texels.emplace_back(float(e[0]), float(e[1]), float(e[0]), 0.0f);
    };
    for (int j = 0; j < grid; ++j) {
        for (int i = 0; i < grid; ++i) {
            Rect r{{-1.0 + 2.0 * i / grid - margin, -1.0 + 2.0 * j / grid - margin},
                   {-1.0 + 2.0 * (i + 1) / grid + margin, -1.0 + 2.0 * (j + 1) / grid + margin}};
            const std::size_t cell = std::size_t(j) * grid + i;
            texels[cell].x = float(texels.size());
            int triangles = 0;
            for (std::size_t t = 0; t < _triangles.size(); ++t) {
                const auto& v = _triangles[t];
                if (!overlaps({points[v[0]], points[v[1]], points[v[2]]}, r)) continue;
                recordTriangle(t);
                ++triangles;
            }
            // The cell lies wholly inside the triangulation when no hull edge crosses it and its
            // centre is inside; else points in it may need the nearest hull edge.
            bool crossed = false;
            for (const auto& e : _hullEdges) crossed |= overlaps({points[e[0]], points[e[1]]}, r);
            const glm::dvec2 centre = 0.5 * (r.lo + r.hi);
            bool centreInside = false;
            for (const auto& t : _triangles)
                centreInside |= cross(points[t[0]], points[t[1]], centre) >= 0 &&
                                cross(points[t[1]], points[t[2]], centre) >= 0 &&
                                cross(points[t[2]], points[t[0]], centre) >= 0;
            int edges = 0;
            const float firstEdge = float(texels.size());
            if (crossed || !centreInside) {
                // The nearest edge of any point q of the cell is no farther from q than any
                // other edge, whose distance to q is at most its distance to the farthest
                // corner (distance to a segment is convex): edges nearer than that bound are the
                // only candidates.
                const glm::dvec2 corners[4] = {r.lo, {r.hi.x, r.lo.y}, r.hi, {r.lo.x, r.hi.y}};
                double bound = 1e300;
                for (const auto& e : _hullEdges) {
                    double farthest = 0;
                    for (const auto& c : corners)
                        farthest =
                            std::max(farthest, pointSegmentDistance(c, points[e[0]], points[e[1]]));
                    bound = std::min(bound, farthest);
                }
                for (std::size_t e = 0; e < _hullEdges.size(); ++e) {
                    const auto& v = _hullEdges[e];
                    if (segmentRectDistance(points[v[0]], points[v[1]], r) > bound + margin)
                        continue;
                    recordEdge(e);
                    ++edges;
                }
            }
            texels[cell].y = float(triangles);
            texels[cell].z = firstEdge;
            texels[cell].w = float(edges);
            table.maxTriangleCandidates = std::max(table.maxTriangleCandidates, triangles);
            table.maxEdgeCandidates = std::max(table.maxEdgeCandidates, edges);
        }
    }
    if (texels.size() >= std::size_t(1) << 24)
        throw Error("direction table: " + std::to_string(texels.size()) +
                    " texels, more than float addresses reach");
    table.width = width;
    table.height = int((texels.size() + width - 1) / width);
    table.texels.assign(std::size_t(table.width) * table.height * 4, 0.0f);
    for (std::size_t k = 0; k < texels.size(); ++k)
        for (int c = 0; c < 4; ++c) table.texels[k * 4 + c] = texels[k][c];

    // How much a lookup tests, over directions uniform on the hemisphere (for ShaderCost).
    const int samples = 200;
    double tested = 0, edgesTested = 0, outside = 0, total = 0;
    for (int a = 0; a < samples; ++a)
        for (int b = 0; b < samples; ++b) {
            const double z = (a + 0.5) / samples,
                         phi = 2.0 * glm::pi<double>() * (b + 0.5) / samples;
            const double s = std::sqrt(1.0 - z * z);
            const glm::vec3 d(float(s * std::cos(phi)), float(s * std::sin(phi)), float(z));
            const glm::vec2 p = directionToDisc(d);
            const glm::vec4& cell =
                texels[std::size_t(gridCell(p.y, grid)) * grid + gridCell(p.x, grid)];
            int n = 0;
            float bestLowest = -3.0e38f;
            for (int k = 0; k < int(cell.y); ++k) {
                ++n;
                const glm::vec4 ab = texels[std::size_t(cell.x) + 3 * k];
                const glm::vec4 c = texels[std::size_t(cell.x) + 3 * k + 1];
                const glm::vec3 w = barycentric({ab.x, ab.y}, {ab.z, ab.w}, {c.x, c.y}, c.z, p);
                bestLowest = std::max(bestLowest, std::min(std::min(w.x, w.y), w.z));
                if (bestLowest >= 0.0f) break;
            }
            tested += n;
            if (bestLowest < -kOutsideHull && cell.w > 0.0f) {
                outside += 1;
                edgesTested += cell.w;
            }
            total += 1;
        }
    table.meanTrianglesTested = tested / total;
    table.meanEdgesTested = edgesTested / total;
    table.outsideShare = outside / total;
    return table;
}

InterpolationWeights DirectionInterpolator::lookupTable(const DirectionTable& table,
                                                        const glm::vec3& direction) {
    const auto texel = [&](int address) {
        const float* t = table.texels.data() + std::size_t(address) * 4;
        return glm::vec4(t[0], t[1], t[2], t[3]);
    };
    const int g = table.grid;
    const glm::vec2 p = directionToDisc(direction);
    const glm::vec4 range = texel(gridCell(p.y, g) * g + gridCell(p.x, g));
    float bestLowest = -3.0e38f;
    glm::vec3 best(0.0f);
    int bestIndices = -1;
    const int trianglesEnd = int(range.x) + 3 * int(range.y);
    for (int r = int(range.x); r < trianglesEnd; r += 3) {
        const glm::vec4 ab = texel(r), c = texel(r + 1);
        const glm::vec3 w = barycentric({ab.x, ab.y}, {ab.z, ab.w}, {c.x, c.y}, c.z, p);
        const float lowest = std::min(std::min(w.x, w.y), w.z);
        if (lowest > bestLowest) {
            bestLowest = lowest;
            best = w;
            bestIndices = r + 2;
        }
        if (lowest >= 0.0f) break;
    }
    if (bestLowest < -kOutsideHull && range.w > 0.0f) {
        float bestDistance = 3.0e38f;
        const int edgesEnd = int(range.z) + 2 * int(range.w);
        for (int r = int(range.z); r < edgesEnd; r += 2) {
            const glm::vec4 ab = texel(r);
            const glm::vec2 q = projectOnEdge({ab.x, ab.y}, {ab.z, ab.w}, p);
            if (q.y < bestDistance) {
                bestDistance = q.y;
                best = glm::vec3(1.0f - q.x, q.x, 0.0f);
                bestIndices = r + 1;
            }
        }
    } else {
        best = clampAndNormalise(best);
    }
    if (bestIndices < 0) return {};  // an empty cell: the table builder never makes one
    const glm::vec4 index = texel(bestIndices);
    return toWeights(best, int(index.x + 0.5f), int(index.y + 0.5f), int(index.z + 0.5f));
}

}  // namespace osgBTF
