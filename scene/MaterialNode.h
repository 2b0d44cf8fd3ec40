// osgBTF: the scene-graph node that renders its children with a fitted BTF material.
//
//   osg::ref_ptr<osgBTF::MaterialNode> node = new osgBTF::MaterialNode;
//   node->setMaterialFile("wool-lpca.btfmat");   // or setMaterial(material)
//   node->setTextureScale(4);                    // the material repeats 4x per texcoord unit
//   node->addChild(osgDB::readNodeFile("cow.osgt"));
//
// What it does (scene/README.md has the details and limits):
//  - applies the material's shared StateSet (one osg::Program per method, textures and uniforms
//    per material, built once per Material object) to its children, plus its own texture scale;
//  - gives every Geometry below it that lacks one a tangent frame (vertex attribute 6,
//    "osgBTF_tangent": xyz along +s, w = handedness), once, when children are added or the
//    material is set;
//  - feeds every osg::LightSource of the scene being culled (up to 8) to the shaders in eye
//    space, for each camera and frame; with no LightSource in the scene, the view's own light
//    (osgViewer's headlight or sky light), or a white headlight when there is no view.
//  - multiplies each light's term by Sattler et al. 2003's smooth shadow terminator (on by default,
//  alpha
//    15 degrees; scene/ShadowTerminator.h);
//  - below an osgShadow::ShadowedScene whose technique is an osgShadow::ShadowMap, SoftShadowMap
//    or ViewDependentShadowMap (its first map), samples the technique's shadow map for the light
//    it shadows (setShadowLight), with any texture unit; under any other technique it draws
//    unshadowed, its own program and textures PROTECTED from the technique's OVERRIDE, with one
//    notice;
//  - optionally draws the material through a coordinate map (setCoordinateMap[File]): a large
//    non-repeating surface from a small sample, at the cost of four dependent fetches (the
//    filtered lookup of the map's four entries around a fragment).
// A material that cannot be loaded is reported with OSG_WARN (file and problem); the node then
// draws its children with their own state, so the rest of the scene is unaffected.
#pragma once

#include <atomic>
#include <cstddef>
#include <map>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <osg/Camera>
#include <osg/Group>
#include <osg/Light>
#include <osg/Matrixd>
#include <osg/StateSet>
#include <osg/Texture>
#include <osg/Uniform>
#include <osg/observer_ptr>
#include <osgDB/Options>

#include "core/CoordinateMap.h"
#include "materials/Material.h"
#include "materials/ShaderInterface.h"

namespace osgUtil {
class CullVisitor;
}

namespace osgBTF {

/** One light as the shaders see it: eye-space position (w = 0: direction toward the light,
 *  w = 1: point position), RGB colour (the osg::Light's diffuse) and its per-vertex visibility
 *  slot (materials/LightVisibility.h; -1: none, always seen). */
struct EyeLight {
    osg::Vec4 position;
    osg::Vec3 color;
    int visibilitySlot = -1;
};

/** The shader's light limit (materials/ShaderInterface.h). */
constexpr int kMaxLights = shader::kMaxLights;

class MaterialNode : public osg::Group {
public:
    MaterialNode();
    explicit MaterialNode(Material* material);
    MaterialNode(const MaterialNode& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY);
    META_Node(osgBTF, MaterialNode)

        /** Uses `material` (null: none). Forgets the material file name unless the material knows
         *  the file it was loaded from (Material::sourceFile), which then becomes the file name. */
        void setMaterial(Material* material);
    Material* getMaterial() { return _material.get(); }
    const Material* getMaterial() const { return _material.get(); }

    /** Loads a fitted-material file, found like any osgDB file (as given, then on the options'
     *  and OSG_FILE_PATH's data paths). Files already loaded by any MaterialNode (same path, size
     *  and modification time) are shared, not read again. On failure: OSG_WARN
     *  "osgBTF::MaterialNode: FILE: problem", no material, returns false; the file name is kept
     *  either way (a scene written back keeps referring to it). */
    bool setMaterialFile(const std::string& file, const osgDB::Options* options = nullptr);
    /** The name given to setMaterialFile (or the loaded material's source file); what .osgt/.osgb
     *  files store. */
    const std::string& getMaterialFile() const { return _materialFile; }
    /** The problem of the last failed setMaterialFile, empty after a success. */
    const std::string& getMaterialError() const { return _materialError; }

