#include "environment/EnvironmentLitGroup.h"

#include <algorithm>
#include <chrono>
#include <set>

#include <osg/LightSource>
#include <osg/MatrixTransform>
#include <osg/Notify>
#include <osg/Texture2D>
#include <osgDB/ObjectWrapper>

#include "core/Error.h"
#include "core/Notify.h"
#include "environment/VertexEnvironment.h"
#include "materials/EnvironmentState.h"
#include "materials/IlluminationPca.h"
#include "materials/LightVisibility.h"
#include "scene/MaterialNode.h"

namespace osgBTF {

namespace {

/** The MaterialNodes below a node, with the transform from each (its first path) to the node,
 *  and the geometries. */
struct Collector : osg::NodeVisitor {
    Collector() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) { matrices.emplace_back(); }
    void apply(osg::Transform& transform) override {
        osg::Matrixd matrix = matrices.back();
        transform.computeLocalToWorldMatrix(matrix, this);
        matrices.push_back(matrix);
        traverse(transform);
        matrices.pop_back();
    }
    void apply(osg::Group& group) override {
        if (auto* node = dynamic_cast<MaterialNode*>(&group))
            if (std::find(nodes.begin(), nodes.end(), node) == nodes.end()) {
                nodes.push_back(node);
                placements.push_back(matrices.back());
            }
        traverse(group);
    }
    void apply(osg::Geometry& geometry) override { geometries.push_back(&geometry); }
    std::vector<osg::ref_ptr<MaterialNode>> nodes;
    std::vector<osg::Matrixd> placements;
    std::vector<osg::Geometry*> geometries;
    std::vector<osg::Matrixd> matrices;
};

/** Thrown from the progress callback to stop the work of a group being deleted. */
struct Cancelled {};

}  // namespace

/** A geometry lit through illumination PCA: its data at any rotation, and how to draw them. */
struct EnvironmentLitGroup::RotatingGeometry {
    osg::ref_ptr<osg::Geometry> geometry;
    osg::ref_ptr<const Material> material;
    std::shared_ptr<const IlluminationPca> pca;
    std::size_t stride = 0;  ///< folded values per vertex
    /** The data texture's image, once drawn: later rotations are written into it in place. */
    osg::ref_ptr<osg::Image> data;
};

struct EnvironmentLitGroup::Result {
    // nullptr: the geometry's StateSet from before (a method lit by representative lights).
    std::vector<std::pair<osg::ref_ptr<osg::Geometry>, osg::ref_ptr<osg::StateSet>>> states;
    std::string error;
    Key key;
    osg::ref_ptr<osg::Group> occluders;
    std::vector<osg::ref_ptr<osg::Node>> placed;
    std::vector<RotatingGeometry> rotating;
    // The representative lights' per-vertex occlusion, three arrays per geometry.
    std::vector<std::pair<osg::ref_ptr<osg::Geometry>, std::vector<osg::ref_ptr<osg::Vec4Array>>>>
        occlusion;  // illumination PCA on: instead of fixed states
};

EnvironmentLitGroup::EnvironmentLitGroup() {
    // traverse() runs in every update traversal (as osgParticle's systems do).
    setNumChildrenRequiringUpdateTraversal(1);
    _representative->setName("osgBTF environment representative lights");
}

EnvironmentLitGroup::EnvironmentLitGroup(const EnvironmentLitGroup& other,
                                         const osg::CopyOp& copyop)
    : osg::Group(other, copyop),
      _light(other._light),
      _representativeCount(other._representativeCount),
      _visibility(other._visibility) {
    setNumChildrenRequiringUpdateTraversal(getNumChildrenRequiringUpdateTraversal() + 1);
    _representative->setName("osgBTF environment representative lights");
}

EnvironmentLitGroup::~EnvironmentLitGroup() {
    _cancel = true;
    if (_worker.joinable()) _worker.join();
}

void EnvironmentLitGroup::setLight(EnvironmentLight* light) {
    _light = light;
    _dirty = true;
}

void EnvironmentLitGroup::setRepresentativeLights(int count) {
    _representativeCount = std::clamp(count, 1, kMaxLights);
    std::get<3>(_representativeFor) = 0;  // rebuilt in the next update
}

