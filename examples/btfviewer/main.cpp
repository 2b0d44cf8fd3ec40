// btfviewer: an osgViewer application for BTF materials. Shows scenes, fitted materials and
// measured BTFs (through osgBTF's osgDB plugins), switches the material of every
// osgBTF::MaterialNode with keys, orbits a light with keys or Shift + mouse, and shows OSG's
// frame and GPU times (StatsHandler). `btfviewer --help` documents everything;
// examples/README.md too.
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <iomanip>
#include <iostream>
#include <sstream>
#include <system_error>

#include <osg/ApplicationUsage>
#include <osg/ArgumentParser>
#include <osg/Camera>
#include <osg/GLExtensions>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/GraphicsContext>
#include <osg/Image>
#include <osg/LightSource>
#include <osg/MatrixTransform>
#include <osg/NodeVisitor>
#include <osgDB/FileNameUtils>
#include <osgDB/ReadFile>
#include <osgDB/Registry>
#include <osgDB/WriteFile>
#include <osgGA/GUIEventHandler>
#include <osgGA/TrackballManipulator>
#include <osgShadow/ShadowMap>
#include <osgShadow/ShadowedScene>
#include <osgText/Text>
#include <osgViewer/Viewer>
#include <osgViewer/ViewerEventHandlers>

#include "core/Error.h"
#include "examples/ExampleScenes.h"
#include "examples/btfviewer/EnvironmentControl.h"
#include "examples/btfviewer/WindowSetup.h"
#include "materials/MethodRegistry.h"
#include "scene/MaterialNode.h"
#include "scene/OwnPlugins.h"
#include "scene/ShadowTerminator.h"
#include "streaming/StreamingGroup.h"

namespace {

using osgBTF::Material;
using osgBTF::MaterialNode;

constexpr const char* kKeyHelp =
    "Keys:\n"
    "  m / M            next / previous material on every object\n"
    "  1 .. 9           material N on every object\n"
    "  0                every object's own material again\n"
    "  Left / Right     orbit light azimuth -/+ 15 degrees\n"
    "  Up / Down        orbit light elevation +/- 15 degrees\n"
    "  Shift + drag     orbit the light with the mouse (left button)\n"
    "  o                orbit light on / off\n"
    "  l                the scene's own lights on / off\n"
    "  t                smooth shadow terminator on / off (every object)\n"
    "  [ / ]            terminator alpha -/+ 5 degrees\n"
    "  x                cast shadows on / off (a scene's osgShadow::ShadowedScene, or --shadows)\n"
    "  s                statistics: frame rate, then frame/event/update/cull/draw/GPU times,\n"
    "                   then scene counts (press again to cycle, off at the end)\n"
    "  , / .            --env: turn the environment -/+ 15 degrees about Z (recomputed in the\n"
    "                   background; the HUD shows the progress)\n"
    "  - / + (=)        --env: exposure / or x sqrt(2) (real time)\n"
    "  v                RTI mode: tilt the view 0 / 20 / 40 / 60 degrees from the captured one\n"
    "  h                OSG's help overlay;  f  full screen / window;  Space  home view\n"
    "  Esc              quit\n"
    "Mouse (without Shift): the trackball: left rotates, middle pans, right zooms. RTI mode\n"
    "(a capture of one view, or --rti): the view is fixed and the light follows the mouse.\n";

/** Every MaterialNode below a node, in traversal order, each once. */
class MaterialNodeCollector : public osg::NodeVisitor {
public:
    MaterialNodeCollector() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
    void apply(osg::Group& group) override {
        if (auto* node = dynamic_cast<MaterialNode*>(&group))
            if (std::find(nodes.begin(), nodes.end(), node) == nodes.end()) nodes.push_back(node);
        traverse(group);
    }
    std::vector<osg::ref_ptr<MaterialNode>> nodes;
};

/** Every LightSource below a node. */
class LightSourceCollector : public osg::NodeVisitor {
public:
    LightSourceCollector() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
    void apply(osg::LightSource& light) override {
        lights.push_back(&light);
        traverse(light);
    }
    std::vector<osg::ref_ptr<osg::LightSource>> lights;
};

/** Every ShadowedScene below a node. */
class ShadowedSceneCollector : public osg::NodeVisitor {
public:
    ShadowedSceneCollector() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
    void apply(osg::Group& group) override {
        if (auto* scene = dynamic_cast<osgShadow::ShadowedScene*>(&group))
            scenes.push_back({scene, scene->getShadowTechnique()});
        traverse(group);
    }
    std::vector<
        std::pair<osg::ref_ptr<osgShadow::ShadowedScene>, osg::ref_ptr<osgShadow::ShadowTechnique>>>
        scenes;
};

/** One material the keys can put on every object. */
struct MaterialChoice {
    osg::ref_ptr<Material> material;
    std::string label;  // "sample-laf.btfmat (laf)"
};

/** What the keys and the mouse change: the material on every MaterialNode, the orbit light,
 *  the scene's own lights; and the HUD line that says so. */
class ViewerState : public osg::Referenced {
public:
    std::vector<osg::ref_ptr<MaterialNode>> nodes;
    std::vector<osg::ref_ptr<Material>> ownMaterials;  // per node, as loaded
    std::vector<MaterialChoice> choices;
    int current = 0;  // 0: every node's own material; k: choices[k - 1] everywhere

    osg::ref_ptr<osg::LightSource> orbitLight;
    // Degrees. Azimuth 0: from -Y, the side osgViewer's home view looks from; 90: from +X (the
    // right of that view). Elevation above the XY plane (Z is up).
    double azimuth = -30, elevation = 40;
    bool orbitLightOn = true;
    std::vector<osg::ref_ptr<osg::LightSource>> sceneLights;
    bool sceneLightsOn = true;

    bool terminatorOn = true;
    double terminatorAlpha = osgBTF::kDefaultTerminatorAlpha;
    // Each ShadowedScene with the technique it had; shadows off: no technique.
    std::vector<
        std::pair<osg::ref_ptr<osgShadow::ShadowedScene>, osg::ref_ptr<osgShadow::ShadowTechnique>>>
        shadowedScenes;
    bool shadowsOn = true;

