#include "examples/btf-examples/SceneBench.h"

#include <cmath>
#include <cstdio>
#include <map>
#include <sstream>

#include <osg/LightSource>
#include <osg/Transform>

#include "scene/MaterialNode.h"

#include "core/Error.h"
#include "harness/headless/HeadlessRenderer.h"

namespace osgBTF::examples {

void setSceneLightCount(osg::Group& scene, int count) {
    if (count < 1 || count > 8)
        throw Error("scene lights: " + std::to_string(count) + " is not in 1..8");
    std::vector<osg::LightSource*> lights;
    for (unsigned i = 0; i < scene.getNumChildren(); ++i)
        if (auto* light = dynamic_cast<osg::LightSource*>(scene.getChild(i)))
            lights.push_back(light);
    for (std::size_t i = std::size_t(count); i < lights.size(); ++i) scene.removeChild(lights[i]);
    for (int n = int(lights.size()); n < count; ++n) {
        osg::ref_ptr<osg::LightSource> extra = new osg::LightSource;
        extra->setName("bench light " + std::to_string(n));
        extra->getLight()->setLightNum(n);
        // Above the scene, spread by the golden angle: every light reaches the objects' fronts.
        const float angle = 2.39996f * float(n);
        extra->getLight()->setPosition(
            osg::Vec4(0.6f * std::cos(angle), -0.8f + 0.3f * std::sin(angle), 0.7f, 0.0f));
        extra->getLight()->setDiffuse(osg::Vec4(0.3f, 0.3f, 0.3f, 1.0f));
        scene.insertChild(0, extra.get());
    }
}

namespace {

/** The world-space bounding box of every MaterialNode's subtree: what the benchmark shades (the
 *  scene's own bound also holds the point light's position and the labels). */
struct MaterialBounds : osg::NodeVisitor {
    MaterialBounds() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
    void apply(osg::Group& group) override {
        if (auto* node = dynamic_cast<MaterialNode*>(&group)) {
            const osg::BoundingSphere sphere = node->getBound();
            const osg::Matrix toWorld = osg::computeLocalToWorld(getNodePath());
            box.expandBy(osg::BoundingSphere(sphere.center() * toWorld,
                                             sphere.radius() * float(toWorld.getScale().x())));
            return;
        }
        traverse(group);
    }
    osg::BoundingBox box;
};

}  // namespace

CameraSetup frontCamera(osg::Node& scene, int width, int height) {
    MaterialBounds bounds;
    scene.accept(bounds);
    const osg::BoundingBox box =
        bounds.box.valid()
            ? bounds.box
            : osg::BoundingBox(
                  scene.getBound().center() - osg::Vec3(1, 1, 1) * scene.getBound().radius(),
                  scene.getBound().center() + osg::Vec3(1, 1, 1) * scene.getBound().radius());
    const double fovy = 30.0, aspect = double(width) / double(height);
    const double tanHalfY = std::tan(osg::DegreesToRadians(fovy / 2.0)),
                 tanHalfX = tanHalfY * aspect;
    // The row of objects fills the picture with a 10 % margin: the width against the
    // horizontal field of view, the height against the vertical one, from in front of the box.
    const double halfWidth = 0.5 * (box.xMax() - box.xMin());
    const double halfHeight = 0.5 * (box.zMax() - box.zMin());
    const double halfDepth = 0.5 * (box.yMax() - box.yMin());
    const double distance = 1.1 * std::max(halfWidth / tanHalfX, halfHeight / tanHalfY) + halfDepth;
    osg::Vec3d direction(0.0, -1.0, 0.35);
    direction.normalize();
    CameraSetup setup;
    const osg::Vec3d centre(box.center());
    setup.view = osg::Matrixd::lookAt(centre + direction * distance, centre, osg::Vec3d(0, 0, 1));
    setup.projection = osg::Matrixd::perspective(fovy, aspect, distance * 0.05, distance * 3.0);
    setup.width = width;
    setup.height = height;
    return setup;
}

std::vector<SceneFps> benchmarkScenes(const std::vector<BenchScene>& scenes,
                                      const std::vector<SceneItem>& items,
                                      const SceneBenchOptions& options,
                                      const std::function<void()>& progress,
                                      std::string* rendererName) {
    HeadlessRenderer renderer;
    if (rendererName) *rendererName = renderer.glRenderer() + " (" + renderer.glVersion() + ")";
    renderer.setColorTarget(options.target.format, false);
    std::vector<SceneFps> results;
    for (const BenchScene& scene : scenes) {
        for (const SceneItem& item : items) {
            // The scene as written, every object showing this item's material.
            const std::vector<SceneItem> same(items.size(), item);
            for (int lights : options.lights) {
                osg::ref_ptr<osg::Group> root = scene.build(same);
                setSceneLightCount(*root, lights);
                renderer.setScene(root.get());
                renderer.setCamera(frontCamera(*root, options.width, options.height));
                const PassTiming timing =
                    renderer.timePasses(options.frames, GpuTimer::Auto, options.warmupFrames);
                results.push_back({scene.name, item.label, lights, timing.wallMs, timing.gpuMs});
                renderer.setScene(nullptr);
                if (progress) progress();
            }
        }
    }
    return results;
}

namespace {

std::string fixedDecimals(double value, int decimals) {
    char buffer[64];
    std::snprintf(buffer, sizeof buffer, "%.*f", decimals, value);
    return buffer;
}

}  // namespace

std::string sceneFpsMarkdown(const std::vector<SceneFps>& results, const SceneBenchOptions& options,
                             const std::string& renderer) {
    bool gpu = false;
    for (const SceneFps& r : results) gpu = gpu || r.gpuMs >= 0;
    std::ostringstream md;
    md << "Example scenes at " << options.width << "x" << options.height << ", "
       << options.target.name << " target, median of " << options.frames << " frames after "
       << options.warmupFrames << " warm-up frames; renderer " << renderer
       << ". fps = 1000 / frame ms, a frame = cull + draw + glFinish (wall clock)"
       << (gpu ? "; GPU ms = GL_TIME_ELAPSED of the frame's draw" : "") << ".\n\n"
       << "| scene | method |";
    for (int l : options.lights)
        md << " fps " << l << (l == 1 ? " light" : " lights") << " | frame ms |"
           << (gpu ? " GPU ms |" : "");
    md << "\n|---|---|";
    for (std::size_t i = 0; i < options.lights.size(); ++i)
        md << (gpu ? "---|---|---|" : "---|---|");
    md << "\n";
    // Rows in the order measured: one per (scene, method).
    std::vector<std::pair<std::string, std::string>> rows;
    std::map<std::tuple<std::string, std::string, int>, const SceneFps*> byKey;
    for (const SceneFps& r : results) {
        if (rows.empty() || rows.back() != std::make_pair(r.scene, r.method))
            rows.push_back({r.scene, r.method});
        byKey[{r.scene, r.method, r.lights}] = &r;
    }
    for (const auto& [scene, method] : rows) {
        md << "| " << scene << " | " << method << " |";
        for (int l : options.lights) {
            const auto it = byKey.find({scene, method, l});
            if (it == byKey.end()) {
                md << " n/a | n/a |" << (gpu ? " n/a |" : "");
                continue;
            }
            md << " " << fixedDecimals(it->second->fps(), 1) << " | "
               << fixedDecimals(it->second->frameMs, 2) << " |";
            if (gpu)
                md << " " << (it->second->gpuMs >= 0 ? fixedDecimals(it->second->gpuMs, 3) : "n/a")
                   << " |";
        }
        md << "\n";
    }
    return md.str();
}

std::string sceneFpsCsv(const std::vector<SceneFps>& results) {
    std::ostringstream csv;
    csv << "scene,method,lights,frame_ms,fps,gpu_ms\n";
    for (const SceneFps& r : results)
        csv << r.scene << "," << r.method << "," << r.lights << "," << fixedDecimals(r.frameMs, 4)
            << "," << fixedDecimals(r.fps(), 3) << ","
            << (r.gpuMs >= 0 ? fixedDecimals(r.gpuMs, 4) : "") << "\n";
    return csv.str();
}

}  // namespace osgBTF::examples
