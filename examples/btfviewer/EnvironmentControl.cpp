#include "examples/btfviewer/EnvironmentControl.h"

#include <cmath>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <osg/NodeVisitor>

#include "core/Error.h"
#include "materials/EnvironmentState.h"
#include "scene/VertexEnvironment.h"

namespace btfviewer {

namespace {

/** Every Geometry below a node. */
struct GeometryCollector : osg::NodeVisitor {
    GeometryCollector() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
    void apply(osg::Geometry& geometry) override { geometries.push_back(&geometry); }
    std::vector<osg::Geometry*> geometries;
};

/** Installs finished work in the update traversal, where the scene graph may change. */
struct UpdateCallback : osg::NodeCallback {
    explicit UpdateCallback(EnvironmentControl* control) : control(control) {}
    void operator()(osg::Node* node, osg::NodeVisitor* nv) override {
        if (osg::ref_ptr<EnvironmentControl> c; control.lock(c)) c->update();
        traverse(node, nv);
    }
    osg::observer_ptr<EnvironmentControl> control;
};

}  // namespace

struct EnvironmentControl::Result {
    // nullptr: the geometry's own StateSet again (a method drawn by representative lights).
    std::vector<std::pair<osg::Geometry*, osg::ref_ptr<osg::StateSet>>> states;
    std::string error;
};

EnvironmentControl::EnvironmentControl(const std::string& file, float exposure, float rotation,
                                       osg::Node* scene,
                                       std::vector<osg::ref_ptr<osgBTF::MaterialNode>> nodes)
    : _light(new osgBTF::EnvironmentLight),
      _scene(scene),
      _nodes(std::move(nodes)),
      _group(new osg::Group),
      _representative(new osg::Group) {
    _light->setFile(file);
    if (!_light->hasMap()) throw osgBTF::Error("--env: " + _light->getError());
    _light->setExposure(exposure);
    _light->setRotation(rotation);
    _group->setName("btfviewer environment");
    _group->addChild(_representative.get());
    _group->setUpdateCallback(new UpdateCallback(this));
    for (const auto& node : _nodes) {
        GeometryCollector collector;
        node->accept(collector);
        for (osg::Geometry* geometry : collector.geometries) {
            _original.emplace(geometry, geometry->getStateSet());
            // The draw thread of the previous frame may still use the StateSet being replaced.
            geometry->setDataVariance(osg::Object::DYNAMIC);
        }
    }
    rebuildRepresentativeLights();
}

EnvironmentControl::~EnvironmentControl() {
    if (_worker.joinable()) _worker.join();
}

void EnvironmentControl::rebuildRepresentativeLights() {
    _representative->removeChildren(0, _representative->getNumChildren());
    _representative->addChild(osgBTF::representativeLightSources(*_light, 8).get());
}

void EnvironmentControl::request() {
    _pending = true;
    if (!_worker.joinable()) start();
}

void EnvironmentControl::rotate(float degrees) {
    _light->setRotation(std::remainder(_light->getRotation() + degrees, 360.0f));
    rebuildRepresentativeLights();
    request();
}

void EnvironmentControl::scaleExposure(float factor) {
    _light->setExposure(_light->getExposure() * factor);  // the folded data's uniform: real time
    rebuildRepresentativeLights();
}

void EnvironmentControl::start() {
    _pending = false;
    _done = false;
    _progress = 0;
    _total = 0;
    // Everything the worker reads is copied or fixed here: the map, the materials.
    std::vector<std::pair<osg::ref_ptr<osgBTF::MaterialNode>, osg::ref_ptr<osgBTF::Material>>> work;
    for (const auto& node : _nodes) work.emplace_back(node, node->getMaterial());
    const osgBTF::EnvironmentMap map = _light->projectionMap();
    _result = std::make_unique<Result>();
    _worker = std::thread([this, work, map] {
        try {
            for (const auto& [node, material] : work) {
                GeometryCollector collector;
                node->accept(collector);
                if (!material || !osgBTF::foldsEnvironment(*material)) {
                    for (osg::Geometry* g : collector.geometries)
                        _result->states.emplace_back(g, nullptr);
                    continue;
                }
                osgBTF::VertexEnvironmentOptions options;
                options.progress = [this](std::size_t done, std::size_t total) {
                    _progress = done;
                    _total = total;
                };
                for (osgBTF::GeometryEnvironment& entry : osgBTF::computeVertexEnvironment(
                         *node, _scene.get(), material->lights(), map, options)) {
                    std::vector<std::vector<float>> folded;
                    folded.reserve(entry.g.size());
                    for (const auto& g : entry.g)
                        folded.push_back(osgBTF::foldEnvironment(*material, g));
                    _result->states.emplace_back(entry.geometry.get(),
                                                 osgBTF::environmentStateSet(*material, folded));
                }
            }
        } catch (const std::exception& e) {
            _result->error = e.what();
        }
        _done = true;
    });
}

void EnvironmentControl::install(Result& result) {
    if (!result.error.empty()) {
        _error = result.error;
        std::cerr << "btfviewer: environment: " << result.error << "\n";
        return;
    }
    _error.clear();
    for (auto& [geometry, state] : result.states) {
        if (!state) {
            auto original = _original.find(geometry);
            geometry->setStateSet(original == _original.end() ? nullptr : original->second.get());
            continue;
        }
        state->addUniform(_light->getExposureUniform());
        geometry->setStateSet(state.get());
    }
}

void EnvironmentControl::update() {
    if (!_worker.joinable()) return;
    if (changed) changed();  // the progress
    if (!_done) return;
    _worker.join();
    // Work for an older rotation or material is dropped when a newer one is pending.
    if (!_pending) install(*_result);
    _result.reset();
    if (_pending) start();
    if (changed) changed();
}

void EnvironmentControl::finish() {
    while (_worker.joinable()) {
        _worker.join();
        if (!_pending) install(*_result);
        _result.reset();
        if (_pending) start();
    }
    if (changed) changed();
}

std::string EnvironmentControl::status() const {
    std::ostringstream text;
    text << std::fixed << std::setprecision(0) << "environment: rotation " << _light->getRotation()
         << ", exposure " << std::setprecision(2) << _light->getExposure() << "  [ , . - + ]";
    if (_worker.joinable()) {
        const std::size_t total = _total, done = _progress;
        text << "  computing" << (total ? " " + std::to_string(100 * done / total) + " %" : "");
    }
    if (!_error.empty()) text << "  error: " << _error;
    return text.str();
}

}  // namespace btfviewer
