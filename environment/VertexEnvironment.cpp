#include "environment/VertexEnvironment.h"

#include <atomic>
#include <cmath>
#include <limits>

#include <embree3/rtcore.h>
#include <tbb/parallel_for.h>
#include <glm/geometric.hpp>
#include <osg/NodeVisitor>
#include <osg/Transform>
#include <osg/TriangleIndexFunctor>

#include "core/Error.h"
#include "core/Progress.h"
#include "materials/EnvironmentState.h"
#include "materials/Material.h"
#include "materials/ShaderInterface.h"
#include "scene/EnvironmentLight.h"

namespace osgBTF {

namespace {

/** Every osg::Geometry below a node with its matrix to the node's frame. */
class GeometryCollector : public osg::NodeVisitor {
public:
    GeometryCollector() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
    void apply(osg::Geometry& geometry) override {
        found.emplace_back(&geometry, osg::computeLocalToWorld(getNodePath()));
    }
    std::vector<std::pair<osg::ref_ptr<osg::Geometry>, osg::Matrixd>> found;
};

std::vector<std::pair<osg::ref_ptr<osg::Geometry>, osg::Matrixd>> collect(const osg::Node& node) {
    GeometryCollector collector;
    const_cast<osg::Node&>(node).accept(collector);  // reads only
    return std::move(collector.found);
}

struct TriangleIndices {
    std::vector<unsigned>* out = nullptr;
    void operator()(unsigned a, unsigned b, unsigned c) {
        out->push_back(a);
        out->push_back(b);
        out->push_back(c);
    }
};

glm::vec3 toGlm(const osg::Vec3d& v) {
    return glm::vec3(float(v.x()), float(v.y()), float(v.z()));
}

}  // namespace

struct SceneOccluder::Embree {
    RTCDevice device = nullptr;
    RTCScene scene = nullptr;
    ~Embree() {
        if (scene) rtcReleaseScene(scene);
        if (device) rtcReleaseDevice(device);
    }
};

SceneOccluder::SceneOccluder(const osg::Node& node) : _embree(new Embree) {
    _embree->device = rtcNewDevice(nullptr);
    if (!_embree->device) throw Error("visibility: Embree could not create a device");
    _embree->scene = rtcNewScene(_embree->device);
    osg::BoundingBox bounds;
    for (auto& [geometry, matrix] : collect(node)) {
        const osg::Vec3Array* vertices =
            dynamic_cast<const osg::Vec3Array*>(geometry->getVertexArray());
        if (!vertices || vertices->empty()) continue;
        osg::TriangleIndexFunctor<TriangleIndices> functor;
        std::vector<unsigned> indices;
        functor.out = &indices;
        geometry->accept(functor);
        if (indices.empty()) continue;
        RTCGeometry mesh = rtcNewGeometry(_embree->device, RTC_GEOMETRY_TYPE_TRIANGLE);
        float* v = static_cast<float*>(rtcSetNewGeometryBuffer(mesh, RTC_BUFFER_TYPE_VERTEX, 0,
                                                               RTC_FORMAT_FLOAT3, 3 * sizeof(float),
                                                               vertices->size()));
        for (std::size_t i = 0; i < vertices->size(); ++i) {
            const osg::Vec3d p = osg::Vec3d((*vertices)[i]) * matrix;
            bounds.expandBy(p);
            v[i * 3] = float(p.x()), v[i * 3 + 1] = float(p.y()), v[i * 3 + 2] = float(p.z());
        }
        unsigned* idx = static_cast<unsigned*>(
            rtcSetNewGeometryBuffer(mesh, RTC_BUFFER_TYPE_INDEX, 0, RTC_FORMAT_UINT3,
                                    3 * sizeof(unsigned), indices.size() / 3));
        std::copy(indices.begin(), indices.end(), idx);
        rtcCommitGeometry(mesh);
        rtcAttachGeometry(_embree->scene, mesh);
        rtcReleaseGeometry(mesh);
        _triangles += indices.size() / 3;
    }
    rtcCommitScene(_embree->scene);
    if (rtcGetDeviceError(_embree->device) != RTC_ERROR_NONE)
        throw Error("visibility: Embree could not build the scene");
    if (bounds.valid()) _epsilon = std::max(1e-6f, 1e-4f * float(bounds.radius()));
}

SceneOccluder::~SceneOccluder() = default;

bool SceneOccluder::occluded(const glm::vec3& origin, const glm::vec3& direction) const {
    RTCIntersectContext context;
    rtcInitIntersectContext(&context);
    RTCRay ray{};
    ray.org_x = origin.x, ray.org_y = origin.y, ray.org_z = origin.z;
    ray.dir_x = direction.x, ray.dir_y = direction.y, ray.dir_z = direction.z;
    ray.tnear = _epsilon;
    ray.tfar = std::numeric_limits<float>::infinity();
    ray.mask = ~0u;
    rtcOccluded1(_embree->scene, &context, &ray);
    return ray.tfar < 0.0f;  // Embree sets tfar to -inf on a hit
}

OcclusionTest SceneOccluder::test() const {
    return [this](const glm::vec3& o, const glm::vec3& d) { return occluded(o, d); };
}

std::vector<GeometryEnvironment> computeVertexEnvironment(const osg::Node& lit,
                                                          const osg::Node* occluders,
                                                          const DirectionSet& lights,
                                                          const EnvironmentMap& map,
                                                          const VertexEnvironmentOptions& options) {
    const DirectionInterpolator interpolator(lights);
    const DirectionTable table =
        interpolator.table(shader::kDirectionGrid, shader::kDirectionTableWidth);
    std::unique_ptr<SceneOccluder> occluder;
    if (options.visibility && occluders) occluder.reset(new SceneOccluder(*occluders));
    const OcclusionTest test = occluder ? occluder->test() : OcclusionTest();

    std::vector<GeometryEnvironment> result;
    std::size_t total = 0;
    for (auto& [geometry, matrix] : collect(lit)) {
        const osg::Vec3Array* vertices =
            dynamic_cast<const osg::Vec3Array*>(geometry->getVertexArray());
        const osg::Vec3Array* normals =
            dynamic_cast<const osg::Vec3Array*>(geometry->getNormalArray());
        if (!vertices || !normals || normals->size() != vertices->size() ||
            normals->getBinding() != osg::Array::BIND_PER_VERTEX)
            continue;
        const osg::Vec4Array* tangents = dynamic_cast<const osg::Vec4Array*>(
            geometry->getVertexAttribArray(shader::kTangentAttribute));
        if (tangents && tangents->size() != vertices->size()) tangents = nullptr;
        GeometryEnvironment entry;
        entry.geometry = geometry;
        // Normals by the inverse transpose: transform3x3(M, v) is M v, i.e. v times M transposed
        // in OSG's row-vector convention (preMult would add M's translation, as for a point).
        const osg::Matrixd normalMatrix = osg::Matrixd::inverse(matrix);
        for (std::size_t i = 0; i < vertices->size(); ++i) {
            SurfaceFrame f;
            f.position = toGlm(osg::Vec3d((*vertices)[i]) * matrix);
            f.normal = glm::normalize(
                toGlm(osg::Matrixd::transform3x3(normalMatrix, osg::Vec3d((*normals)[i]))));
            glm::vec3 t(0.0f);
            float handedness = 1.0f;
            if (tangents) {
                const osg::Vec4& a = (*tangents)[i];
                t = toGlm(osg::Matrixd::transform3x3(osg::Vec3d(a.x(), a.y(), a.z()), matrix));
                handedness = a.w() < 0.0f ? -1.0f : 1.0f;
            }
            t -= f.normal * glm::dot(f.normal, t);
            if (glm::dot(t, t) < 1e-12f)  // the shader's rule for a missing tangent
                t = std::abs(f.normal.x) < 0.9f ? glm::cross(glm::vec3(1, 0, 0), f.normal)
                                                : glm::cross(glm::vec3(0, 1, 0), f.normal);
            f.tangent = glm::normalize(t);
            f.bitangent = glm::cross(f.normal, f.tangent) * handedness;
            entry.frames.push_back(f);
        }
        entry.g.resize(vertices->size());
        entry.visibleSolidAngle.resize(vertices->size());
        total += vertices->size();
        result.push_back(std::move(entry));
    }

    Progress progress("environment", total);
    std::atomic<std::size_t> done{0};
    for (GeometryEnvironment& entry : result) {
        tbb::parallel_for(std::size_t(0), entry.frames.size(), [&](std::size_t i) {
            const std::vector<EnvironmentSample> samples =
                visibleEnvironment(map, entry.frames[i], test);
            double omega = 0;
            for (const EnvironmentSample& s : samples) omega += s.solidAngle;
            entry.visibleSolidAngle[i] = omega;
            entry.g[i] = projectEnvironment(samples, table, lights.size());
            progress.advance();
            const std::size_t n = ++done;
            if (options.progress) options.progress(n, total);
        });
    }
    progress.finish();
    return result;
}

std::vector<GeometryLightOcclusion> computeVertexLightOcclusion(
    const osg::Node& lit, const osg::Node& occluders, const std::vector<glm::vec3>& directions) {
    const SceneOccluder occluder(occluders);
    std::vector<GeometryLightOcclusion> result;
    for (auto& [geometry, matrix] : collect(lit)) {
        const osg::Vec3Array* vertices =
            dynamic_cast<const osg::Vec3Array*>(geometry->getVertexArray());
        if (!vertices) continue;
        GeometryLightOcclusion entry;
        entry.geometry = geometry;
        entry.occlusion.resize(vertices->size() * directions.size());
        const osg::Matrixd toOccluders = matrix;  // a structured binding: not capturable
        tbb::parallel_for(std::size_t(0), vertices->size(), [&](std::size_t i) {
            const glm::vec3 position = toGlm(osg::Vec3d((*vertices)[i]) * toOccluders);
            for (std::size_t k = 0; k < directions.size(); ++k)
                entry.occlusion[i * directions.size() + k] =
                    occluder.occluded(position, glm::normalize(directions[k])) ? 1.0f : 0.0f;
        });
        result.push_back(std::move(entry));
    }
    return result;
}

std::size_t applyEnvironmentLighting(osg::Node& lit, const osg::Node* occluders,
                                     const Material& material, const EnvironmentLight& light,
                                     const VertexEnvironmentOptions& options) {
    if (!hasFoldedEnvironment(material.methodName()))
        throw Error("environment: method '" + material.methodName() +
                    "' has no folded environment lighting");
    // Variants a method cannot fold (fmf with log values) fail here, before the projection.
    foldEnvironment(material, std::vector<glm::vec3>(material.lights().size(), glm::vec3(0.0f)));
    std::vector<GeometryEnvironment> lighting =
        computeVertexEnvironment(lit, occluders, material.lights(), light.projectionMap(), options);
    for (GeometryEnvironment& entry : lighting) {
        std::vector<std::vector<float>> folded(entry.g.size());
        tbb::parallel_for(std::size_t(0), entry.g.size(), [&](std::size_t i) {
            folded[i] = foldEnvironment(material, entry.g[i]);
        });
        osg::ref_ptr<osg::StateSet> state = environmentStateSet(material, folded);
        state->addUniform(light.getExposureUniform());
        entry.geometry->setStateSet(state);
    }
    return lighting.size();
}

}  // namespace osgBTF
