// osgBTF: interpolation between measured directions.
//
// Directions are mapped to a disc with the parabolic map p = (x, y) / (1 + z) (formats.md §3; the
// map btflib and seed 003 use). It is a stereographic projection, which maps circles on the
// sphere to circles in the plane, so the planar Delaunay triangulation of the mapped samples is the
// spherical Delaunay triangulation of the directions themselves. A query direction gets the
// barycentric weights of the triangle that contains it: at most 3 indices, weights >= 0 summing
// to 1, exactly (index, 1) at a measured direction. Outside the convex hull of the samples
// (below theta 75 for Bonn data) it takes the closest point of the hull boundary, i.e. it blends
// the two nearest boundary samples.
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

class DirectionInterpolator {
public:
    DirectionInterpolator() = default;
    /** Triangulates the set; throws Error if it has fewer than 3 directions or is degenerate. */
    explicit DirectionInterpolator(const DirectionSet& directions);

    /** Exact weights of the triangulation (the CPU reference). */
    InterpolationWeights weights(const glm::vec3& direction) const;

    /** A baked lookup table for shaders: resolution x resolution cells over the square
     *  [-1, 1]^2 of the disc map, cell (i, j) at p = ((i + 0.5) / R * 2 - 1, (j + 0.5) / R * 2 - 1)
     *  holding the weights of that cell centre (cells outside the disc hold the horizon's),
     *  except that the cell containing a measured direction holds exactly that direction, so
     *  lookups stay exact at the samples (resolution must separate them: 64 does for Bonn 81).
     *  indices: RGB floats (integral), weights: RGB floats; row j = bottom-up, as GL textures. */
    struct Baked {
        int resolution = 0;
        std::vector<float> indices;  ///< resolution^2 * 3
        std::vector<float> weights;  ///< resolution^2 * 3
    };
    Baked bake(int resolution) const;

    /** What a shader does with the baked table: the weights of the nearest cell centre. */
    static InterpolationWeights lookupBaked(const Baked& baked, const glm::vec3& direction);
    /** Index of the cell lookupBaked reads for this direction. */
    static std::size_t bakedCell(const Baked& baked, const glm::vec3& direction);

    std::size_t directionCount() const { return _points.size(); }
    const std::vector<std::array<int, 3>>& triangles() const { return _triangles; }
    const std::vector<glm::dvec2>& discPoints() const { return _points; }

private:
    std::vector<glm::vec3> _sampleDirections;
    std::vector<glm::dvec2> _points;
    std::vector<std::array<int, 3>> _triangles;  ///< counter-clockwise
    std::vector<std::array<int, 2>> _hullEdges;
};

}  // namespace osgBTF