    osg::ref_ptr<osgText::Text> hud;
    osg::ref_ptr<btfviewer::EnvironmentControl> environment;  // --env

    // RTI mode: one flat patch seen as it was captured (straight down onto +Z, image up = +Y),
    // the light following the mouse as in RTIViewer; 'v' tilts the view about X.
    bool rti = false;
    double tilt = 0;  // degrees
    osg::ref_ptr<osg::Camera> camera;
    double patchHeight = 1;

    /** The light from a direction in world space (x right, y up in the captured image, z toward
     *  the camera). */
    void setLightDirection(const osg::Vec3d& d) {
        azimuth = osg::RadiansToDegrees(std::atan2(d.x(), -d.y()));
        elevation = osg::RadiansToDegrees(std::asin(std::clamp(d.z(), -1.0, 1.0)));
        placeOrbitLight();
    }
    /** RTIViewer's light control: the window is the hemisphere seen from above, the mouse's
     *  normalised position (-1..1) its x and y; outside the unit circle, the horizon. */
    void lightFromMouse(double x, double y) {
        const double r = std::sqrt(x * x + y * y);
        if (r > 1) {
            x /= r;
            y /= r;
        }
        setLightDirection(osg::Vec3d(x, y, std::sqrt(std::max(0.0, 1 - x * x - y * y))));
    }
    void placeRtiCamera() {
        // Far enough for the patch to fill ~90 % of a 30 degree field of view.
        const double t = osg::DegreesToRadians(tilt);
        const double distance = 0.55 * patchHeight / std::tan(osg::DegreesToRadians(15.0));
        camera->setViewMatrixAsLookAt(osg::Vec3d(0, -std::sin(t), std::cos(t)) * distance,
                                      osg::Vec3d(0, 0, 0), osg::Vec3d(0, std::cos(t), std::sin(t)));
        updateHud();
    }
    void cycleTilt() {
        tilt = tilt >= 60 ? 0 : tilt + 20;
        placeRtiCamera();
    }

    void applyTerminator() {
        terminatorAlpha = std::clamp(terminatorAlpha, 0.0, 60.0);
        for (const osg::ref_ptr<MaterialNode>& node : nodes) {
            node->setShadowTerminator(terminatorOn);
            node->setTerminatorAlpha(float(terminatorAlpha));
        }
        updateHud();
    }
    void toggleShadows() {
        shadowsOn = !shadowsOn;
        for (auto& [scene, technique] : shadowedScenes)
            scene->setShadowTechnique(shadowsOn ? technique.get() : nullptr);
        updateHud();
    }

    void selectMaterial(int index) {
        if (index < 0 || index > int(choices.size())) return;
        current = index;
        for (std::size_t i = 0; i < nodes.size(); ++i)
            nodes[i]->setMaterial(current == 0 ? ownMaterials[i].get()
                                               : choices[std::size_t(current - 1)].material.get());
        if (environment) environment->request();  // folded for the new method
        updateHud();
    }
    void cycleMaterial(int step) {
        const int count = int(choices.size()) + 1;
        selectMaterial(((current + step) % count + count) % count);
    }
    void orbit(double azimuthDegrees, double elevationDegrees) {
        azimuth = std::remainder(azimuth + azimuthDegrees, 360.0);
        elevation = std::clamp(elevation + elevationDegrees, -89.0, 89.0);
        placeOrbitLight();
    }
    void placeOrbitLight() {
        const double a = osg::DegreesToRadians(azimuth), e = osg::DegreesToRadians(elevation);
        orbitLight->getLight()->setPosition(osg::Vec4(float(std::cos(e) * std::sin(a)),
                                                      float(-std::cos(e) * std::cos(a)),
                                                      float(std::sin(e)), 0.0f));
        updateHud();
    }
    void toggleOrbitLight() {
        orbitLightOn = !orbitLightOn;
        orbitLight->setNodeMask(orbitLightOn ? ~0u : 0u);
        updateHud();
    }
    void toggleSceneLights() {
        sceneLightsOn = !sceneLightsOn;
        // MaterialNode skips LightSources outside the cull mask, like the CullVisitor does.
        for (const osg::ref_ptr<osg::LightSource>& light : sceneLights)
            light->setNodeMask(sceneLightsOn ? ~0u : 0u);
        updateHud();
    }
    void updateHud() {
        if (!hud) return;
        std::ostringstream text;
        text << "material: "
             << (current == 0 ? std::string("each object's own")
                              : choices[std::size_t(current - 1)].label)
             << "  [m, 0-9]\n"
             << std::fixed << std::setprecision(0)
             << "orbit light: " << (orbitLightOn ? "on" : "off") << ", azimuth " << azimuth
             << ", elevation " << elevation << "  [arrows, Shift+drag, o]\n"
             << "scene lights: " << sceneLights.size()
             << (sceneLights.empty() ? ""
                 : sceneLightsOn     ? " on"
                                     : " off")
             << "  [l]\n"
             << "terminator: " << (terminatorOn ? "on" : "off") << ", alpha " << terminatorAlpha
             << "  [t, [, ]]   cast shadows: "
             << (shadowedScenes.empty() ? "none"
                 : shadowsOn            ? "on"
                                        : "off")
             << "  [x]"
             << "   stats [s]  help [h]";
        if (rti)
            text << "\nRTI mode: the light follows the mouse; view tilted " << tilt
                 << " degrees from the captured one  [v]";
        if (environment) text << "\n" << environment->status();
        if (streaming) text << "\n" << streamingStatus();
        hud->setText(text.str());
    }

