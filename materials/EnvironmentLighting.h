// osgBTF: HDR environment lighting of BTF materials (Sattler et al. 2003 section 5), the CPU side.
//
// A measured BTF value already contains the cosine term, so an environment L(d) lights a surface
// point with
//
//     T(x, v) = integral over the upper hemisphere of V(d) L(d) BTF(x, v, d) dOmega(d)
//
// (V: visibility). Every method renders a point light at d as a blend of the measured light
// directions with the interpolation weights w_i(d) (core/DirectionInterpolation.h), so the
// integral of the interpolated BTF is exactly
//
//     T(x, v) = sum_i g_i BTF(x, v, l_i),   g_i = sum_{visible texels t} w_i(d_t) L_t Omega_t
//
// (projectEnvironment: the environment projected onto the measured light directions, RGB, no
// extra cosine). Linear methods fold g into their light basis once per vertex and view (pca's
// foldPca: gamma*_kj = sum_i g_i p_ikj), after which a view costs what one point light costs; each
// such method does so in its own folder (MethodInfo::environment, materials/EnvironmentState.h).
//
// The sum runs over the texels of the lat-long map (each with its exact solid angle), not over a
// local hemicube as in Sattler et al. 2003: a texel's radiance then reaches the measured directions
// with the weights of its own centre, so one bright texel at a measured direction acts exactly as a
// point light of intensity L Omega there. Texels that straddle the horizon are split into
// horizonSplit(width) parts per side (parts about 0.7 degrees wide), so the weights of a white
// environment sum to 2 pi (within 1e-3, tested for maps 16 to 256 texels wide).
#pragma once

#include <cstdint>
#include <functional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include "core/DirectionInterpolation.h"

namespace osgBTF {

class Material;

/** A lat-long (equirectangular) HDR map in world space, +Z up (OSG's convention). Rows are
 *  bottom-up as in osg::Image: row r spans polar angles (from +Z) [pi (H-1-r)/H, pi (H-r)/H], so
 *  the top row of the image file is the sky's zenith. Column c spans azimuths [2 pi c/W,
 *  2 pi (c+1)/W], measured from +X toward +Y. `rotationDegrees` turns the whole environment about
 *  +Z (counter-clockwise seen from above): the texel at azimuth phi lights from phi + rotation. */
struct EnvironmentMap {
    int width = 0, height = 0;
    std::vector<float> rgb;  ///< width * height * 3, row-major, bottom row first
    float rotationDegrees = 0.0f;

    /** A uniform environment of one radiance (1 x 1 texel). */
    static EnvironmentMap constant(const glm::vec3& radiance);

    glm::vec3 texel(int column, int row) const;
    /** Exact solid angle of a texel of row r: (2 pi / W) (cos theta0 - cos theta1). */
    double solidAngle(int row) const;
    /** World direction of a point of the map, (u, v) in texel units from its lower left corner
     *  ((c + 0.5, r + 0.5): a texel's centre), rotation applied. */
    glm::vec3 direction(double u, double v) const;
    /** Radiance from a world direction (the texel that contains it; rotation applied). */
    glm::vec3 radiance(const glm::vec3& worldDirection) const;
    /** The map averaged down to `width` columns (height width / 2) by whole-texel boxes weighted
     *  by solid angle, so every region keeps its power; returns *this when it is not larger.
     *  Throws Error for a width < 2 or a map whose size is not a multiple. */
    EnvironmentMap downsampled(int width) const;
};

/** A surface point: position and its local frame in world space (orthonormal; z = normal). */
struct SurfaceFrame {
    glm::vec3 position{0.0f};
    glm::vec3 tangent{1, 0, 0}, bitangent{0, 1, 0}, normal{0, 0, 1};
};

/** Whether the scene blocks the ray from `origin` along the unit world direction. */
using OcclusionTest = std::function<bool(const glm::vec3& origin, const glm::vec3& direction)>;

/** Parts per side of a horizon-straddling texel of a map `width` texels wide: ceil(512 / width),
 *  at least 1. */
int horizonSplit(int width);

/** One visible piece of the environment seen from a surface point: a texel (or a part of one at
 *  the horizon) with its local direction, solid angle and radiance. */
struct EnvironmentSample {
    glm::vec3 local;     ///< unit, z > 0
    double solidAngle;   ///< steradians
    glm::vec3 radiance;  ///< the texel's
};

/** Every texel (part) of the map above the frame's horizon that `occluded` does not block (no
 *  test: all visible), in texel order. The solid angles of an unoccluded point sum to 2 pi up to
 *  the horizon split's resolution (tested: 1e-3). */
std::vector<EnvironmentSample> visibleEnvironment(const EnvironmentMap& map,
                                                  const SurfaceFrame& frame,
                                                  const OcclusionTest& occluded = {});

/** g_i of every measured light direction (RGB): sum of w_i(d) L Omega over the samples, with the
 *  exact weights (every triangle tested). */
std::vector<glm::vec3> projectEnvironment(const std::vector<EnvironmentSample>& samples,
                                          const DirectionInterpolator& lights);
/** The same through the shaders' grid table (DirectionInterpolator::lookupTable: the same
 *  weights up to float rounding, ~20x faster for the 81 Bonn directions). */
std::vector<glm::vec3> projectEnvironment(const std::vector<EnvironmentSample>& samples,
                                          const DirectionTable& table, std::size_t lightCount);

/** The brute-force reference any method can be checked against: sum over the samples of
 *  L Omega BTF(x, v, d) through the material's own evaluate(). */
glm::vec3 environmentReference(const Material& material, int x, int y, const glm::vec3& view,
                               const std::vector<EnvironmentSample>& samples);

/** Throws Error "environment: N projected values for M measured light directions" unless g
 *  holds one value per measured light direction of the material (what every fold needs). */
void checkProjected(const Material& material, const std::vector<glm::vec3>& g);

/** sum_i g_i BTF(x, v, l_i) with the material's evaluate() at the measured light directions:
 *  equal to environmentReference up to rounding for every method whose point-light rendering is
 *  linear in the light interpolation weights (pca, fmf, lpca, ...). */
glm::vec3 evaluateProjected(const Material& material, int x, int y, const glm::vec3& view,
                            const std::vector<glm::vec3>& g);

/** A representative light: a directional light standing for one region of the environment. */
struct RepresentativeLight {
    glm::vec3 direction;  ///< world, unit: the region's power-weighted centroid
    glm::vec3 power;      ///< RGB: sum of L Omega over the region (a point light's intensity)
};

/** Median-cut lights (Debevec 2005) for the methods that are not linear in the light weights:
 *  the map is split `count` (a power of two) ways, each cut across the region's longer side
 *  (width measured with the cosine of the latitude) where the summed luminance L Omega halves.
 *  Throws Error for a count that is not a power of two between 1 and 1024. */
std::vector<RepresentativeLight> medianCutLights(const EnvironmentMap& map, int count);

/** The lights, seen from a surface point, through the method's point-light evaluation: sum over
 *  lights above the horizon and not occluded of power * BTF(x, v, d). */
glm::vec3 evaluateRepresentative(const Material& material, int x, int y, const glm::vec3& view,
                                 const SurfaceFrame& frame,
                                 const std::vector<RepresentativeLight>& lights,
                                 const OcclusionTest& occluded = {});

}  // namespace osgBTF
