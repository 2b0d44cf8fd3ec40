// btfviewer --env: lights every MaterialNode by an HDR environment (seed 004 section 5, see
// scene/README.md). Methods with folded environment lighting (pca, fmf, lpca) get per-vertex data
// with Embree visibility of the whole scene; the others are lit by 8 median-cut representative
// lights. A new rotation or material recomputes the per-vertex data on a worker thread (the old
// lighting stays on screen until the new one is installed in the update traversal); exposure and
// the camera are real time.
#pragma once

#include <atomic>
#include <functional>
#include <map>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include <osg/Geometry>
#include <osg/Group>
#include <osg/StateSet>

#include "scene/EnvironmentLight.h"
#include "scene/MaterialNode.h"

namespace btfviewer {

class EnvironmentControl : public osg::Referenced {
public:
    /** Reads the map (throws osgBTF::Error "--env: FILE: problem"); `scene` occludes and holds
     *  the MaterialNodes. node() goes into the scene graph (the representative lights, and the
     *  update callback that installs finished work). */
    EnvironmentControl(const std::string& file, float exposure, float rotation, osg::Node* scene,
                       std::vector<osg::ref_ptr<osgBTF::MaterialNode>> nodes);

    osg::Group* node() const { return _group.get(); }
    /** Recomputes for the nodes' current materials and the current rotation (worker thread). */
    void request();
    void rotate(float degrees);
    void scaleExposure(float factor);
    /** "environment: rotation R, exposure E  [keys][  computing N %]". */
    std::string status() const;
    /** Blocks until no work is running or pending and installs the result (--frames runs). */
    void finish();

    /** Called in the update traversal: installs a finished result, starts pending work. */
    void update();
    /** Called (update traversal) while work runs and when it is installed: the HUD. */
    std::function<void()> changed;

protected:
    ~EnvironmentControl() override;

private:
    struct Result;
    void start();
    void install(Result& result);
    void rebuildRepresentativeLights();

    osg::ref_ptr<osgBTF::EnvironmentLight> _light;
    osg::ref_ptr<osg::Node> _scene;
    std::vector<osg::ref_ptr<osgBTF::MaterialNode>> _nodes;
    osg::ref_ptr<osg::Group> _group;
    osg::ref_ptr<osg::Group> _representative;
    std::map<osg::Geometry*, osg::ref_ptr<osg::StateSet>> _original;  // geometry StateSets
    std::thread _worker;
    std::unique_ptr<Result> _result;
    std::atomic<bool> _done{false};
    bool _pending = false;
    std::atomic<std::size_t> _progress{0}, _total{0};
    std::string _error;
};

}  // namespace btfviewer