void EnvironmentLitGroup::setVisibility(bool on) {
    _visibility = on;
}

void EnvironmentLitGroup::setRotationSamples(int samples) {
    _rotationSamples = samples >= 2 ? samples : 0;
}

void EnvironmentLitGroup::setRotationComponents(int components) {
    _rotationComponents = std::max(1, components);
}

EnvironmentLitGroup::Key EnvironmentLitGroup::currentKey(
    std::vector<osg::ref_ptr<MaterialNode>>& nodes) {
    Key key;
    if (_light) {
        key.file = _light->getFile();
        // With illumination PCA a rotation is rebuilt from the samples, not computed again.
        key.rotation = _rotationSamples > 0 ? 0.0f : _light->getRotation();
        key.projectionWidth = _light->getProjectionWidth();
        key.mapWidth = _light->getMapWidth();
        key.mapHeight = _light->getMapHeight();
    }
    key.visibility = _visibility;
    key.rotationSamples = _rotationSamples;
    key.rotationComponents = _rotationSamples > 0 ? _rotationComponents : 0;
    Collector collector;
    for (unsigned i = 0; i < getNumChildren(); ++i) getChild(i)->accept(collector);
    nodes = collector.nodes;
    _placements.clear();
    for (std::size_t i = 0; i < nodes.size(); ++i) {
        key.materials.emplace_back(nodes[i].get(), nodes[i]->getMaterial());
        _placements[nodes[i].get()] = collector.placements[i];
    }
    return key;
}

void EnvironmentLitGroup::updateRepresentativeLights() {
    const auto wanted =
        _light && _light->hasMap()
            ? std::make_tuple(_light->getFile(), _light->getRotation(), _light->getExposure(),
                              _representativeCount, _visibility)
            : std::make_tuple(std::string(), 0.0f, -1.0f, 0, false);
    if (wanted == _representativeFor) return;
    _representativeFor = wanted;
    _representative->removeChildren(0, _representative->getNumChildren());
    if (std::get<3>(wanted) == 0) return;
    osg::ref_ptr<osg::Group> lights = representativeLightSources(*_light, _representativeCount);
    // Each light reads its per-vertex occlusion from its slot (with visibility on).
    for (unsigned k = 0; k < lights->getNumChildren() && _visibility; ++k)
        if (auto* source = dynamic_cast<osg::LightSource*>(lights->getChild(k)))
            if (int(k) < shader::kLightVisibilitySlots)
                source->setUserValue(shader::kLightVisibilityUserValue, int(k));
    _representative->addChild(lights.get());
}

std::vector<glm::vec3> EnvironmentLitGroup::representativeDirections() const {
    std::vector<glm::vec3> directions;
    struct Sources : osg::NodeVisitor {
        Sources() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
        void apply(osg::LightSource& source) override {
            int slot = -1;
            if (source.getLight() && source.getUserValue(shader::kLightVisibilityUserValue, slot) &&
                slot >= 0) {
                const osg::Vec4& p = source.getLight()->getPosition();
                if (std::size_t(slot) >= found.size()) found.resize(std::size_t(slot) + 1);
                found[std::size_t(slot)] = glm::vec3(p.x(), p.y(), p.z());
            }
            traverse(source);
        }
        std::vector<glm::vec3> found;
    } sources;
    const_cast<osg::Group&>(*_representative).accept(sources);
    directions = sources.found;
    return directions;
}