    /** Tiling: how often the material repeats per unit of texture coordinate (default 1). With
     *  a coordinate map, how often the MAP repeats. */
    void setTextureScale(float scale);
    float getTextureScale() const { return _textureScale; }

    /** Renders the material through a coordinate map (core/CoordinateMap.h, e.g. `btf
     *  synthesize`'s output; null: none): the texture coordinates (times the texture scale) then
     *  cover the map, wrapping around, and each of its texels shows the sample texel the map
     *  names (materials/CoordinateMapRendering.h). Works with any material and method. A map
     *  into another sample size than the material's is refused when both are set: OSG_WARN
     *  "osgBTF::MaterialNode: MAP: made for a WxH sample, but material 'M' is wxh (the node draws
     * the material without the map)", getCoordinateMapError() says it, and the material is drawn
     * without the map. Returns false then. Forgets the map file name. */
    bool setCoordinateMap(std::shared_ptr<const CoordinateMap> map);
    const std::shared_ptr<const CoordinateMap>& getCoordinateMap() const { return _map; }
    /** Reads a coordinate map file, found like setMaterialFile's (maps already read by any node,
     *  same path, size and modification time, are shared). On failure: OSG_WARN
     *  "osgBTF::MaterialNode: FILE: problem (the node draws the material without the map)", no
     *  map, returns false; the file name is kept either way (what .osgt/.osgb files store). */
    bool setCoordinateMapFile(const std::string& file, const osgDB::Options* options = nullptr);
    const std::string& getCoordinateMapFile() const { return _mapFile; }
    /** The problem of the last failed map setting or size check, empty when the map is used or
     *  none is set. */
    const std::string& getCoordinateMapError() const { return _mapError; }
    /** Whether the material is drawn through the map (both set, sizes matching). */
    bool usesCoordinateMap() const { return _mapStateSet.valid(); }

    /** Sattler et al. 2003's smooth shadow terminator (scene/ShadowTerminator.h), for every light
     * and method: per vertex u = (1 + cos(alpha + angle(n, l))) / 2 into a blurred 1D step of
     *  `softness` width. On by default; off draws exactly what the node drew without it. */
    void setShadowTerminator(bool enabled);
    bool getShadowTerminator() const { return _terminator; }
    /** alpha in degrees (default 15; 0 puts the boundary at n.l = 0). */
    void setTerminatorAlpha(float degrees);
    float getTerminatorAlpha() const { return _terminatorAlpha; }
    /** Width in u of the blurred step (default 0.1, 0..1; 0: the hard step). */
    void setTerminatorSoftness(float softness);
    float getTerminatorSoftness() const { return _terminatorSoftness; }

    /** Which of the node's lights (in collectLights' order) the shadow technique above the node
     *  shadows. Default -1: the light the technique picks when it was given none (the last
     *  osg::Light culled in the camera's render stage; for a ViewDependentShadowMap the last one
     *  whose number is ShadowSettings::getLightNum(), when that is >= 0), found in cull when the
     *  scene's LightSources come before the shadowed models, else the node's last light. Set it
     *  when ShadowMap::setLight chooses another. */
    void setShadowLight(int index) { _shadowLight = index; }
    int getShadowLight() const { return _shadowLight; }

    /** Adds tangents (attribute 6) to every Geometry below this node that has texture
     *  coordinates on unit 0 and no attribute 6 yet. Called automatically by addChild,
     *  insertChild, replaceChild, setChild and setMaterial; call it yourself after adding
     *  geometry deeper below a child. Returns the number of geometries it changed. */
    unsigned generateTangents();

    /** The lights the shaders get when this node is culled with `cv` (what traverse() uses;
     *  public for tests and tools). */
    static std::vector<EyeLight> collectLights(osgUtil::CullVisitor& cv);

    bool addChild(osg::Node* child) override;
    bool insertChild(unsigned int index, osg::Node* child) override;
    bool replaceChild(osg::Node* origChild, osg::Node* newChild) override;
    bool setChild(unsigned int index, osg::Node* node) override;

    /** Cull pushes the material's state; OSG's compile visitors (osgUtil::GLObjectsVisitor as
     *  osgViewer's first frame runs it, osgUtil::StateToCompile of the incremental compile) get
     *  the material's and this node's StateSets before the children. */
    void traverse(osg::NodeVisitor& nv) override;

