#include "scene/MaterialNode.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <map>
#include <mutex>
#include <set>
#include <system_error>
#include <tuple>
#include <vector>

#include <osg/Camera>
#include <osg/Geometry>
#include <osg/LightSource>
#include <osg/Notify>
#include <osg/Transform>
#include <osg/View>
#include <osgDB/FileNameUtils>
#include <osgDB/FileUtils>
#include <osgShadow/ShadowMap>
#include <osgShadow/ShadowedScene>
#include <osgShadow/ViewDependentShadowMap>
#include <osgUtil/CullVisitor>
#include <osgUtil/GLObjectsVisitor>
#include <osgUtil/IncrementalCompileOperation>
#include <osgUtil/TangentSpaceGenerator>

#include "core/Error.h"
#include "core/Notify.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/LightVisibility.h"
#include "materials/MethodPrograms.h"
#include "scene/OpenMaterial.h"
#include "scene/ShadowTerminator.h"
#include "scene/SharedObjects.h"

namespace osgBTF {

namespace {

/** One StateSet per coordinate map, method, number of texture units the material binds
 *  (createCoordinateMapStateSet checks that number against the map's unit) and number of mip
 *  levels of the material (the map's chain follows them): the map's texture,
 *  uploaded once per context, and the method's map program, shared by every node drawing the
 *  map. Nodes push it at cull, so the texture's list of parent StateSets, which OSG does not
 *  guard, never changes when nodes are made or deleted on other threads. The stamp is
 *  the map itself: the entry keeps it alive, so no other map can take its address meanwhile. */
using MapStateSets = SharedObjects<std::tuple<const CoordinateMap*, std::string, std::size_t, int>,
                                   osg::StateSet, std::shared_ptr<const CoordinateMap>>;
MapStateSets& mapStateSets() {
    static auto* const cache = new MapStateSets;
    return *cache;
}

}  // namespace

std::size_t releaseUnusedSharedObjects() {
    return releaseUnusedSharedMaterials() + mapStateSets().releaseUnused() +
           releaseUnusedTerminatorStateSets();
}

namespace {

osg::ref_ptr<osg::StateSet> sharedMapStateSet(const std::shared_ptr<const CoordinateMap>& map,
                                              const Material& material) {
    const osg::StateSet& materialState = *material.sharedStateSet();
    const std::size_t units = materialState.getTextureAttributeList().size();
    const int levels = material.mipLayout().levelCount();
    return mapStateSets().get({map.get(), material.methodName(), units, levels}, map, [&] {
        return createCoordinateMapStateSet(material, materialState,
                                           createCoordinateMapTexture(material, *map).get());
    });
}

constexpr unsigned kTangentAttribute = shader::kTangentAttribute;

// ---- tangents ------------------------------------------------------------------------------

bool isPerVertex(const osg::Array* array, unsigned vertexCount) {
    return array && array->getNumElements() == vertexCount &&
           (array->getBinding() == osg::Array::BIND_PER_VERTEX ||
            array->getBinding() == osg::Array::BIND_UNDEFINED);
}

osg::Vec3 vec3At(const osg::Array& array, unsigned i) {
    switch (array.getType()) {
        case osg::Array::Vec3ArrayType:
            return static_cast<const osg::Vec3Array&>(array)[i];
        case osg::Array::Vec4ArrayType: {
            const osg::Vec4& v = static_cast<const osg::Vec4Array&>(array)[i];
            return osg::Vec3(v.x(), v.y(), v.z());
        }
        default:
            return osg::Vec3();
    }
}

/** Tangent xyz along +s and handedness w (binormal = w * cross(normal, tangent)) for one
 *  Geometry, from osgUtil::TangentSpaceGenerator run on a copy that holds only what it reads (it
 *  would otherwise rewrite indexed geometry in place, and reads normals out of bounds unless
 *  they are per vertex). */
bool addTangents(osg::Geometry& geometry) {
    if (geometry.getVertexAttribArray(kTangentAttribute)) return false;  // never twice
    const osg::Array* vertices = geometry.getVertexArray();
    if (!vertices || vertices->getNumElements() == 0) return false;
    const unsigned count = vertices->getNumElements();
    const osg::Array* texCoords = geometry.getTexCoordArray(0);
    if (!isPerVertex(texCoords, count)) {
        OSGBTF_NOTIFY(osg::INFO,
                      "osgBTF::MaterialNode: geometry '"
                          << geometry.getName()
                          << "' has no per-vertex texture coordinates on unit 0: no tangents");
        return false;
    }
    const osg::Array* normals = geometry.getNormalArray();
    const bool vertexNormals =
        isPerVertex(normals, count) && (normals->getType() == osg::Array::Vec3ArrayType ||
                                        normals->getType() == osg::Array::Vec4ArrayType);

    osg::ref_ptr<osg::Geometry> work = new osg::Geometry;
    work->setVertexArray(const_cast<osg::Array*>(vertices));
    work->setTexCoordArray(0, const_cast<osg::Array*>(texCoords));
    if (vertexNormals) work->setNormalArray(const_cast<osg::Array*>(normals));
    for (unsigned i = 0; i < geometry.getNumPrimitiveSets(); ++i)
        work->addPrimitiveSet(geometry.getPrimitiveSet(i));
    osg::ref_ptr<osgUtil::TangentSpaceGenerator> generator = new osgUtil::TangentSpaceGenerator;
    generator->generate(work.get(), 0);
    const osg::Vec4Array* t = generator->getTangentArray();
    const osg::Vec4Array* b = generator->getBinormalArray();
    const osg::Vec4Array* n = generator->getNormalArray();
    if (!t || t->size() != count || !b || b->size() != count) return false;

    osg::ref_ptr<osg::Vec4Array> tangents = new osg::Vec4Array(count);
    for (unsigned i = 0; i < count; ++i) {
        osg::Vec3 tangent((*t)[i].x(), (*t)[i].y(), (*t)[i].z());
        const osg::Vec3 binormal((*b)[i].x(), (*b)[i].y(), (*b)[i].z());
        const osg::Vec3 normal =
            vertexNormals ? vec3At(*normals, i) : osg::Vec3((*n)[i].x(), (*n)[i].y(), (*n)[i].z());
        const float length = tangent.length();
        if (!(length > 1e-12f) || !std::isfinite(length)) {
            (*tangents)[i] = osg::Vec4(0, 0, 0, 1);  // the shader then picks a frame itself
            continue;
        }
        tangent /= length;
        (*tangents)[i] = osg::Vec4(tangent, ((normal ^ tangent) * binormal) < 0 ? -1.0f : 1.0f);
    }
    geometry.setVertexAttribArray(kTangentAttribute, tangents.get(), osg::Array::BIND_PER_VERTEX);
    if (geometry.getUseDisplayList()) geometry.dirtyDisplayList();
    return true;
}

class TangentVisitor : public osg::NodeVisitor {
public:
    TangentVisitor() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
    using osg::NodeVisitor::apply;
    void apply(osg::Node& node) override {
        // A scene file can place a node below itself (fuzz/regression/scene_file/), and this
        // visitor runs while it is read (addChild, setMaterial): a node already on the path is
        // not entered again, or the traversal recurses until the stack overflows.
        const osg::NodePath& path = getNodePath();
        if (!path.empty() && std::find(path.begin(), path.end() - 1, &node) != path.end() - 1)
            return;
        traverse(node);
    }
    void apply(osg::Geometry& geometry) override {
        if (addTangents(geometry)) ++changed;
    }
    unsigned changed = 0;
};

// ---- lights --------------------------------------------------------------------------------

EyeLight toEyeLight(const osg::Light& light, const osg::Matrixd& toEye) {
    const osg::Vec4d position = osg::Vec4d(light.getPosition()) * toEye;
    const osg::Vec4& diffuse = light.getDiffuse();
    EyeLight eye;
    eye.color = osg::Vec3(diffuse.r(), diffuse.g(), diffuse.b());
    if (std::abs(position.w()) < 1e-12) {
        osg::Vec3d direction(position.x(), position.y(), position.z());
        direction.normalize();
        eye.position = osg::Vec4(osg::Vec3(direction), 0.0f);
    } else {
        eye.position = osg::Vec4(position.x() / position.w(), position.y() / position.w(),
                                 position.z() / position.w(), 1.0f);
    }
    return eye;
}

/** Every LightSource below the root, its light in eye space, as the CullVisitor would place it:
 *  Transforms compose as in cull (ABSOLUTE_RF ones restart from the eye), ABSOLUTE_RF light
 *  sources are in eye space, nested Cameras are skipped (their subgraphs have their own
 *  lights), switched-off children and nodes outside the traversal mask are ignored. */
class LightCollector : public osg::NodeVisitor {
public:
    LightCollector(const osg::Matrixd& rootModelView, unsigned traversalMask)
        : osg::NodeVisitor(TRAVERSE_ACTIVE_CHILDREN) {
        setTraversalMask(traversalMask);
        _matrices.push_back(rootModelView);
    }
    void apply(osg::Camera&) override {}
    void apply(osg::Transform& transform) override {
        osg::Matrixd matrix = _matrices.back();
        transform.computeLocalToWorldMatrix(matrix, this);
        _matrices.push_back(matrix);
        traverse(transform);
        _matrices.pop_back();
    }
    void apply(osg::LightSource& source) override {
        if (const osg::Light* light = dynamic_cast<const osg::Light*>(source.getLight())) {
            lights.push_back(
                toEyeLight(*light, source.getReferenceFrame() == osg::LightSource::ABSOLUTE_RF
                                       ? osg::Matrixd::identity()
                                       : _matrices.back()));
            int slot = -1;
            if (source.getUserValue(shader::kLightVisibilityUserValue, slot) && slot >= 0 &&
                slot < shader::kLightVisibilitySlots)
                lights.back().visibilitySlot = slot;
        }
        traverse(source);
    }
    std::vector<EyeLight> lights;

private:
    std::vector<osg::Matrixd> _matrices;
};

}  // namespace

unsigned generateTangents(osg::Node& node) {
    TangentVisitor visitor;
    node.accept(visitor);
    return visitor.changed;
}

// ---- MaterialNode --------------------------------------------------------------------------

MaterialNode::MaterialNode()
    : _terminatorAlpha(kDefaultTerminatorAlpha), _terminatorSoftness(kDefaultTerminatorSoftness) {
    createNodeState();
}

MaterialNode::MaterialNode(Material* material) : MaterialNode() {
    setMaterial(material);
}

MaterialNode::MaterialNode(const MaterialNode& other, const osg::CopyOp& copyop)
    : osg::Group(other, copyop),
      _material(other._material),
      _materialFile(other._materialFile),
      _materialError(other._materialError),
      _textureScale(other._textureScale),
      _map(other._map),
      _mapFile(other._mapFile),
      _mapError(other._mapError),
      _mapStateSet(other._mapStateSet),
      _terminator(other._terminator),
      _terminatorAlpha(other._terminatorAlpha),
      _terminatorSoftness(other._terminatorSoftness),
      _shadowLight(other._shadowLight) {
    // The material (and its shared StateSet) and the map state are shared; per-node and
    // per-camera state is not.
    createNodeState();
}

void MaterialNode::createNodeState() {
    _textureScaleUniform = new osg::Uniform("osgBTF_textureScale", _textureScale);
    _nodeStateSet = new osg::StateSet;
    _nodeStateSet->addUniform(_textureScaleUniform.get());
    _terminatorUniform = new osg::Uniform(shader::kTerminator, false);
    _terminatorAlphaUniform = new osg::Uniform(shader::kTerminatorAlpha, 0.0f);
    _nodeStateSet->addUniform(_terminatorUniform.get());
    _nodeStateSet->addUniform(_terminatorAlphaUniform.get());
    updateTerminatorState();
}

void MaterialNode::updateTerminatorState() {
    // The texture's unit is fixed; a method that binds a texture there itself keeps it, and the
    // node draws that material without the terminator (reported when the material is set).
    const osg::StateSet* material = materialStateSet();
    const bool unitFree =
        !material || int(material->getTextureAttributeList().size()) <= shader::kTerminatorUnit;
    const bool on = _terminator && unitFree;
    _terminatorUniform->set(on);
    _terminatorAlphaUniform->set(float(osg::DegreesToRadians(double(_terminatorAlpha))));
    _terminatorStateSet = on ? terminatorStateSet(_terminatorSoftness) : nullptr;
}

void MaterialNode::setShadowTerminator(bool enabled) {
    _terminator = enabled;
    updateTerminatorState();
}

void MaterialNode::setTerminatorAlpha(float degrees) {
    _terminatorAlpha = degrees;
    updateTerminatorState();
}

void MaterialNode::setTerminatorSoftness(float softness) {
    _terminatorSoftness = std::clamp(softness, 0.0f, 1.0f);
    updateTerminatorState();
}

MaterialNode::~MaterialNode() {
    _material = nullptr;
    releaseUnusedSharedObjects();  // the GPU memory of a material nothing else draws goes now
}

void MaterialNode::setMaterial(Material* material) {
    _material = material;
    releaseUnusedSharedObjects();
    _materialError.clear();
    if (material) {
        _materialFile = material->sourceFile;
        try {
            material->sharedStateSet();  // builds the program and textures now, not in cull
        } catch (const std::exception& e) {
            _materialError = e.what();
            OSGBTF_NOTIFY(osg::WARN, "osgBTF::MaterialNode: " << e.what());
            _material = nullptr;
        }
    } else {
        _materialFile.clear();
    }
    updateMapState();
    updateTerminatorState();
    if (_terminator && _material &&
        int(_material->sharedStateSet()->getTextureAttributeList().size()) >
            shader::kTerminatorUnit)
        OSG_WARN << "osgBTF::MaterialNode: method '" << _material->methodName()
                 << "' uses texture unit " << shader::kTerminatorUnit
                 << ", which the shadow terminator needs (the node draws it without)" << std::endl;
    generateTangents();
}

bool MaterialNode::setMaterialFile(const std::string& file, const osgDB::Options* options) {
    if (osgDB::getLowerCaseFileExtension(file) == "bsvtf") {
        // A streamed material, named by its tile set's index: the StreamingGroup above the node
        // streams it and gives it to the node (its serializer, osgdb_osgbtf), not a
        // file read here. Until then the node draws its children with their own state, quietly.
        _material = nullptr;
        _materialFile = file;
        _materialError = file + ": a streamed material (its StreamingGroup provides it)";
        updateMapState();
        return false;
    }
    const std::string path = osgDB::findDataFile(file, options);
    osg::ref_ptr<Material> material;
    std::string problem;
    if (path.empty()) {
        problem = file + ": no such file";
    } else {
        try {
            material = loadSharedMaterial(path);
        } catch (const std::exception& e) {
            problem = e.what();
        }
    }
    if (material) {
        setMaterial(material.get());
        _materialFile = file;
        return _material.valid();
    }
    _material = nullptr;
    _materialFile = file;
    _materialError = problem;
    updateMapState();
    OSGBTF_NOTIFY(osg::WARN, "osgBTF::MaterialNode: "
                                 << problem
                                 << " (the node draws its children without the material)");
    return false;
}

bool MaterialNode::setCoordinateMap(std::shared_ptr<const CoordinateMap> map) {
    _map = std::move(map);
    _mapFile.clear();
    _mapError.clear();
    updateMapState();
    return _mapError.empty();
}

bool MaterialNode::setCoordinateMapFile(const std::string& file, const osgDB::Options* options) {
    if (file.empty()) return setCoordinateMap(nullptr);
    const std::string path = osgDB::findDataFile(file, options);
    std::string problem;
    std::shared_ptr<const CoordinateMap> map;
    if (path.empty()) {
        problem = file + ": no such file";
    } else {
        try {
            map = loadSharedCoordinateMap(path);
        } catch (const std::exception& e) {
            problem = e.what();
        }
    }
    _map = map;
    _mapFile = file;
    _mapError = problem;
    if (!map) {
        _mapStateSet = nullptr;
        OSGBTF_NOTIFY(osg::WARN,
                      "osgBTF::MaterialNode: " << problem
                                               << " (the node draws the material without the map)");
        return false;
    }
    updateMapState();
    return _mapError.empty();
}

void MaterialNode::updateMapState() {
    _mapStateSet = nullptr;
    if (!_map) return;  // keeps the error of a map file that could not be read
    _mapError.clear();
    if (!_material) return;  // checked when a material comes
    try {
        checkCoordinateMapMatches(*_material, *_map,
                                  _mapFile.empty() ? std::string("coordinate map") : _mapFile);
        _mapStateSet = sharedMapStateSet(_map, *_material);
    } catch (const std::exception& e) {
        _mapError = e.what();
        OSGBTF_NOTIFY(osg::WARN,
                      "osgBTF::MaterialNode: " << _mapError
                                               << " (the node draws the material without the map)");
    }
}

void MaterialNode::setTextureScale(float scale) {
    _textureScale = scale;
    _textureScaleUniform->set(scale);
}

unsigned MaterialNode::generateTangents() {
    return osgBTF::generateTangents(*this);
}

namespace {

/** Whether `child` is `node` or one of its ancestors: below `node` it would close a cycle, which
 *  every traversal follows until the stack overflows and whose references keep it alive. A
 *  scene file closes one by naming an enclosing node's UniqueID among its children
 *  (fuzz/regression/scene_file/). Warns when it would. */
bool closesCycle(const osg::Node& node, const osg::Node* child) {
    if (!child) return false;
    std::vector<const osg::Node*> todo{&node};
    std::set<const osg::Node*> seen;
    while (!todo.empty()) {
        const osg::Node* n = todo.back();
        todo.pop_back();
        if (n == child) {
            OSG_WARN << "osgBTF::MaterialNode: a child that is the node itself or one of its "
                        "parents would make a cycle; it is left out"
                     << std::endl;
            return true;
        }
        if (!seen.insert(n).second) continue;
        for (const osg::Group* parent : n->getParents()) todo.push_back(parent);
    }
    return false;
}

}  // namespace

bool MaterialNode::addChild(osg::Node* child) {
    if (closesCycle(*this, child) || !osg::Group::addChild(child)) return false;
    osgBTF::generateTangents(*child);
    return true;
}

bool MaterialNode::insertChild(unsigned int index, osg::Node* child) {
    if (closesCycle(*this, child) || !osg::Group::insertChild(index, child)) return false;
    osgBTF::generateTangents(*child);
    return true;
}

bool MaterialNode::replaceChild(osg::Node* origChild, osg::Node* newChild) {
    if (closesCycle(*this, newChild) || !osg::Group::replaceChild(origChild, newChild))
        return false;
    if (newChild) osgBTF::generateTangents(*newChild);
    return true;
}

bool MaterialNode::setChild(unsigned int index, osg::Node* node) {
    if (closesCycle(*this, node) || !osg::Group::setChild(index, node)) return false;
    if (node) osgBTF::generateTangents(*node);
    return true;
}

std::vector<EyeLight> MaterialNode::collectLights(osgUtil::CullVisitor& cv) {
    // The scene is what the innermost camera being culled sees: the subgraph below the last
    // Camera on the node path, or everything the cull started from. Its model-view matrix is
    // recovered from this node's: current = path * root, path being the Transforms in between
    // as the CullVisitor composed them. An ABSOLUTE_RF Transform in between hides the root's
    // matrix; then the camera's view matrix stands in for it (exact for a top-level camera).
    const osg::NodePath& path = cv.getNodePath();
    std::size_t root = 0;
    for (std::size_t i = 0; i < path.size(); ++i)
        if (dynamic_cast<const osg::Camera*>(path[i])) root = i + 1;
    osg::Camera* camera = cv.getCurrentCamera();
    osg::Matrixd pathMatrix;
    bool recoverable = true;
    for (std::size_t i = root; i < path.size(); ++i) {
        const osg::Transform* transform = path[i]->asTransform();
        if (!transform) continue;
        if (transform->getReferenceFrame() != osg::Transform::RELATIVE_RF) recoverable = false;
        transform->computeLocalToWorldMatrix(pathMatrix, &cv);
    }
    osg::Matrixd rootModelView = camera ? camera->getViewMatrix() : osg::Matrixd::identity();
    osg::Matrixd inversePath;
    if (recoverable && cv.getModelViewMatrix() && inversePath.invert(pathMatrix))
        rootModelView = inversePath * osg::Matrixd(*cv.getModelViewMatrix());

    std::vector<EyeLight> lights;
    if (root < path.size()) {
        LightCollector collector(rootModelView, cv.getTraversalMask());
        path[root]->accept(collector);
        lights = std::move(collector.lights);
    }
    if (lights.empty()) {
        // No LightSource: the light osgViewer adds itself (View::setLightingMode), as SceneView
        // places it: a headlight in eye space, a sky light in world space.
        osg::Camera* master = cv.getRenderStage() ? cv.getRenderStage()->getCamera() : camera;
        osg::View* view = master ? master->getView() : nullptr;
        if (view && view->getLight() && view->getLightingMode() != osg::View::NO_LIGHT)
            lights.push_back(
                toEyeLight(*view->getLight(), view->getLightingMode() == osg::View::SKY_LIGHT
                                                  ? master->getViewMatrix()
                                                  : osg::Matrixd::identity()));
        else
            lights.push_back({osg::Vec4(0, 0, 1, 0), osg::Vec3(1, 1, 1)});
    }
    if (lights.size() > std::size_t(kMaxLights)) {
        OSGBTF_NOTIFY(osg::INFO, "osgBTF::MaterialNode: " << lights.size()
                                                          << " lights, the shaders use the first "
                                                          << kMaxLights);
        lights.resize(kMaxLights);
    }
    return lights;
}

osg::StateSet* MaterialNode::lightStateSet(osgUtil::CullVisitor& cv) {
    const osg::FrameStamp* stamp = cv.getFrameStamp();
    osg::Camera* camera = cv.getCurrentCamera();
    std::lock_guard<std::mutex> lock(_lightsMutex);
    pruneCameraLights();
    CameraLights& entry = _lightsPerCamera[camera];
    if (!entry.stateSet) {
        entry.camera = camera;
        entry.stateSet = new osg::StateSet;
        entry.stateSet->setDataVariance(osg::Object::DYNAMIC);
        entry.count = new osg::Uniform("osgBTF_lightCount", 0);
        entry.positions =
            new osg::Uniform(osg::Uniform::FLOAT_VEC4, "osgBTF_lightPosition", kMaxLights);
        entry.colors = new osg::Uniform(osg::Uniform::FLOAT_VEC3, "osgBTF_lightColor", kMaxLights);
        entry.visibilitySlots =
            new osg::Uniform(osg::Uniform::INT, shader::kLightVisibilitySlot, kMaxLights);
        for (osg::Uniform* uniform : {entry.count.get(), entry.positions.get(), entry.colors.get(),
                                      entry.visibilitySlots.get()}) {
            uniform->setDataVariance(osg::Object::DYNAMIC);
            entry.stateSet->addUniform(uniform);
        }
    } else if (stamp && entry.frameNumber == stamp->getFrameNumber()) {
        return entry.stateSet.get();  // culled again in this frame (several parents)
    }
    entry.frameNumber = stamp ? stamp->getFrameNumber() : ~0u;
    const std::vector<EyeLight> lights = collectLights(cv);
    entry.count->set(int(lights.size()));
    entry.lights = lights;
    for (int i = 0; i < kMaxLights; ++i) {
        const bool used = i < int(lights.size());
        entry.positions->setElement(i, used ? lights[i].position : osg::Vec4());
        entry.colors->setElement(i, used ? lights[i].color : osg::Vec3());
        entry.visibilitySlots->setElement(unsigned(i), used ? lights[i].visibilitySlot : -1);
    }
    return entry.stateSet.get();
}

namespace {

/** Which of `lights` a technique given no light of its own shadows: the last osg::Light of the
 *  render stage's positional state (ShadowMap's choice, and ViewDependentShadowMap's first light),
 *  only lights numbered `lightNum` when it is >= 0 (ShadowSettings::setLightNum), found after
 *  culling the shadowed scene; here the last one culled so far (the same when the scene's
 *  LightSources come before its models), matched to `lights` by its eye-space position. Else the
 *  last of `lights`. */
int techniqueLight(osgUtil::CullVisitor& cv, const std::vector<EyeLight>& lights, int lightNum) {
    const int last = int(lights.size()) - 1;
    osgUtil::RenderStage* stage = cv.getRenderStage();
    if (!stage || !stage->getPositionalStateContainer()) return last;
    const osg::Light* selected = nullptr;
    const osg::RefMatrix* matrix = nullptr;
    for (const auto& [attribute, at] : stage->getPositionalStateContainer()->getAttrMatrixList())
        if (const auto* light = dynamic_cast<const osg::Light*>(attribute.get()))
            if (lightNum < 0 || light->getLightNum() == lightNum) {
                selected = light;
                matrix = at.get();
            }
    if (!selected) return last;
    const EyeLight eye = toEyeLight(*selected, matrix ? osg::Matrixd(*matrix) : osg::Matrixd());
    for (int i = last; i >= 0; --i) {
        const osg::Vec4 d = lights[std::size_t(i)].position - eye.position;
        if (d.length2() < 1e-8f * std::max(1.0f, eye.position.length2())) return i;
    }
    return last;
}

/** The depth texture a technique MaterialNode supports samples for this cull, its TexGen unit
 *  and the osg::Light number it shadows (-1: any); no texture under other techniques, and when
 *  the technique makes no usable depth map (ShadowSettings' debug draw, units from 8). */
struct TechniqueShadow {
    bool supported = false;
    osg::Texture* depth = nullptr;
    int unit = -1;
    int lightNum = -1;
};

/** ShadowMap (and SoftShadowMap) pushes its StateSet, the depth texture on its unit, before it
 *  traverses the shadowed scene: the texture is in the cull's state graph. */
TechniqueShadow shadowMapShadow(const osgShadow::ShadowMap& technique, osgUtil::CullVisitor& cv) {
    TechniqueShadow shadow;
    shadow.supported = true;
    shadow.unit = int(technique.getTextureUnit());
    for (osgUtil::StateGraph* graph = cv.getCurrentStateGraph(); graph && !shadow.depth;
         graph = graph->_parent) {
        const osg::StateSet* stateSet = graph->getStateSet();
        if (!stateSet) continue;
        auto* texture = dynamic_cast<osg::Texture*>(const_cast<osg::StateAttribute*>(
            stateSet->getTextureAttribute(unsigned(shadow.unit), osg::StateAttribute::TEXTURE)));
        if (texture && texture->getShadowComparison()) shadow.depth = texture;
    }
    return shadow;
}

/** ViewDependentShadowMap (OSG 3.6) culls the shadowed scene first, under an empty placeholder
 *  StateSet, and only then makes this frame's shadow cameras and binds their depth textures (on
 *  ShadowSettings::getBaseShadowTextureUnit() and up, one per map, with eye-linear TexGen placed
 *  in the render stage like ShadowMap's, and the same comparison: LEQUAL, border 1). So nothing
 *  is bound yet when this node is culled; but each frame takes its maps' ShadowData, in order,
 *  from the previous frame's list of this view, whose first entry is therefore the first map
 *  of this frame: its texture is the one sampled, found before it is drawn. On a view's first
 *  frame the list is empty, and gets the ShadowData the technique would have made (the same
 *  constructor, from the same ShadowSettings), so that frame is shadowed too. Only the first map
 *  is read: it shadows the first light (techniqueLight, or the settings' light number), the one
 *  VDSM's own shader shadows; with two maps per light the second's share of the view is lit. */
TechniqueShadow viewDependentShadow(osgShadow::ViewDependentShadowMap& technique,
                                    const osgShadow::ShadowedScene& scene,
                                    osgUtil::CullVisitor& cv) {
    TechniqueShadow shadow;
    shadow.supported = true;
    const osgShadow::ShadowSettings* settings = scene.getShadowSettings();
    // Without settings VDSM itself cannot run (it reads them unchecked); a debug-draw map is a
    // colour texture; units from 8 get no TexGen, so VDSM drops their maps.
    if (!settings || settings->getDebugDraw() || settings->getBaseShadowTextureUnit() >= 8)
        return shadow;
    osgShadow::ViewDependentShadowMap::ViewDependentData* data =
        technique.getViewDependentData(&cv);
    if (!data) return shadow;
    osgShadow::ViewDependentShadowMap::ShadowDataList& maps = data->getShadowDataList();
    if (maps.empty()) maps.push_back(new osgShadow::ViewDependentShadowMap::ShadowData(data));
    osg::Texture* texture = maps.front()->_texture.get();
    if (texture && texture->getShadowComparison()) shadow.depth = texture;
    shadow.unit = int(settings->getBaseShadowTextureUnit());
    shadow.lightNum = settings->getLightNum();
    return shadow;
}

/** The program ([0]) and the texture of each unit u ([1 + u]) that `sets` bind, a later set's
 *  winning: what this node's own state draws with. */
std::vector<osg::StateAttribute*> ownAttributes(std::initializer_list<const osg::StateSet*> sets) {
    std::vector<osg::StateAttribute*> own(1, nullptr);
    for (const osg::StateSet* set : sets) {
        if (!set) continue;
        if (const osg::StateAttribute* program = set->getAttribute(osg::StateAttribute::PROGRAM))
            own[0] = const_cast<osg::StateAttribute*>(program);
        const unsigned units = unsigned(set->getTextureAttributeList().size());
        if (own.size() < units + 1) own.resize(units + 1, nullptr);
        for (unsigned unit = 0; unit < units; ++unit)
            if (const osg::StateAttribute* texture =
                    set->getTextureAttribute(unit, osg::StateAttribute::TEXTURE))
                own[unit + 1] = const_cast<osg::StateAttribute*>(texture);
    }
    return own;
}

/** Binds `own`'s textures again, PROTECTED, on their units, and its program too when
 *  `program`: a shadow technique's OVERRIDE (ShadowMap's depth texture on unit 1, SoftShadowMap's
 *  jitter texture on unit 2, ViewDependentShadowMap's depth textures from unit 1, any program or
 *  texture of another technique) then leaves the material's state alone. */
void protectOwnAttributes(osg::StateSet& state, const std::vector<osg::StateAttribute*>& own,
                          bool program) {
    const unsigned protect = osg::StateAttribute::ON | osg::StateAttribute::PROTECTED;
    if (program && own[0]) state.setAttribute(own[0], protect);
    for (std::size_t i = 1; i < own.size(); ++i)
        if (own[i]) state.setTextureAttribute(unsigned(i - 1), own[i], protect);
}

/** The innermost ShadowedScene on `path` (null: none), and whether this cull is its technique's
 *  depth pass: ShadowMap culls the shadowed scene twice, once for the view (its StateSet with the
 *  depth texture and TexGen pushed) and once below its own render-to-texture Camera, which then
 *  follows the ShadowedScene on the node path; ViewDependentShadowMap likewise, once per map,
 *  below its shadow cameras. */
osgShadow::ShadowedScene* enclosingShadowedScene(const osg::NodePath& path, bool& depthPass) {
    osgShadow::ShadowedScene* scene = nullptr;
    depthPass = false;
    for (osg::Node* node : path) {
        if (auto* shadowed = dynamic_cast<osgShadow::ShadowedScene*>(node)) {
            scene = shadowed;
            depthPass = false;
        } else if (scene && dynamic_cast<const osg::Camera*>(node)) {
            depthPass = true;
        }
    }
    return scene;
}

/** What a depth pass draws the node's geometry with instead of the material (depthOnlyProgram),
 *  shared by every node. Not PROTECTED: a technique that binds its own depth program with
 *  OVERRIDE keeps it. Never destroyed, like the other shared state. */
osg::StateSet* depthPassStateSet() {
    static osg::StateSet* const state = [] {
        auto* created = new osg::StateSet;
        created->ref();
        created->setAttribute(depthOnlyProgram().get(), osg::StateAttribute::ON);
        return created;
    }();
    return state;
}

}  // namespace

osg::StateSet* MaterialNode::shadowStateSet(osgUtil::CullVisitor& cv) {
    // Below a ShadowedScene, and not in its technique's depth pass (traverse draws that pass
    // without the material: it only needs depth, and must not sample the texture it writes).
    bool depthPass = false;
    osgShadow::ShadowedScene* scene = enclosingShadowedScene(cv.getNodePath(), depthPass);
    if (!scene || depthPass || !scene->getShadowTechnique()) return nullptr;
    const std::vector<osg::StateAttribute*> own = ownAttributes(
        {materialStateSet(), _nodeStateSet.get(), _terminatorStateSet.get(), _mapStateSet.get()});
    osgShadow::ShadowTechnique* anyTechnique = scene->getShadowTechnique();
    TechniqueShadow shadow;
    if (const auto* technique = dynamic_cast<const osgShadow::ShadowMap*>(anyTechnique))
        shadow = shadowMapShadow(*technique, cv);
    else if (auto* technique = dynamic_cast<osgShadow::ViewDependentShadowMap*>(anyTechnique))
        shadow = viewDependentShadow(*technique, *scene, cv);
    osg::Texture* depth = shadow.depth;
    const int unit = shadow.unit;
    if (!depth) {
        // Any other technique: the material is drawn as it is without one, unshadowed, whatever
        // the technique binds with OVERRIDE (its textures, its program).
        if (!shadow.supported && !_shadowNoticeGiven.exchange(true))
            OSG_NOTICE << "osgBTF::MaterialNode: shadow technique '" << anyTechnique->className()
                       << "' is not supported (osgShadow::ShadowMap, SoftShadowMap and "
                          "ViewDependentShadowMap are): the node draws without cast shadows"
                       << std::endl;
        std::lock_guard<std::mutex> lock(_lightsMutex);
        CameraLights& entry = _lightsPerCamera[cv.getCurrentCamera()];
        if (!entry.unshadowedStateSet || entry.unshadowedOwn != own) {
            entry.unshadowedStateSet = new osg::StateSet;
            protectOwnAttributes(*entry.unshadowedStateSet, own, true);
            entry.unshadowedOwn = own;
            entry.camera = cv.getCurrentCamera();
        }
        return entry.unshadowedStateSet.get();
    }

    std::lock_guard<std::mutex> lock(_lightsMutex);
    CameraLights& entry = _lightsPerCamera[cv.getCurrentCamera()];
    osg::ref_ptr<osg::Texture> current;
    const bool stale = !entry.shadowStateSet || !entry.shadowTexture.lock(current) ||
                       current.get() != depth || entry.shadowUnit != unit ||
                       entry.shadowMapState != _mapStateSet.get() || entry.shadowOwn != own;
    if (stale) {
        osg::ref_ptr<osg::StateSet> state = new osg::StateSet;
        state->setAttributeAndModes(shadowMapProgram(*_material, _mapStateSet.valid()).get(),
                                    osg::StateAttribute::ON | osg::StateAttribute::PROTECTED);
        state->setTextureAttribute(shader::kShadowMapUnit, depth, osg::StateAttribute::ON);
        state->addUniform(new osg::Uniform(shader::kShadowMap, shader::kShadowMapUnit));
        state->addUniform(new osg::Uniform(shader::kShadowTexGenUnit, unit));
        entry.shadowLight = new osg::Uniform(shader::kShadowLight, -1);
        entry.shadowLight->setDataVariance(osg::Object::DYNAMIC);
        state->addUniform(entry.shadowLight.get());
        // The technique binds its texture on its unit with OVERRIDE (SoftShadowMap its jitter
        // texture on the next one too, ViewDependentShadowMap a white texture on unit 0 and its
        // maps with OVERRIDE unless its settings say otherwise); what this node's state put there
        // (the material's textures use units from 0, the techniques' default is 1) is bound again,
        // PROTECTED, so the material keeps its textures and the shader reads the depth texture
        // from kShadowMapUnit instead.
        protectOwnAttributes(*state, own, false);
        entry.camera = cv.getCurrentCamera();
        entry.shadowStateSet = state;
        entry.shadowTexture = depth;
        entry.shadowUnit = unit;
        entry.shadowMapState = _mapStateSet.get();
        entry.shadowOwn = own;
    }
    const int count = int(entry.lights.size());
    const int light =
        _shadowLight >= 0 ? _shadowLight : techniqueLight(cv, entry.lights, shadow.lightNum);
    entry.shadowLight->set(light < count ? light : -1);
    return entry.shadowStateSet.get();
}

void MaterialNode::traverse(osg::NodeVisitor& nv) {
    osgUtil::CullVisitor* cv =
        nv.getVisitorType() == osg::NodeVisitor::CULL_VISITOR ? nv.asCullVisitor() : nullptr;
    if (!cv || !_material) {
        // OSG's compile passes see only the StateSets of nodes and drawables; the material's are
        // pushed at cull, outside the graph, so they are shown here or never compiled ahead.
        osg::StateSet* material = cv ? nullptr : materialStateSet();
        if (material) {
            if (auto* compile = dynamic_cast<osgUtil::GLObjectsVisitor*>(&nv)) {
                compile->apply(*material);
                compile->apply(*_nodeStateSet);
                if (_terminatorStateSet) compile->apply(*_terminatorStateSet);
                if (_mapStateSet) compile->apply(*_mapStateSet);
            } else if (auto* collect = dynamic_cast<osgUtil::StateToCompile*>(&nv)) {
                collect->apply(*material);
                collect->apply(*_nodeStateSet);
                if (_terminatorStateSet) collect->apply(*_terminatorStateSet);
                if (_mapStateSet) collect->apply(*_mapStateSet);
            }
        }
        osg::Group::traverse(nv);
        return;
    }
    bool depthPass = false;
    if (enclosingShadowedScene(cv->getNodePath(), depthPass) && depthPass) {
        // A shadow technique's depth pass (VDSM's maps are 2048 x 2048 each): running the BTF
        // program there cost more than the view itself (issue 47).
        cv->pushStateSet(depthPassStateSet());
        osg::Group::traverse(nv);
        cv->popStateSet();
        return;
    }
    cv->pushStateSet(_material->sharedStateSet());
    cv->pushStateSet(_nodeStateSet.get());
    if (_terminatorStateSet) cv->pushStateSet(_terminatorStateSet.get());
    if (_mapStateSet) cv->pushStateSet(_mapStateSet.get());
    cv->pushStateSet(lightStateSet(*cv));
    osg::StateSet* shadow = shadowStateSet(*cv);
    if (shadow) cv->pushStateSet(shadow);
    osg::Group::traverse(nv);
    if (shadow) cv->popStateSet();
    cv->popStateSet();
    if (_mapStateSet) cv->popStateSet();
    if (_terminatorStateSet) cv->popStateSet();
    cv->popStateSet();
    cv->popStateSet();
}

osg::StateSet* MaterialNode::materialStateSet() const {
    if (!_material) return nullptr;
    try {
        return _material->sharedStateSet();
    } catch (const std::exception&) {
        return nullptr;  // reported by setMaterial; GL passes must not throw
    }
}

void MaterialNode::pruneCameraLights() const {
    for (auto it = _lightsPerCamera.begin(); it != _lightsPerCamera.end();)
        // A null key (a cull without a camera) has nothing to observe: kept, as its StateSet
        // may still be in a render graph.
        it = !it->first || it->second.camera.valid() ? std::next(it) : _lightsPerCamera.erase(it);
}

std::size_t MaterialNode::getNumCameraLightStates() const {
    std::lock_guard<std::mutex> lock(_lightsMutex);
    return _lightsPerCamera.size();
}

void MaterialNode::resizeGLObjectBuffers(unsigned int maxSize) {
    osg::Group::resizeGLObjectBuffers(maxSize);
    if (osg::StateSet* material = materialStateSet()) material->resizeGLObjectBuffers(maxSize);
    _nodeStateSet->resizeGLObjectBuffers(maxSize);
    if (_terminatorStateSet) _terminatorStateSet->resizeGLObjectBuffers(maxSize);
    if (_mapStateSet) _mapStateSet->resizeGLObjectBuffers(maxSize);
    std::lock_guard<std::mutex> lock(_lightsMutex);
    for (auto& [camera, entry] : _lightsPerCamera) {
        if (entry.stateSet) entry.stateSet->resizeGLObjectBuffers(maxSize);
        if (entry.shadowStateSet) entry.shadowStateSet->resizeGLObjectBuffers(maxSize);
        if (entry.unshadowedStateSet) entry.unshadowedStateSet->resizeGLObjectBuffers(maxSize);
    }
}

void MaterialNode::releaseGLObjects(osg::State* state) const {
    osg::Group::releaseGLObjects(state);
    if (const osg::StateSet* material = materialStateSet()) material->releaseGLObjects(state);
    _nodeStateSet->releaseGLObjects(state);
    if (_terminatorStateSet) _terminatorStateSet->releaseGLObjects(state);
    if (_mapStateSet) _mapStateSet->releaseGLObjects(state);
    std::lock_guard<std::mutex> lock(_lightsMutex);
    pruneCameraLights();
    for (const auto& [camera, entry] : _lightsPerCamera) {
        if (entry.stateSet) entry.stateSet->releaseGLObjects(state);
        if (entry.shadowStateSet) entry.shadowStateSet->releaseGLObjects(state);
        if (entry.unshadowedStateSet) entry.unshadowedStateSet->releaseGLObjects(state);
    }
}

}  // namespace osgBTF