void EnvironmentLitGroup::start(const Key& key, std::vector<osg::ref_ptr<MaterialNode>> nodes) {
    _dirty = false;
    _done = false;
    _progress = 0;
    _total = 0;
    _result = std::make_unique<Result>();
    _result->key = key;
    // A geometry drawn under several MaterialNodes (a scene that embeds one model under each)
    // can hold only one per-vertex StateSet: every further node gets its own copy of its
    // subgraph (nodes and drawables; the vertex arrays stay shared).
    std::set<osg::Geometry*> seen;
    const auto geometriesOf = [](osg::Node& node) {
        Collector collector;
        node.accept(collector);
        return collector.geometries;
    };
    for (const auto& node : nodes) {
        std::vector<osg::Geometry*> geometries = geometriesOf(*node);
        if (std::any_of(geometries.begin(), geometries.end(),
                        [&](osg::Geometry* g) { return seen.count(g) != 0; })) {
            for (unsigned i = 0; i < node->getNumChildren(); ++i)
                node->setChild(i, osg::clone(node->getChild(i), osg::CopyOp::DEEP_COPY_ALL));
            geometries = geometriesOf(*node);
        }
        seen.insert(geometries.begin(), geometries.end());
        // The originals are recorded before any of our StateSets replaces them.
        for (osg::Geometry* geometry : geometries)
            if (_original.emplace(geometry, geometry->getStateSet()).second)
                // The previous frame's draw may still use the StateSet being replaced.
                geometry->setDataVariance(osg::Object::DYNAMIC);
    }
    if (!_light || !_light->hasMap()) {
        _result->error = !_light ? "no EnvironmentLight"
                         : _light->getError().empty()
                             ? "the EnvironmentLight has no map"
                             : "the EnvironmentLight has no map: " + _light->getError();
        _done = true;
        joinAndInstall();  // reports it once; the same key does not start again
        return;
    }
    // Each MaterialNode as it stands in this group: under a transform holding the transforms
    // between them (kept by the result and released on this thread, as the occluders), so its
    // vertices, frames and rays are in the occluders' space.
    std::vector<std::tuple<osg::ref_ptr<MaterialNode>, osg::ref_ptr<Material>, const osg::Node*>>
        work;
    for (const auto& node : nodes) {
        const auto placement = _placements.find(node.get());
        const osg::Node* lit = node.get();
        if (placement != _placements.end() && !placement->second.isIdentity()) {
            osg::ref_ptr<osg::MatrixTransform> placed = new osg::MatrixTransform(placement->second);
            placed->addChild(node.get());
            _result->placed.push_back(placed);
            lit = placed.get();
        }
        work.emplace_back(node, node->getMaterial(), lit);
    }
    const EnvironmentMap map = _light->projectionMap();
    const bool visibility = _visibility;
    const std::vector<glm::vec3> directions =
        visibility ? representativeDirections() : std::vector<glm::vec3>();
    const int samples = _rotationSamples, components = _rotationComponents;
    _result->key.rotation = _light->getRotation();  // the illumination PCA's rotation 0
    // The occluders: this group's children as they are now (not this group, whose
    // representative lights the update thread rebuilds while the worker runs).
    // Held by the result, so it is released here, on the update thread (releasing it removes a
    // parent from every child).
    _result->occluders = new osg::Group;
    for (unsigned i = 0; i < getNumChildren(); ++i) _result->occluders->addChild(getChild(i));
    const osg::Group* occluders = _result->occluders.get();
    OSGBTF_NOTIFY(osg::NOTICE, "osgBTF::EnvironmentLitGroup: lighting "
                                   << work.size() << " material node(s) by "
                                   << (key.file.empty() ? "an in-memory map" : key.file)
                                   << ", rotation " << key.rotation << " degrees");
    _worker =
        std::thread([this, work, map, visibility, occluders, samples, components, directions] {
            try {
                for (const auto& [node, material, lit] : work) {
                    Collector collector;
                    node->accept(collector);
                    if (!material || !foldsEnvironment(*material)) {
                        for (osg::Geometry* g : collector.geometries)
                            _result->states.emplace_back(g, nullptr);
                        if (directions.empty()) continue;
                        // Lit by the representative lights: which of them each vertex sees.
                        for (GeometryLightOcclusion& entry :
                             computeVertexLightOcclusion(*lit, *occluders, directions)) {
                            const std::size_t vertices = entry.occlusion.size() / directions.size();
                            std::vector<osg::ref_ptr<osg::Vec4Array>> arrays;
                            for (int a = 0; a < shader::kLightVisibilityAttributes; ++a)
                                arrays.push_back(new osg::Vec4Array(unsigned(vertices)));
                            for (const auto& array : arrays)  // w unused: 1, as GL's default
                                std::fill(array->begin(), array->end(), osg::Vec4(0, 0, 0, 1));
                            for (std::size_t v = 0; v < vertices; ++v)
                                for (std::size_t k = 0; k < directions.size(); ++k)
                                    (*arrays[k / 3])[v][int(k % 3)] =
                                        entry.occlusion[v * directions.size() + k];
                            _result->occlusion.emplace_back(entry.geometry, std::move(arrays));
                        }
                        continue;
                    }
                    VertexEnvironmentOptions options;
                    options.visibility = visibility;
                    options.progress = [this](std::size_t done, std::size_t total) {
                        if (_cancel) throw Cancelled();
                        _progress = done;  // per rotation sample when there are several
                        _total = total;
                    };
                    if (samples == 0) {
                        for (GeometryEnvironment& entry : computeVertexEnvironment(
                                 *lit, occluders, material->lights(), map, options)) {
                            std::vector<std::vector<float>> folded;
                            folded.reserve(entry.g.size());
                            for (const auto& g : entry.g)
                                folded.push_back(foldEnvironment(*material, g));
                            _result->states.emplace_back(entry.geometry,
                                                         environmentStateSet(*material, folded));
                        }
                        continue;
                    }
                    // Illumination PCA: every geometry's folded data, flattened, at each rotation.
                    std::vector<osg::ref_ptr<osg::Geometry>> geometries;
                    std::vector<std::vector<std::vector<float>>> flat;  // [geometry][rotation]
                    for (int a = 0; a < samples; ++a) {
                        EnvironmentMap rotated = map;
                        rotated.rotationDegrees = map.rotationDegrees + 360.0f * float(a) / samples;
                        std::vector<GeometryEnvironment> entries = computeVertexEnvironment(
                            *lit, occluders, material->lights(), rotated, options);
                        if (a == 0) {
                            for (const auto& entry : entries) geometries.push_back(entry.geometry);
                            flat.resize(entries.size());
                        }
                        for (std::size_t i = 0; i < entries.size() && i < flat.size(); ++i) {
                            std::vector<float> values;
                            for (const auto& g : entries[i].g) {
                                const std::vector<float> folded = foldEnvironment(*material, g);
                                values.insert(values.end(), folded.begin(), folded.end());
                            }
                            flat[i].push_back(std::move(values));
                        }
                    }
                    for (std::size_t i = 0; i < geometries.size(); ++i) {
                        RotatingGeometry r;
                        r.geometry = geometries[i];
                        r.material = material;
                        r.stride = foldedStride(*material);
                        int a = 0;
                        // Sample a was computed at the light's rotation at the start + 360 a / A.
                        r.pca = std::make_shared<IlluminationPca>(IlluminationPca::build(
                            [&](float) { return std::move(flat[i][std::size_t(a++)]); }, samples,
                            components));
                        _result->rotating.push_back(std::move(r));
                    }
                }
            } catch (const Cancelled&) {
                _result->error = "cancelled";
            } catch (const std::exception& e) {
                _result->error = e.what();
            }
            _done = true;
        });
}

