// osgBTF::EnvironmentLitGroup: a Group whose MaterialNodes are lit by an HDR environment (Sattler
// et al. 2003 section 5), kept up to date by itself, so a scene file lights its materials in any
// viewer (stock osgviewer included) without application code.
//
// In the update traversal it looks for MaterialNodes below it and, when the light's map, rotation
// or projection width, or the set of MaterialNodes and their materials changed since the last
// computation (or after dirty()), starts the per-vertex work on a worker thread: linear methods
// (pca, fmf, lpca) get folded per-vertex data with ray-cast visibility of everything below this
// group (applyEnvironmentLighting's computation, environment/VertexEnvironment.h); the others are
// lit by representative lights of the map (median cut), which the group holds and traverses itself.
// The previous lighting stays on screen until the new one is installed, in a later update
// traversal. Exposure changes are real time. Geometry edits need dirty().
//
// Serialized (.osgt/.osgb) as osgBTF::EnvironmentLitGroup: Light (an osgBTF::EnvironmentLight),
// RepresentativeLights, Visibility, then the children as for osg::Group.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <glm/vec3.hpp>
#include <osg/Geometry>
#include <osg/Group>
#include <osg/Matrixd>

#include "scene/EnvironmentLight.h"

namespace osgBTF {

class MaterialNode;

class EnvironmentLitGroup : public osg::Group {
public:
    EnvironmentLitGroup();
    EnvironmentLitGroup(const EnvironmentLitGroup& other,
                        const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY);
    META_Node(osgBTF, EnvironmentLitGroup)

        void setLight(EnvironmentLight* light);
    EnvironmentLight* getLight() { return _light.get(); }
    const EnvironmentLight* getLight() const { return _light.get(); }
    /** Median-cut lights for the methods without folded lighting (1..8, default 8). */
    void setRepresentativeLights(int count);
    int getRepresentativeLights() const { return _representativeCount; }
    /** Self-shadowing: rays against everything below this group (default true). */
    void setVisibility(bool on);
    bool getVisibility() const { return _visibility; }

    /** Illumination PCA (Sattler et al. 2003 section 5.3): with A > 0, the folded data are computed
     * for A rotations of the map (360 / A degrees apart; A times the work and, while building, A
     *  times the data's memory) and compressed to `components` principal components per
     *  geometry, and a new rotation is then rebuilt in the update traversal from the two
     *  neighbouring samples' coefficients (no worker, no ray casting). 0 (default): every new
     *  rotation is computed exactly on the worker. The paper's setting: 30 and 5. */
    void setRotationSamples(int samples);
    int getRotationSamples() const { return _rotationSamples; }
    void setRotationComponents(int components);
    int getRotationComponents() const { return _rotationComponents; }
    /** Milliseconds the last rotation rebuilt from the illumination PCA took (-1: none yet). */
    double lastRebuildMilliseconds() const { return _rebuildMs; }

    /** Recompute in the next update traversal (after geometry below changed). */
    void dirty() { _dirty = true; }
    /** Starts pending work if none runs, waits for it and installs it: for a first frame that
     *  must show the result (captures, tests). Call between frames, from the update thread. */
    void finish();
    /** Work running or pending. */
    bool computing() const { return _worker.joinable() || _dirty; }
    /** Vertices done and in all of the running work (0, 0 when idle). */
    std::size_t progressDone() const { return _progress; }
    std::size_t progressTotal() const { return _total; }
    /** The last computation's error (empty when it succeeded); also reported with OSG_WARN. */
    const std::string& getError() const { return _error; }
    /** Called from the update traversal while work runs and once when it is installed. */
    void setProgressCallback(std::function<void()> callback) { _changed = std::move(callback); }

    void traverse(osg::NodeVisitor& nv) override;

protected:
    ~EnvironmentLitGroup() override;

private:
    struct Result;
    /** What the lighting was computed for; a difference means recomputing. */
    struct Key {
        std::string file;
        float rotation = 0;
        int projectionWidth = 0, mapWidth = 0, mapHeight = 0;
        bool visibility = true;
        int rotationSamples = 0, rotationComponents = 0;
        std::vector<std::pair<const MaterialNode*, const void*>> materials;
        bool operator==(const Key& o) const {
            return file == o.file && rotation == o.rotation &&
                   projectionWidth == o.projectionWidth && mapWidth == o.mapWidth &&
                   mapHeight == o.mapHeight && visibility == o.visibility &&
                   rotationSamples == o.rotationSamples &&
                   rotationComponents == o.rotationComponents && materials == o.materials;
        }
    };
    Key currentKey(std::vector<osg::ref_ptr<MaterialNode>>& nodes);
    void update();
    void start(const Key& key, std::vector<osg::ref_ptr<MaterialNode>> nodes);
    void joinAndInstall();
    void updateRepresentativeLights();
    /** Toward each representative light, by visibility slot (empty with visibility off). */
    std::vector<glm::vec3> representativeDirections() const;
    /** Every geometry's StateSet from its illumination PCA at the light's rotation. */
    void rebuildFromIlluminationPca();

    osg::ref_ptr<EnvironmentLight> _light;
    int _representativeCount = 8;
    int _rotationSamples = 0, _rotationComponents = 5;
    struct RotatingGeometry;
    std::vector<RotatingGeometry> _rotating;  // with illumination PCA: what rebuilds a rotation
    float _installedRotation = 0;
    float _pcaRotation = 0;  // the light's rotation at the illumination PCA's sample 0
    double _rebuildMs = -1;
    bool _visibility = true;
    osg::ref_ptr<osg::Group> _representative = new osg::Group;
    std::tuple<std::string, float, float, int, bool> _representativeFor{"", 0.0f, -1.0f, 0, false};
    std::map<osg::Geometry*, osg::ref_ptr<osg::StateSet>> _original;  // StateSets before us
    std::map<const MaterialNode*, osg::Matrixd> _placements;          // node -> this group's space
    Key _computed;
    bool _everComputed = false;
    bool _dirty = false;
    std::thread _worker;
    std::unique_ptr<Result> _result;
    std::atomic<bool> _done{false}, _cancel{false};
    std::atomic<std::size_t> _progress{0}, _total{0};
    std::string _error;
    std::function<void()> _changed;
};

}  // namespace osgBTF
