// osgBTF: interpolation between measured directions.
//
// Directions are mapped to a disc with the parabolic map p = (x, y) / (1 + z) (formats.md §3; the
// map btflib and Schwartz et al. 2013 use). It is a stereographic projection, which maps circles on
// the sphere to circles in the plane, so the planar Delaunay triangulation of the mapped samples is
// the spherical Delaunay triangulation of the directions themselves. A query direction gets the
// barycentric weights of the triangle that contains it: at most 3 indices, weights >= 0 summing
// to 1, (index, 1) at a measured direction up to float rounding. Outside the convex hull of the
// samples (below theta 75 for Bonn data) it takes the closest point of the hull boundary, i.e. it
// blends the two nearest boundary samples. The weights are continuous in the direction. A set
// with no triangle (1 direction, 2, or all on one line of the disc map: a one-view capture, a
// few views along one azimuth) has a chain of segments in the hull's place and every query takes
// its closest point: constant for one direction, a blend along the segment for two.
//
// The triangulation is built in double; the weights are evaluated in float with the formulas and
// the operation order of shaders/common/directions.glsl, from the same float vertex data, so the
// CPU reference and the shaders differ only by rounding (about 1e-6).
#pragma once

#include <array>
#include <vector>

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

#include "core/Directions.h"

namespace osgBTF {

struct InterpolationWeights {
    std::array<int, 3> index{0, 0, 0};
    std::array<float, 3> weight{0, 0, 0};  ///< >= 0, sum 1; unused slots have weight 0
};

/** Parabolic disc map and its inverse. Directions below the horizon are clamped to it. */
glm::vec2 directionToDisc(const glm::vec3& direction);
glm::vec3 discToDirection(const glm::vec2& p);

/** The GPU form of a DirectionInterpolator, read by btfLookupDirections in
 *  shaders/common/directions.glsl: `grid` x `grid` cells over the square [-1, 1]^2 of the disc
 *  map, each listing the triangles that overlap it and, where part of the cell lies outside the
 *  triangulation, the hull edges that can be the nearest one for a point in it. A fragment tests
 *  only its cell's candidates, with the reference's formulas, so the result is exact (not a
 *  sampled table). RGBA float texels addressed linearly: texel a is at column a % width, row
 *  a / width (rows bottom-up, as GL textures). Layout:
 *  - texel j * grid + i, cell (i, j) (cell i spans x in [-1 + 2i/grid, -1 + 2(i+1)/grid]):
 *    (first triangle record, triangle count, first edge record, edge count);
 *  - a triangle record is 3 texels: (a.x, a.y, b.x, b.y), (c.x, c.y, 1 / area, 0),
 *    (index a, index b, index c, 0), with area = cross(b - a, c - a) > 0;
 *  - an edge record is 2 texels: (a.x, a.y, b.x, b.y), (index a, index b, index a, 0).
 *  Candidates are listed in the reference's order (triangle, then hull edge index). */
struct DirectionTable {
    int grid = 0;
    int width = 0, height = 0;
    std::vector<float> texels;      ///< width * height * 4
    int maxTriangleCandidates = 0;  ///< the most triangles any cell lists
    int maxEdgeCandidates = 0;      ///< the most hull edges any cell lists
    // What a lookup tests, mean over directions uniform on the hemisphere (shader cost counts):
    double meanTrianglesTested = 0;  ///< candidate triangles until the one holding the point
    double meanEdgesTested = 0;      ///< hull edges (all of the cell's, outside the triangulation)
    double outsideShare = 0;         ///< share of directions outside the triangulation
};

class DirectionInterpolator {
public:
    DirectionInterpolator() = default;
    /** Triangulates the set. Sets without a triangle (one direction, two, all on one line of
     *  the disc map) interpolate along the chain of segments joining them instead (hullEdges;
     *  docs/formats.md, "Interpolating few directions"). Throws Error for an empty set or two
     *  equal directions. */
    explicit DirectionInterpolator(const DirectionSet& directions);

    /** Exact weights of the triangulation (the CPU reference). Every triangle is tested. */
    InterpolationWeights weights(const glm::vec3& direction) const;

    /** The table for shaders (see DirectionTable); throws Error for grid < 1 or width < 1. */
    DirectionTable table(int grid, int width) const;
    /** What btfLookupDirections does with the table, on the CPU (the same arithmetic). */
    static InterpolationWeights lookupTable(const DirectionTable& table,
                                            const glm::vec3& direction);

    std::size_t directionCount() const { return _points.size(); }
    const std::vector<std::array<int, 3>>& triangles() const { return _triangles; }
    const std::vector<std::array<int, 2>>& hullEdges() const { return _hullEdges; }
    /** The samples in the disc map, as float (what the weights are computed from). */
    const std::vector<glm::vec2>& discPoints() const { return _discPoints; }

private:
    std::vector<glm::dvec2> _points;  ///< double, for the triangulation
    std::vector<glm::vec2> _discPoints;
    std::vector<float> _inverseArea;             ///< per triangle, from the float points
    std::vector<std::array<int, 3>> _triangles;  ///< counter-clockwise
    std::vector<std::array<int, 2>> _hullEdges;
};

}  // namespace osgBTF