void EnvironmentLitGroup::joinAndInstall() {
    if (_worker.joinable()) _worker.join();
    if (!_result) return;
    Result result = std::move(*_result);
    _result.reset();
    _computed = result.key;
    if (_rotationSamples > 0) _computed.rotation = 0.0f;  // what currentKey() gives then
    _everComputed = true;
    if (!result.error.empty()) {
        _error = result.error;
        OSGBTF_NOTIFY(osg::WARN, "osgBTF::EnvironmentLitGroup: " << result.error);
        return;
    }
    _error.clear();
    for (auto& [geometry, state] : result.states) {
        if (!state) {
            const auto original = _original.find(geometry.get());
            geometry->setStateSet(original == _original.end() ? nullptr : original->second.get());
            continue;
        }
        state->addUniform(_light->getExposureUniform());
        geometry->setStateSet(state.get());
    }
    const std::size_t installed = result.states.size() + result.rotating.size();
    for (auto& [geometry, arrays] : result.occlusion)
        for (int a = 0; a < shader::kLightVisibilityAttributes; ++a)
            geometry->setVertexAttribArray(shader::kLightVisibilityAttribute[a],
                                           arrays[std::size_t(a)].get(),
                                           osg::Array::BIND_PER_VERTEX);
    _rotating = std::move(result.rotating);
    _pcaRotation = result.key.rotation;
    if (!_rotating.empty()) rebuildFromIlluminationPca();
    OSGBTF_NOTIFY(osg::NOTICE, "osgBTF::EnvironmentLitGroup: lighting installed ("
                                   << installed << " geometries)");
}

