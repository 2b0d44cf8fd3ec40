// osgBTF: per-vertex environment lighting of a scene (Sattler et al. 2003 section 5.2): for every
// vertex of the geometries below a node, the visible environment projected onto a material's
// measured light directions (g_i, materials/EnvironmentLighting.h), with hemisphere visibility of
// the whole scene ray-cast by Embree (SceneOccluder).
//
// The paper rasterises a hemicube per vertex; casting one ray per environment texel from the
// vertex gives the same visibility without a GL context, on all cores, and lets the projection
// use each texel's exact solid angle (see EnvironmentLighting.h). The work runs on TBB worker
// threads and reports progress (callback and core/Progress.h).
#pragma once

#include <cstddef>
#include <functional>
#include <memory>
#include <vector>

#include <osg/Geometry>
#include <osg/Node>
#include <osg/ref_ptr>

#include "core/Directions.h"
#include "materials/EnvironmentLighting.h"

namespace osgBTF {

/** Ray casting against every triangle below a node (world coordinates, transforms applied),
 *  through Embree. Queries are thread-safe. */
class SceneOccluder {
public:
    /** Collects the node's triangles; throws Error if Embree cannot build a scene. */
    explicit SceneOccluder(const osg::Node& node);
    ~SceneOccluder();
    SceneOccluder(const SceneOccluder&) = delete;
    SceneOccluder& operator=(const SceneOccluder&) = delete;

    /** Whether a triangle lies along the ray (origin, unit direction) beyond a small distance
     *  (1e-4 of the scene's bounding radius: a ray leaving a vertex must not hit the vertex's own
     *  triangles). */
    bool occluded(const glm::vec3& origin, const glm::vec3& direction) const;
    OcclusionTest test() const;
    std::size_t triangleCount() const { return _triangles; }

private:
    struct Embree;
    std::unique_ptr<Embree> _embree;
    std::size_t _triangles = 0;
    float _epsilon = 1e-6f;
};

struct VertexEnvironmentOptions {
    /** Ray-cast the scene's visibility (false: every direction above the horizon is visible). */
    bool visibility = true;
    /** Called from worker threads with (vertices done, vertex count), at most once per vertex. */
    std::function<void(std::size_t, std::size_t)> progress;
};

/** The per-vertex result for one geometry: for every vertex, the projected environment g (RGB
 *  per measured light direction) and the visible solid angle (2 pi when nothing occludes it). */
struct GeometryEnvironment {
    osg::ref_ptr<osg::Geometry> geometry;
    std::vector<std::vector<glm::vec3>> g;
    std::vector<double> visibleSolidAngle;
    std::vector<SurfaceFrame> frames;  ///< world-space vertex frames the projection used
};

/** Every geometry below `lit` (its vertices transformed to world space by the transforms above
 *  them inside `lit`), occluded by everything below `occluders` (may be the same node). The
 *  frame of a vertex: its normal, and the tangent attribute osgBTF_tangent (6) if present
 *  (MaterialNode adds it), else any perpendicular. Geometries without per-vertex normals are
 *  skipped. Throws Error from the projection (e.g. an empty map). */
std::vector<GeometryEnvironment> computeVertexEnvironment(const osg::Node& lit,
                                                          const osg::Node* occluders,
                                                          const DirectionSet& lights,
                                                          const EnvironmentMap& map,
                                                          const VertexEnvironmentOptions& options);

/** Per-vertex occlusion of single directions (the representative lights of environment
 *  lighting, materials/LightVisibility.h): 1 where a ray from the vertex toward the direction
 *  hits a triangle below the occluders, else 0; occlusion[vertex * directions + k]. */
struct GeometryLightOcclusion {
    osg::ref_ptr<osg::Geometry> geometry;
    std::vector<float> occlusion;
};

/** For every geometry below `lit` (transforms inside it applied, as computeVertexEnvironment),
 *  against everything below `occluders`; directions in the same space (toward the light). */
std::vector<GeometryLightOcclusion> computeVertexLightOcclusion(
    const osg::Node& lit, const osg::Node& occluders, const std::vector<glm::vec3>& directions);

class EnvironmentLight;
class Material;

/** Environment lighting for a linear method (hasFoldedEnvironment: pca, fmf, lpca), in the scene:
 *  computeVertexEnvironment for every geometry below `lit`, folded per vertex on worker threads,
 *  and each geometry's StateSet replaced by environmentStateSet (materials/EnvironmentState.h)
 *  plus the light's exposure uniform (shared: setExposure is real-time). The material's own
 *  StateSet must be applied above the geometries (a MaterialNode holding the material does).
 *  The geometries must draw triangles (the program's geometry stage takes triangles; quads
 *  are a GL error). Run it again when the map, its rotation or the geometry changes. Returns the
 * geometries lit; throws Error for a method without folding or a light without a map. */
std::size_t applyEnvironmentLighting(osg::Node& lit, const osg::Node* occluders,
                                     const Material& material, const EnvironmentLight& light,
                                     const VertexEnvironmentOptions& options = {});

}  // namespace osgBTF