    /** BSVTF (--stream): what has arrived and the GPU memory it takes, against plain fmf. */
    std::string streamingStatus() const {
        const osgBTF::TileStreamer& streamer = *streaming->streamer();
        const osgBTF::StreamingStats s = streamer.stats();
        std::ostringstream text;
        text << std::fixed << std::setprecision(1) << "streaming: " << streamer.materialCount()
             << " materials, " << s.residentTiles << " of " << streamer.scheduler().capacity()
             << " cache tiles, U " << s.uPacketsReceived << "/" << s.uPackets << ", "
             << double(s.bytesReceived) / 1048576.0 << " MiB received"
             << (s.failures ? ", " + std::to_string(s.failures) + " failed" : std::string())
             << (streaming->settled() ? ", converged" : "")
             << "\nGPU: " << double(streamer.gpuBytes()) / 1048576.0
             << " MiB (as plain fmf: " << double(plainFmfBytes) / 1048576.0 << " MiB)";
        return text.str();
    }

    osg::ref_ptr<osgBTF::StreamingGroup> streaming;
    std::uint64_t plainFmfBytes = 0;

protected:
    ~ViewerState() override = default;
};

class ControlHandler : public osgGA::GUIEventHandler {
public:
    explicit ControlHandler(ViewerState* state) : _state(state) {}

    bool handle(const osgGA::GUIEventAdapter& ea, osgGA::GUIActionAdapter&) override {
        using GEA = osgGA::GUIEventAdapter;
        switch (ea.getEventType()) {
            case GEA::FRAME:
                // The streaming line changes as tiles arrive, without any event.
                if (_state->streaming) _state->updateHud();
                return false;
            case GEA::KEYDOWN:
                return handleKey(ea.getKey());
            case GEA::MOVE:
                if (!_state->rti) return false;
                _state->lightFromMouse(ea.getXnormalized(), ea.getYnormalized());
                return true;
            case GEA::PUSH:
                if (_state->rti && !(ea.getModKeyMask() & GEA::MODKEY_SHIFT)) return true;
                if ((ea.getModKeyMask() & GEA::MODKEY_SHIFT) &&
                    ea.getButtonMask() == GEA::LEFT_MOUSE_BUTTON) {
                    _dragging = true;
                    _lastX = ea.getXnormalized();
                    _lastY = ea.getYnormalized();
                    return true;  // handled events are ignored by the trackball
                }
                return false;
            case GEA::DRAG:
                if (_state->rti && !_dragging) {
                    _state->lightFromMouse(ea.getXnormalized(), ea.getYnormalized());
                    return true;
                }
                if (!_dragging) return false;
                // A drag across the whole window turns the light half around.
                _state->orbit(-90.0 * (ea.getXnormalized() - _lastX),
                              45.0 * (ea.getYnormalized() - _lastY));
                _lastX = ea.getXnormalized();
                _lastY = ea.getYnormalized();
                return true;
            case GEA::RELEASE:
                if (!_dragging) return false;
                _dragging = false;
                return true;
            default:
                return false;
        }
    }

    void getUsage(osg::ApplicationUsage& usage) const override {
        usage.addKeyboardMouseBinding("m", "Next material on every object (M: previous)");
        usage.addKeyboardMouseBinding("1-9", "Material N on every object");
        usage.addKeyboardMouseBinding("0", "Every object's own material");
        usage.addKeyboardMouseBinding("Left/Right", "Orbit light azimuth");
        usage.addKeyboardMouseBinding("Up/Down", "Orbit light elevation");
        usage.addKeyboardMouseBinding("Shift+drag", "Orbit the light with the mouse");
        usage.addKeyboardMouseBinding("o", "Orbit light on/off");
        usage.addKeyboardMouseBinding("l", "The scene's own lights on/off");
        usage.addKeyboardMouseBinding("t", "Smooth shadow terminator on/off");
        usage.addKeyboardMouseBinding("[ / ]", "Terminator alpha -/+ 5 degrees");
        usage.addKeyboardMouseBinding("x", "Cast shadows on/off");
        usage.addKeyboardMouseBinding("v", "RTI mode: tilt the view");
        usage.addKeyboardMouseBinding(", .", "--env: turn the environment -/+ 15 degrees");
        usage.addKeyboardMouseBinding("- +", "--env: exposure / or x sqrt(2)");
    }

protected:
    ~ControlHandler() override = default;

private:
    bool handleKey(int key) {
        using GEA = osgGA::GUIEventAdapter;
        if (key == 'm')
            _state->cycleMaterial(+1);
        else if (key == 'M')
            _state->cycleMaterial(-1);
        else if (key >= '0' && key <= '9')
            _state->selectMaterial(key - '0');
        else if (key == GEA::KEY_Left)
            _state->orbit(-15, 0);
        else if (key == GEA::KEY_Right)
            _state->orbit(+15, 0);
        else if (key == GEA::KEY_Up)
            _state->orbit(0, +15);
        else if (key == GEA::KEY_Down)
            _state->orbit(0, -15);
        else if (key == 'o')
            _state->toggleOrbitLight();
        else if (key == 'l')
            _state->toggleSceneLights();
        else if (key == 't') {
            _state->terminatorOn = !_state->terminatorOn;
            _state->applyTerminator();
        } else if (key == '[' || key == ']') {
            _state->terminatorAlpha += key == ']' ? 5 : -5;
            _state->applyTerminator();
        } else if (key == 'x')
            _state->toggleShadows();
        else if (_state->environment && (key == ',' || key == '.'))
            _state->environment->rotate(key == ',' ? -15.0f : 15.0f);
        else if (_state->environment && (key == '-' || key == '+' || key == '='))
            _state->environment->scaleExposure(key == '-' ? std::sqrt(0.5f) : std::sqrt(2.0f));
        else
            return false;
        return true;
    }