void EnvironmentLitGroup::rebuildFromIlluminationPca() {
    const auto begin = std::chrono::steady_clock::now();
    _installedRotation = _light->getRotation();
    for (RotatingGeometry& r : _rotating) {
        const float degrees = _installedRotation - _pcaRotation;
        // environmentStateSet lays vertex v's values out at v * stride floats: the PCA's vector.
        if (r.data && r.data->getDataType() == GL_FLOAT &&
            r.data->getTotalSizeInBytes() >= r.pca->length() * sizeof(float)) {
            r.pca->reconstructInto(degrees, reinterpret_cast<float*>(r.data->data()));
            r.data->dirty();
            continue;
        }
        const std::vector<float> flat = r.pca->reconstruct(degrees);
        std::vector<std::vector<float>> folded(flat.size() / r.stride);
        for (std::size_t v = 0; v < folded.size(); ++v)
            folded[v].assign(flat.begin() + std::ptrdiff_t(v * r.stride),
                             flat.begin() + std::ptrdiff_t((v + 1) * r.stride));
        osg::ref_ptr<osg::StateSet> state = environmentStateSet(*r.material, folded);
        state->addUniform(_light->getExposureUniform());
        state->setDataVariance(osg::Object::DYNAMIC);
        for (const auto& attributes : state->getTextureAttributeList())
            for (const auto& [type, attribute] : attributes)
                if (auto* texture = dynamic_cast<osg::Texture2D*>(attribute.first.get()))
                    if (texture->getName() == "osgBTF_envData" && texture->getImage()) {
                        r.data = texture->getImage();
                        r.data->setDataVariance(osg::Object::DYNAMIC);
                    }
        r.geometry->setStateSet(state.get());
    }
    _rebuildMs =
        std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
}

void EnvironmentLitGroup::update() {
    updateRepresentativeLights();
    if (_worker.joinable()) {
        if (_changed) _changed();
        if (!_done) return;
        joinAndInstall();
        if (_changed) _changed();
    }
    std::vector<osg::ref_ptr<MaterialNode>> nodes;
    const Key key = currentKey(nodes);
    if (_dirty || !_everComputed || !(key == _computed))
        start(key, std::move(nodes));
    else if (!_rotating.empty() && _light && _light->getRotation() != _installedRotation)
        rebuildFromIlluminationPca();
}

void EnvironmentLitGroup::finish() {
    updateRepresentativeLights();  // before start(): it casts rays toward them
    if (!_worker.joinable()) {
        std::vector<osg::ref_ptr<MaterialNode>> nodes;
        const Key key = currentKey(nodes);
        if (_dirty || !_everComputed || !(key == _computed)) start(key, std::move(nodes));
    }
    joinAndInstall();
    if (_changed) _changed();
}

void EnvironmentLitGroup::traverse(osg::NodeVisitor& nv) {
    if (nv.getVisitorType() == osg::NodeVisitor::UPDATE_VISITOR) update();
    _representative->accept(nv);
    osg::Group::traverse(nv);
}

}  // namespace osgBTF

REGISTER_OBJECT_WRAPPER(osgBTF_EnvironmentLitGroup, new osgBTF::EnvironmentLitGroup,
                        osgBTF::EnvironmentLitGroup,
                        "osg::Object osg::Node osg::Group osgBTF::EnvironmentLitGroup") {
    ADD_OBJECT_SERIALIZER(Light, osgBTF::EnvironmentLight, nullptr);
    ADD_INT_SERIALIZER(RepresentativeLights, 8);
    ADD_BOOL_SERIALIZER(Visibility, true);
    ADD_INT_SERIALIZER(RotationSamples, 0);
    ADD_INT_SERIALIZER(RotationComponents, 5);
}
