#include "examples/btfviewer/EnvironmentControl.h"

#include <cmath>
#include <iomanip>
#include <sstream>

#include "core/Error.h"

namespace btfviewer {

EnvironmentControl::EnvironmentControl(const std::string& file, float exposure, float rotation,
                                       int rotationSamples, osg::Node* scene)
    : _light(new osgBTF::EnvironmentLight), _group(new osgBTF::EnvironmentLitGroup) {
    _light->setFile(file);
    if (!_light->hasMap()) throw osgBTF::Error("--env: " + _light->getError());
    _light->setExposure(exposure);
    _light->setRotation(rotation);
    _group->setName("btfviewer environment");
    _group->setLight(_light.get());
    _group->setRotationSamples(rotationSamples);
    osg::ref_ptr<osg::Node> keep = scene;
    if (scene->getNumParents() > 0) scene->getParent(0)->replaceChild(scene, _group.get());
    _group->addChild(scene);
}

void EnvironmentControl::rotate(float degrees) {
    _light->setRotation(std::remainder(_light->getRotation() + degrees, 360.0f));
}

void EnvironmentControl::scaleExposure(float factor) {
    _light->setExposure(_light->getExposure() * factor);  // the folded data's uniform: real time
}

std::string EnvironmentControl::status() const {
    std::ostringstream text;
    text << std::fixed << std::setprecision(0) << "environment: rotation " << _light->getRotation()
         << ", exposure " << std::setprecision(2) << _light->getExposure() << "  [ , . - + ]";
    if (_group->computing()) {
        const std::size_t total = _group->progressTotal(), done = _group->progressDone();
        text << "  computing" << (total ? " " + std::to_string(100 * done / total) + " %" : "");
    }
    if (_group->getRotationSamples() > 0 && _group->lastRebuildMilliseconds() >= 0)
        text << std::setprecision(1) << "  (illumination PCA: rebuilt in "
             << _group->lastRebuildMilliseconds() << " ms)";
    if (!_group->getError().empty()) text << "  error: " << _group->getError();
    return text.str();
}

}  // namespace btfviewer
