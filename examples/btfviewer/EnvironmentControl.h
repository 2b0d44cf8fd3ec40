// btfviewer --env: lights every MaterialNode by an HDR environment (Sattler et al. 2003 section 5,
// see scene/README.md) through an osgBTF::EnvironmentLitGroup put above the scene: methods with
// folded environment lighting (pca, fmf, lpca) get per-vertex data with Embree visibility of the
// whole scene, the others 8 median-cut representative lights. A new rotation or material is
// recomputed by the group on a worker thread (the old lighting stays on screen until the new one
// is installed); exposure and the camera are real time. This class adds the keys and the HUD.
#pragma once

#include <functional>
#include <string>

#include <osg/Group>

#include "environment/EnvironmentLitGroup.h"

namespace btfviewer {

class EnvironmentControl : public osg::Referenced {
public:
    /** Reads the map (throws osgBTF::Error "--env: FILE: problem") and puts the lit group
     *  between `scene` and its first parent. `rotationSamples` > 0: illumination PCA. */
    EnvironmentControl(const std::string& file, float exposure, float rotation, int rotationSamples,
                       osg::Node* scene);

    /** Recomputes (the group also notices new materials by itself). */
    void request() { _group->dirty(); }
    void rotate(float degrees);
    void scaleExposure(float factor);
    /** "environment: rotation R, exposure E  [keys][  computing N %]". */
    std::string status() const;
    /** Blocks until the lighting is computed and installed (--frames runs). */
    void finish() { _group->finish(); }
    /** Called in the update traversal while work runs and when it is installed: the HUD. */
    void setChanged(std::function<void()> changed) {
        _group->setProgressCallback(std::move(changed));
    }

protected:
    ~EnvironmentControl() override = default;

private:
    osg::ref_ptr<osgBTF::EnvironmentLight> _light;
    osg::ref_ptr<osgBTF::EnvironmentLitGroup> _group;
};

}  // namespace btfviewer