    /** Forwarded, beyond osg::Group's, to every StateSet this node applies that is not in the
     *  scene graph: the material's shared StateSet (its textures and program), the per-node
     *  StateSet and the per-camera light StateSets. Lets OSG size their per-context buffers
     *  (osgViewer does it when contexts are added) and drop their GL objects when a context
     *  closes (osg::GraphicsContext::close releases every camera's subgraph). Releasing the shared
     *  StateSet releases it for every node using the material (OSG's rule for any shared
     *  StateSet); they recompile in that context when drawn again. */
    void resizeGLObjectBuffers(unsigned int maxSize) override;
    void releaseGLObjects(osg::State* state = nullptr) const override;

    /** How many cameras' light StateSets this node holds, for tests and diagnostics. An entry
     *  goes when its camera is deleted: at the next cull of this node by any camera, or at
     *  releaseGLObjects. */
    std::size_t getNumCameraLightStates() const;

protected:
    ~MaterialNode() override;
    void createNodeState();
    /** The material's shared StateSet; null without a material or when it cannot be built (the
     *  failure is reported where the material is set). */
    osg::StateSet* materialStateSet() const;
    /** Rebuilds _mapStateSet for the current material and map (checks their sizes). */
    void updateMapState();
    /** Drops the light state of cameras that no longer exist; _lightsMutex held. */
    void pruneCameraLights() const;

    /** The per-camera light uniforms, refilled once per frame. */
    osg::StateSet* lightStateSet(osgUtil::CullVisitor& cv);

    osg::ref_ptr<Material> _material;
    std::string _materialFile;
    std::string _materialError;
    float _textureScale = 1.0f;
    osg::ref_ptr<osg::StateSet> _nodeStateSet;  // osgBTF_textureScale
    osg::ref_ptr<osg::Uniform> _textureScaleUniform;
    std::shared_ptr<const CoordinateMap> _map;
    std::string _mapFile;
    std::string _mapError;
    osg::ref_ptr<osg::StateSet> _mapStateSet;  // the map program and texture; null: no map used
    bool _terminator = true;
    float _terminatorAlpha;
    float _terminatorSoftness;
    int _shadowLight = -1;
    osg::ref_ptr<osg::Uniform> _terminatorUniform, _terminatorAlphaUniform;
    /** The terminator's texture, shared (terminatorStateSet); null while the terminator is off. */
    osg::ref_ptr<osg::StateSet> _terminatorStateSet;
    /** Refreshes the terminator state (uniforms of _nodeStateSet, _terminatorStateSet). */
    void updateTerminatorState();

    struct CameraLights {
        // Tells when the camera is gone (pruneCameraLights), so a camera allocated later at a
        // deleted one's address never gets the old entry.
        osg::observer_ptr<osg::Camera> camera;
        unsigned frameNumber = ~0u;
        osg::ref_ptr<osg::StateSet> stateSet;
        osg::ref_ptr<osg::Uniform> count, positions, colors, visibilitySlots;
        std::vector<EyeLight> lights;  // what the uniforms hold
        // Shadow-map state (program variant, the technique's depth texture on
        // shader::kShadowMapUnit), rebuilt when the technique's texture or unit changes.
        osg::ref_ptr<osg::StateSet> shadowStateSet;
        osg::observer_ptr<osg::Texture> shadowTexture;
        int shadowUnit = -1;
        const osg::StateSet* shadowMapState = nullptr;
        osg::ref_ptr<osg::Uniform> shadowLight;
        std::vector<osg::StateAttribute*> shadowOwn;  // the own state shadowStateSet protects
        // Under a technique the node does not support: the node's own program and textures
        // again, PROTECTED from the technique's OVERRIDE, for `unshadowedOwn`.
        osg::ref_ptr<osg::StateSet> unshadowedStateSet;
        std::vector<osg::StateAttribute*> unshadowedOwn;
    };
    /** The shadow-map state for this cull (under a ShadowMap, SoftShadowMap or
     *  ViewDependentShadowMap); under another technique the node's own state bound again
     *  PROTECTED (drawn unshadowed, one notice); null when the node is not below a ShadowedScene,
     *  or is being culled for the technique's own depth pass. */
    osg::StateSet* shadowStateSet(osgUtil::CullVisitor& cv);
    std::atomic<bool> _shadowNoticeGiven{false};  // cull threads of several cameras
    mutable std::mutex _lightsMutex;  // cull threads of several cameras may share this node
    mutable std::map<const osg::Camera*, CameraLights> _lightsPerCamera;
};

/** Adds tangents below `node` (see MaterialNode::generateTangents); returns how many geometries
 *  got one. */
unsigned generateTangents(osg::Node& node);

}  // namespace osgBTF