    osg::ref_ptr<ViewerState> _state;
    bool _dragging = false;
    float _lastX = 0, _lastY = 0;
};

/** Reads back the finished frame (every camera of the window drawn: scene, HUD, statistics)
 *  just before the buffers swap, on the frame it is armed for. */
class CaptureSwapCallback : public osg::GraphicsContext::SwapCallback {
public:
    void swapBuffersImplementation(osg::GraphicsContext* context) override {
        if (armed.exchange(false)) {
            const osg::GraphicsContext::Traits* traits = context->getTraits();
            osg::ref_ptr<osg::Image> captured = new osg::Image;
            captured->readPixels(0, 0, traits->width, traits->height, GL_RGB, GL_UNSIGNED_BYTE);
            image = captured;
        }
        context->swapBuffersImplementation();
    }
    std::atomic<bool> armed{false};
    osg::ref_ptr<osg::Image> image;

protected:
    ~CaptureSwapCallback() override = default;
};

/** Runs once with the new window's context current: notes the renderer and whether OSG's
 *  statistics can show GPU times (a timer query extension). */
class GlInfoOperation : public osg::GraphicsOperation {
public:
    GlInfoOperation() : osg::GraphicsOperation("btfviewer GL info", false) {}
    void operator()(osg::GraphicsContext* context) override {
        const unsigned id = context->getState()->getContextID();
        const auto* renderer = reinterpret_cast<const char*>(glGetString(GL_RENDERER));
        const bool arb = osg::isGLExtensionSupported(id, "GL_ARB_timer_query");
        const bool ext = osg::isGLExtensionSupported(id, "GL_EXT_timer_query");
        std::cout << "btfviewer: OpenGL renderer " << (renderer ? renderer : "(unknown)")
                  << "; GPU times in the statistics: "
                  << (arb   ? "yes (GL_ARB_timer_query)"
                      : ext ? "yes (GL_EXT_timer_query)"
                            : "no (no GL_ARB_timer_query: the GPU row stays empty)")
                  << std::endl;
    }

protected:
    ~GlInfoOperation() override = default;
};

/** The HUD: status lines at the bottom left, over the scene, never lit or depth-tested. */
osg::ref_ptr<osg::Camera> createHud(osgText::Text* text) {
    osg::ref_ptr<osg::Camera> camera = new osg::Camera;
    camera->setReferenceFrame(osg::Transform::ABSOLUTE_RF);
    camera->setProjectionMatrixAsOrtho2D(0, 1280, 0, 1024);
    camera->setViewMatrix(osg::Matrix::identity());
    camera->setClearMask(GL_DEPTH_BUFFER_BIT);
    camera->setRenderOrder(osg::Camera::POST_RENDER);
    camera->setAllowEventFocus(false);
    text->setCharacterSize(20.0f);
    // Bottom left: the statistics ('s') take the top of the window.
    text->setPosition(osg::Vec3(10.0f, 10.0f, 0.0f));
    text->setAlignment(osgText::Text::LEFT_BOTTOM_BASE_LINE);
    text->setColor(osg::Vec4(1.0f, 1.0f, 0.8f, 1.0f));
    text->setDataVariance(osg::Object::DYNAMIC);
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(text);
    geode->getOrCreateStateSet()->setMode(GL_LIGHTING, osg::StateAttribute::OFF);
    geode->getOrCreateStateSet()->setMode(GL_DEPTH_TEST, osg::StateAttribute::OFF);
    camera->addChild(geode.get());
    return camera;
}

/** A flat rectangle of width x height metres in the XY plane around the origin (Z up, normal +Z),
 *  texture coordinates 0..1 across it: --surface-size's model (a square) and RTI mode's patch. */
osg::ref_ptr<osg::Geode> createSurfaceModel(float width, float height) {
    osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec2Array> texCoords = new osg::Vec2Array;
    for (const osg::Vec2 corner :
         {osg::Vec2(0, 0), osg::Vec2(1, 0), osg::Vec2(1, 1), osg::Vec2(0, 1)}) {
        vertices->push_back(
            osg::Vec3((corner.x() - 0.5f) * width, (corner.y() - 0.5f) * height, 0));
        texCoords->push_back(corner);
    }
    geometry->setVertexArray(vertices.get());
    geometry->setTexCoordArray(0, texCoords.get());
    // Per-vertex normals and triangles: what --env's per-vertex program needs.
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array(4);
    std::fill(normals->begin(), normals->end(), osg::Vec3(0, 0, 1));
    geometry->setNormalArray(normals.get(), osg::Array::BIND_PER_VERTEX);
    osg::ref_ptr<osg::DrawElementsUShort> triangles = new osg::DrawElementsUShort(GL_TRIANGLES);
    for (unsigned short i : {0, 1, 2, 0, 2, 3}) triangles->push_back(i);
    geometry->addPrimitiveSet(triangles.get());
    geometry->setName("btfviewer surface");
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(geometry.get());
    return geode;
}

/** Reads one input through osgDB; throws Error "FILE: problem" with osgDB's reason. */
osg::ref_ptr<osg::Node> readInput(const std::string& file) {
    osgDB::ReaderWriter::ReadResult result =
        osgDB::Registry::instance()->readNode(file, osgDB::Registry::instance()->getOptions());
    if (result.validNode()) return result.getNode();
    switch (result.status()) {
        case osgDB::ReaderWriter::ReadResult::FILE_NOT_HANDLED:
            osgBTF::fail(file, "no osgDB plugin reads this file");
        case osgDB::ReaderWriter::ReadResult::FILE_NOT_FOUND:
            // A pseudo-loader name: the plugin says which part is missing.
            if (result.message().empty() || result.message() == file + ": no such file")
                osgBTF::fail(file, "no such file");
            osgBTF::fail(file, result.message());
        default: {
            std::string message = result.message();
            // osgBTF's plugins already name the file; OSG's own messages often do not.
            if (message.rfind(file, 0) == 0) throw osgBTF::Error(message);
            osgBTF::fail(file, message.empty() ? "cannot be read as a scene" : message);
        }
    }
}

/** Writes an image through osgDB to a temporary name, then renames it. */
void writeImageAtomically(const osg::Image& image, const std::string& path) {
    namespace fs = std::filesystem;
    const fs::path target(path);
    const fs::path temporary =
        target.parent_path() / ("." + target.stem().string() + ".tmp-" +
                                std::to_string(::getpid()) + target.extension().string());
    if (!osgDB::writeImageFile(image, temporary.string())) {
        std::error_code ignored;
        fs::remove(temporary, ignored);
        osgBTF::fail(path, "cannot write the capture (no osgDB image writer for '" +
                               target.extension().string() + "' or the folder is not writable)");
    }
    std::error_code error;
    fs::rename(temporary, target, error);
    if (error) {
        fs::remove(temporary, error);
        osgBTF::fail(path, "cannot rename the capture into place: " + error.message());
    }
}

int run(osg::ArgumentParser& arguments) {
    osg::ApplicationUsage* usage = arguments.getApplicationUsage();
    usage->setApplicationName("btfviewer");
    usage->setDescription(
        "btfviewer: views BTF materials with OpenSceneGraph. Each FILE is a scene (.osgt, .osgb, "
        "any model osgDB reads, e.g. the example scenes of btf-examples), a fitted material "
        "(.btfmat, shown on a sphere or --model), a UBO2014 .btf (rendered as stored: an fmf "
        "material of its factors, nothing decoded), a measured BTF (.zip, or a .btf with -O "
        "\"method=NAME ...\": fitted on load and cached by osgBTF's plugins) or a pseudo-loader "
        "name MODEL.(MATERIAL[,scale=S]).btfmaterial. Several files are laid out side by side. "
        "The keys put any material found on every object. The statistics ('s') show frame, "
        "cull, draw and GPU times; the GPU times need GL_ARB_timer_query (Mesa and the NVIDIA "
        "driver have it; without it OSG leaves the GPU bar out).");
    usage->setCommandLineUsage("btfviewer [options] FILE...");
    usage->addCommandLineOption("--model FILE",
                                "Model under material files (default: a sphere, poles on Z)");
    usage->addCommandLineOption("--scale S",
                                "Texture scale of materials given as files: repeats per texture "
                                "coordinate unit (default 4; 1 with --surface-size)");
    usage->addCommandLineOption(
        "--surface-size S",
        "Model under material files: a flat square of S x S metres (Z up, texture coordinates "
        "0..1 across it, so --scale is the repeats over the whole surface), seen from above at "
        "an angle");
    usage->addCommandLineOption(
        "--map FILE",
        "Draw materials given as files through this coordinate map (btf synthesize -o FILE): "
        "the map covers each texture repeat, each of its texels showing the sample texel it "
        "names");
    usage->addCommandLineOption("--material N",
                                "Start with material N on every object (as key N; 0 = own)");
    usage->addCommandLineOption(
        "--light AZ EL",
        "Orbit light direction in degrees (default -30 40): azimuth 0 lights from -Y, the side "
        "the home view looks from, 90 from +X (its right); elevation above the XY plane (Z up)");
    usage->addCommandLineOption("--no-orbit-light", "Start with the orbit light off");
    usage->addCommandLineOption("--no-scene-lights", "Start with the scene's own lights off");
    usage->addCommandLineOption("--terminator-alpha DEG",
                                "The smooth shadow terminator of Sattler et al. 2003 on every "
                                "object with this alpha (default: each "
                                "object's own, 15 unless its scene says otherwise; 0..60)");
    usage->addCommandLineOption("--no-terminator", "Start with the terminator off everywhere");
    usage->addCommandLineOption(
        "--shadows",
        "Cast shadows: the inputs go into an osgShadow::ShadowedScene with a ShadowMap, the "
        "orbit light last in it (the light it shadows; with the orbit light off, the scene's "
        "last light); a scene with its own ShadowedScene keeps it");
    usage->addCommandLineOption(
        "--rti",
        "RTI mode (the default for one material or capture of a single view, e.g. an RTI "
        "capture's .lp file): a flat patch of the material's aspect, seen as captured, the light "
        "following the mouse as in RTIViewer, 'v' tilts the view");
    usage->addCommandLineOption("--no-rti", "Not RTI mode, even for a capture of one view");
    usage->addCommandLineOption("--no-shadows",
                                "Start with cast shadows off (as key x): every ShadowedScene "
                                "without its technique");
    usage->addCommandLineOption("--stats", "Show the frame/GPU time statistics from the start");
    usage->addCommandLineOption("--no-hud", "No status text");
    usage->addCommandLineOption("--frames N", "Render N frames, then exit (default: until Esc)");
    usage->addCommandLineOption(
        "--capture FILE",
        "Write the last of --frames frames (default 3) to FILE (.png, .jpg, ... by the "
        "extension) and exit; runs single-threaded");
    usage->addCommandLineOption(
        "--env FILE",
        "Light every BTF material by this HDR lat-long environment (.hdr, .exr; +Z up, top row "
        "the zenith): " +
            osgBTF::environmentMethodsText() +
            " per vertex with the scene's self-shadowing (recomputed in the background when the "
            "environment turns or the material changes), the other methods by 8 median-cut "
            "lights; the orbit and scene lights start off");
    usage->addCommandLineOption("--exposure E", "--env: exposure (default 1)");
    usage->addCommandLineOption("--env-rotation DEG",
                                "--env: turn the environment about Z (degrees, default 0)");
    usage->addCommandLineOption(
        "--env-samples A",
        "--env: illumination PCA (Sattler et al. 2003, 5.3): compute A rotations up front (A times "
        "the "
        "work), then rebuild any rotation at once from 5 components (default 0: each rotation "
        "computed exactly; Sattler et al. 2003 use 30)");
    usage->addCommandLineOption(
        "--stream LOCATION",
        "A BSVTF tile set (`btf tiles`; a folder or an http:// URL of one) streamed into the "
        "shared tile cache, on the model like a material file; repeatable (Schwartz et al. 2013)");
    usage->addCommandLineOption("--cache-size N",
                                "--stream: texels per side of the RGBA16F tile cache (default "
                                "4032: 3136 tiles, 124 MiB)");
    usage->addCommandLineOption("-O \"OPTIONS\"", "osgDB options for the plugins");
    usage->addCommandLineOption("-h, --help", "This text and the keys");

    if (arguments.read("-h") || arguments.read("--help")) {
        std::cout << usage->getDescription() << "\n\n";
        usage->write(std::cout, osg::ApplicationUsage::COMMAND_LINE_OPTION);  // usage + options
        std::cout << "\nosgViewer's own options work too: --window X Y W H, --screen N, "
                     "--run-on-demand, ...\n\n"
                  << kKeyHelp;
        return 0;
    }

    std::string modelFile, captureFile, pluginOptions, mapFile, envFile;
    float exposure = 1, envRotation = 0;
    float textureScale = 4, surfaceSize = 0;
    int firstMaterial = 0, frames = -1;
    double azimuth = -30, elevation = 40;
    while (arguments.read("--model", modelFile)) {
    }
    bool scaleGiven = false;
    while (arguments.read("--scale", textureScale)) scaleGiven = true;
    bool surfaceGiven = false;
    while (arguments.read("--surface-size", surfaceSize)) surfaceGiven = true;
    while (arguments.read("--map", mapFile)) {
    }
    while (arguments.read("--material", firstMaterial)) {
    }
    while (arguments.read("--light", azimuth, elevation)) {
    }
    while (arguments.read("--frames", frames)) {
    }
    while (arguments.read("--capture", captureFile)) {
    }
    while (arguments.read("-O", pluginOptions)) {
    }
    while (arguments.read("--env", envFile)) {
    }
    while (arguments.read("--exposure", exposure)) {
    }
    while (arguments.read("--env-rotation", envRotation)) {
    }
    int envSamples = 0;
    while (arguments.read("--env-samples", envSamples)) {
    }
    std::vector<std::string> streams;
    for (std::string location; arguments.read("--stream", location);) streams.push_back(location);
    int cacheSize = osgBTF::TileStreamerOptions().cacheSize;
    while (arguments.read("--cache-size", cacheSize)) {
    }
    if (envSamples < 0 || envSamples == 1)
        throw osgBTF::Error("--env-samples " + std::to_string(envSamples) +
                            ": expected 0 (off) or at least 2 rotations");
    const bool noOrbitLight = arguments.read("--no-orbit-light");
    const bool noSceneLights = arguments.read("--no-scene-lights");
    const bool showStats = arguments.read("--stats");
    const bool noHud = arguments.read("--no-hud");
    double terminatorAlpha = -1;
    while (arguments.read("--terminator-alpha", terminatorAlpha)) {
    }
    const bool noTerminator = arguments.read("--no-terminator");
    const bool shadows = arguments.read("--shadows");
    const bool noShadows = arguments.read("--no-shadows");
    const bool rtiForced = arguments.read("--rti"), rtiRefused = arguments.read("--no-rti");
    if (rtiForced && rtiRefused) throw osgBTF::Error("--rti and --no-rti: give one of them");
    if (shadows && noShadows) throw osgBTF::Error("--shadows and --no-shadows: give one of them");
    if (!captureFile.empty() && frames < 0) frames = 3;
    if (!captureFile.empty() && frames < 1)
        throw osgBTF::Error("--frames: at least 1 frame is needed for --capture");
    if (!(textureScale > 0)) throw osgBTF::Error("--scale: must be positive");
    if (surfaceGiven && !(surfaceSize > 0))
        throw osgBTF::Error("--surface-size: must be positive (metres)");
    if (surfaceGiven && !modelFile.empty())
        throw osgBTF::Error("--surface-size and --model: give one of them");
    if (surfaceGiven && !scaleGiven) textureScale = 1;
    if (terminatorAlpha != -1 && !(terminatorAlpha >= 0 && terminatorAlpha <= 60))
        throw osgBTF::Error("--terminator-alpha: must be 0..60 degrees");

    // osgViewer::Viewer reads its own options (--window, --screen, ...) from the arguments.
    osgViewer::Viewer viewer(arguments);
    if (!pluginOptions.empty()) {
        osgDB::Registry::instance()->setOptions(new osgDB::Options(pluginOptions));
    }

    arguments.reportRemainingOptionsAsUnrecognized();
    if (arguments.errors()) {
        std::ostringstream text;
        arguments.writeErrorMessages(text);
        std::string message = text.str();
        while (!message.empty() && message.back() == '\n') message.pop_back();
        throw osgBTF::Error(message + " (btfviewer --help lists the options)");
    }
    std::vector<std::string> files;
    for (int i = 1; i < arguments.argc(); ++i) files.push_back(arguments[i]);
    if (files.empty() && streams.empty()) throw osgBTF::Error("no input files (btfviewer --help)");

    // Inputs: a MaterialNode without children (a material file) gets the model.
    osg::ref_ptr<osg::Node> model;
    std::vector<osg::ref_ptr<osg::Node>> inputs;
    osg::ref_ptr<osgBTF::StreamingGroup> streaming;
    std::uint64_t plainFmfBytes = 0;
    if (!streams.empty()) {
        osgBTF::TileStreamerOptions options;
        options.cacheSize = cacheSize;
        streaming = new osgBTF::StreamingGroup(new osgBTF::TileStreamer(options));
    }
    std::vector<std::pair<std::string, osg::ref_ptr<osg::Node>>> named;
    for (const std::string& file : files) named.emplace_back(file, readInput(file));
    for (const std::string& location : streams) {
        const osg::ref_ptr<osgBTF::StreamedFmfMaterial> streamed =
            streaming->streamer()->open(location);
        plainFmfBytes += streaming->streamer()->plainFmfGpuBytes(streamed->streamIndex());
        named.emplace_back(location, new MaterialNode(streamed.get()));
    }
    // RTI mode: one material file (or capture) and nothing that places it elsewhere; by default
    // when its material has a single measured view.
    const auto* single = named.size() == 1 && streams.empty()
                             ? dynamic_cast<MaterialNode*>(named.front().second.get())
                             : nullptr;
    const bool singleMaterial = single && single->getNumChildren() == 0 && single->getMaterial();
    const bool placed = !modelFile.empty() || surfaceGiven || !mapFile.empty();
    if (rtiForced && (!singleMaterial || placed))
        throw osgBTF::Error(
            "--rti: needs exactly one material file or capture, without --model, --surface-size "
            "or --map");
    const bool rtiMode = rtiForced || (!rtiRefused && singleMaterial && !placed &&
                                       single->getMaterial()->views().size() == 1);
    if (rtiMode) {
        const Material& m = *single->getMaterial();
        // A mip-mapped material's texels are its atlas; the capture is its base level.
        const bool mipmapped = m.mipLayout().levelCount() > 0;
        const int width = mipmapped ? m.mipLayout().baseWidth() : m.width();
        const int height = mipmapped ? m.mipLayout().baseHeight() : m.height();
        model = createSurfaceModel(float(width) / float(height), 1.0f);
        if (!scaleGiven) textureScale = 1;
        std::cout << "btfviewer: RTI mode (" << width << "x" << height << ", " << m.views().size()
                  << " view(s), " << m.lights().size()
                  << " lights): the light follows the mouse, 'v' tilts the view\n";
    }
    for (const auto& [file, node] : named) {
        auto* material = dynamic_cast<MaterialNode*>(node.get());
        if (material && material->getNumChildren() == 0) {
            if (!model)
                model = surfaceGiven
                            ? osg::ref_ptr<osg::Node>(createSurfaceModel(surfaceSize, surfaceSize))
                        : modelFile.empty()
                            ? osg::ref_ptr<osg::Node>(osgBTF::examples::createSphereModel())
                            : readInput(modelFile);
            material->setTextureScale(textureScale);
            if (!mapFile.empty()) {
                if (!material->setCoordinateMapFile(mapFile))
                    throw osgBTF::Error(material->getCoordinateMapError());
                const osgBTF::CoordinateMap& map = *material->getCoordinateMap();
                std::cout << "btfviewer: " << file << " through the coordinate map " << mapFile
                          << ": " << map.width << "x" << map.height
                          << " texels per repeat from the " << map.sampleWidth << "x"
                          << map.sampleHeight << " sample, " << textureScale
                          << " repeat(s) per texture coordinate unit\n";
            }
            // --env puts per-vertex data into the geometries' StateSets: one copy per object.
            material->addChild(envFile.empty()
                                   ? model.get()
                                   : osg::clone(model.get(), osg::CopyOp::DEEP_COPY_NODES |
                                                                 osg::CopyOp::DEEP_COPY_DRAWABLES));
        }
        inputs.push_back(node);
    }
    if ((!mapFile.empty() || surfaceGiven) && !model)
        std::cerr << "btfviewer: note: --map and --surface-size apply to material files (a "
                     "scene keeps its own models and maps)\n";

    osg::ref_ptr<osg::Group> root = new osg::Group;
    osg::ref_ptr<osg::Group> sceneRoot = new osg::Group;
    // Side by side along +X, a fifth of a radius apart; more than 5 objects in rows downward
    // (-Z), facing the home view.
    const std::size_t columns =
        inputs.size() > 5 ? std::size_t(std::ceil(std::sqrt(double(inputs.size())))) : 5;
    float x = 0, z = 0, rowDepth = 0;
    for (std::size_t i = 0; i < inputs.size(); ++i) {
        if (inputs.size() == 1) {
            sceneRoot->addChild(inputs[i].get());
            break;
        }
        const osg::BoundingSphere bound = inputs[i]->getBound();
        const float radius = bound.valid() ? bound.radius() : 1.0f;
        if (i > 0 && i % columns == 0) {
            x = 0;
            z -= rowDepth;
            rowDepth = 0;
        }
        x += i % columns == 0 ? 0.0f : radius * 1.1f;
        osg::ref_ptr<osg::MatrixTransform> place = new osg::MatrixTransform(osg::Matrix::translate(
            osg::Vec3(x, 0, z) - (bound.valid() ? bound.center() : osg::Vec3())));
        place->addChild(inputs[i].get());
        sceneRoot->addChild(place.get());
        x += radius * 1.1f;
        rowDepth = std::max(rowDepth, radius * 2.2f);
    }
    // Streamed materials need the feedback pass and updates of a StreamingGroup above them.
    osg::ref_ptr<osg::Group> sceneTop = sceneRoot;
    if (streaming) {
        streaming->addChild(sceneRoot.get());
        sceneTop = streaming;
    }
    osg::ref_ptr<ViewerState> state = new ViewerState;
    ShadowedSceneCollector shadowed;
    sceneRoot->accept(shadowed);
    // The orbit light goes last into the ShadowedScene --shadows makes, so it is the light the
    // ShadowMap shadows; elsewhere it stays outside the scenes.
    osg::ref_ptr<osg::Group> orbitParent = root;
    if (shadows && shadowed.scenes.empty()) {
        osg::ref_ptr<osgShadow::ShadowedScene> scene = new osgShadow::ShadowedScene;
        osg::ref_ptr<osgShadow::ShadowMap> technique = new osgShadow::ShadowMap;
        technique->setTextureSize(osg::Vec2s(2048, 2048));
        scene->setShadowTechnique(technique.get());
        scene->addChild(sceneTop.get());
        root->addChild(scene.get());
        shadowed.scenes.push_back({scene, technique});
        orbitParent = scene;
    } else {
        root->addChild(sceneTop.get());
    }
    state->shadowedScenes = shadowed.scenes;
    state->streaming = streaming;
    state->plainFmfBytes = plainFmfBytes;
    if (noShadows) state->toggleShadows();

    MaterialNodeCollector materialNodes;
    sceneRoot->accept(materialNodes);
    LightSourceCollector lights;
    sceneRoot->accept(lights);
    state->sceneLights = lights.lights;
    for (const osg::ref_ptr<MaterialNode>& node : materialNodes.nodes) {
        state->nodes.push_back(node);
        state->ownMaterials.push_back(node->getMaterial());
        Material* material = node->getMaterial();
        if (!material) continue;
        const bool known =
            std::any_of(state->choices.begin(), state->choices.end(),
                        [&](const MaterialChoice& choice) { return choice.material == material; });
        if (known) continue;
        const std::string name = !node->getMaterialFile().empty()
                                     ? osgDB::getSimpleFileName(node->getMaterialFile())
                                 : !material->sourceFile.empty() ? material->sourceFile
                                                                 : std::string("in memory");
        state->choices.push_back({material, name + " (" + material->methodName() + ")"});
    }
    if (state->nodes.empty())
        std::cerr << "btfviewer: note: no osgBTF material in the input; the keys that switch "
                     "materials do nothing\n";
    std::cout << "btfviewer: " << state->nodes.size() << " object(s) with a BTF material, "
              << state->choices.size() << " material(s):\n";
    for (std::size_t i = 0; i < state->choices.size(); ++i)
        std::cout << "  " << i + 1 << ": " << state->choices[i].label << "\n";

    // The orbit light: directional, in world space (Z up), white.
    state->orbitLight = new osg::LightSource;
    state->orbitLight->setName("btfviewer orbit light");
    state->orbitLight->getLight()->setLightNum(7);  // clear of the scene's usual 0, 1, ...
    state->orbitLight->getLight()->setDiffuse(osg::Vec4(1, 1, 1, 1));
    state->orbitLight->getLight()->setSpecular(osg::Vec4(1, 1, 1, 1));
    state->azimuth = azimuth;
    state->elevation = std::clamp(elevation, -89.0, 89.0);
    orbitParent->addChild(state->orbitLight.get());
    if (!noHud) {
        state->hud = new osgText::Text;
        root->addChild(createHud(state->hud.get()).get());
    }
    state->placeOrbitLight();
    if (noOrbitLight) state->toggleOrbitLight();
    if (noSceneLights) state->toggleSceneLights();
    if (firstMaterial < 0 || firstMaterial > int(state->choices.size()))
        throw osgBTF::Error("--material " + std::to_string(firstMaterial) + ": there are " +
                            std::to_string(state->choices.size()) + " materials (0 = own)");
    state->selectMaterial(firstMaterial);
    if (terminatorAlpha >= 0 || noTerminator) {
        if (terminatorAlpha >= 0) state->terminatorAlpha = terminatorAlpha;
        state->terminatorOn = !noTerminator;
        state->applyTerminator();
    } else if (!state->nodes.empty()) {
        state->terminatorOn = state->nodes.front()->getShadowTerminator();
        state->terminatorAlpha = state->nodes.front()->getTerminatorAlpha();
        state->updateHud();
    }
    if (!envFile.empty()) {
        state->environment = new btfviewer::EnvironmentControl(envFile, exposure, envRotation,
                                                               envSamples, sceneRoot.get());
        state->environment->setChanged([s = state.get()] { s->updateHud(); });
        if (!noOrbitLight) state->toggleOrbitLight();
        if (!noSceneLights && !state->sceneLights.empty()) state->toggleSceneLights();
    }

    viewer.setSceneData(root.get());
    osg::ref_ptr<osgGA::TrackballManipulator> manipulator = new osgGA::TrackballManipulator;
    if (surfaceGiven && inputs.size() == 1) {
        // A floor: seen from the front (-Y) and above at about 30 degrees, not edge-on as the
        // automatic home view (from -Y, level) would show it.
        manipulator->setAutoComputeHomePosition(false);
        manipulator->setHomePosition(osg::Vec3d(0, -0.85 * surfaceSize, 0.5 * surfaceSize),
                                     osg::Vec3d(0, 0.05 * surfaceSize, 0), osg::Vec3d(0, 0, 1));
    }
    if (rtiMode) {
        // No manipulator: the view matrix is the captured view's (ViewerState::placeRtiCamera).
        state->rti = true;
        state->camera = viewer.getCamera();
        state->placeRtiCamera();
    } else {
        viewer.setCameraManipulator(manipulator.get());
    }
    viewer.addEventHandler(new ControlHandler(state.get()));
    viewer.addEventHandler(new osgViewer::StatsHandler);
    viewer.addEventHandler(new osgViewer::HelpHandler(usage));
    viewer.addEventHandler(new osgViewer::WindowSizeHandler);

    if (!captureFile.empty())
        viewer.setThreadingModel(osgViewer::Viewer::SingleThreaded);  // the read-back is in step
    viewer.setRealizeOperation(new GlInfoOperation);
    btfviewer::openWindow(viewer);  // --window's, or one that fits the screen; throws why not
    osg::ref_ptr<CaptureSwapCallback> capture;
    if (!captureFile.empty()) {
        osg::GraphicsContext* context = viewer.getCamera()->getGraphicsContext();
        if (!context) throw osgBTF::Error("--capture: the viewer has no window to read back");
        capture = new CaptureSwapCallback;
        context->setSwapCallback(capture.get());
    }
    // The StatsHandler cycles on 's'; its second page has the frame and GPU times. The keys are
    // queued after the first frame: realize() restarts the event clock, and the handler decides
    // whether to show a GPU row when it first opens, from the extensions of a context that has
    // drawn.
    auto pressStatsKeys = [&] {
        if (!showStats) return;
        viewer.getEventQueue()->keyPress('s');
        viewer.getEventQueue()->keyPress('s');
    };
    if (frames < 0) {
        viewer.frame();
        pressStatsKeys();
        return viewer.run();
    }
    // A fixed number of frames shows the finished environment lighting (--env's, and that of
    // any osgBTF::EnvironmentLitGroup in the scene files).
    struct LitGroups : osg::NodeVisitor {
        LitGroups() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
        void apply(osg::Group& group) override {
            if (auto* lit = dynamic_cast<osgBTF::EnvironmentLitGroup*>(&group)) lit->finish();
            traverse(group);
        }
    } litGroups;
    root->accept(litGroups);
    for (int frame = 0; frame < frames && !viewer.done(); ++frame) {
        if (frame == 1) pressStatsKeys();
        if (capture && frame == frames - 1) capture->armed = true;
        viewer.frame();
    }
    if (capture) {
        if (!capture->image) throw osgBTF::Error(captureFile + ": no frame was captured");
        writeImageAtomically(*capture->image, captureFile);
        std::cout << "btfviewer: wrote " << captureFile << " (" << capture->image->s() << "x"
                  << capture->image->t() << ")\n";
    }
    return 0;
}

}  // namespace

int main(int argc, char** argv) {
    osgBTF::useOwnPlugins();  // the material readers and osgdb_btfexr, without OSG_LIBRARY_PATH
    osg::ArgumentParser arguments(&argc, argv);
    try {
        return run(arguments);
    } catch (const std::exception& e) {
        std::cerr << "btfviewer: " << e.what() << "\n";
        return 1;
    }
}
