// btf-examples --bench-fps: frames per second of the example scenes, headless, per method and
// light count (Meseth et al. 2003 Table 3 reports fps).
#pragma once

#include <osg/Group>
#include <osg/Node>
#include <osgDB/Options>

#include <functional>
#include <string>
#include <vector>

#include "examples/ExampleScenes.h"
#include "harness/PassCost.h"

namespace osgBTF::examples {

struct SceneBenchOptions {
    int width = 1920, height = 1080;
    std::vector<int> lights = {1, 8};
    int frames = 20;
    int warmupFrames = 3;
    PassTarget target = passTarget("rgba8");  ///< what a viewer's window is
};

/** One scene of the benchmark: builds the side-by-side scene with the given items (every
 *  object of it shows the method under test). */
struct BenchScene {
    std::string name;
    std::function<osg::ref_ptr<osg::Group>(const std::vector<SceneItem>&)> build;
};

struct SceneFps {
    std::string scene, method;
    int lights = 0;
    double frameMs = -1;  ///< median wall time of a frame ending with glFinish
    double gpuMs = -1;    ///< median GL_TIME_ELAPSED of the frame (hardware renderers), else -1
    double fps() const { return frameMs > 0 ? 1000.0 / frameMs : 0.0; }
};

/** Keeps the scene's first `count` LightSources (the key light, then the fill light) and adds
 *  white directional ones (light numbers 2..7) spread around the key light up to `count`
 *  (1..8). Throws Error for another count. */
void setSceneLightCount(osg::Group& scene, int count);

/** A perspective camera (30 degrees vertical field of view) looking at the scene's objects from
 *  the front (-Y) and a little above, as osgViewer's home view does, closer: the bounding box of
 *  its MaterialNodes fills the viewport with a 10 % margin (the scene's own bound also holds a
 *  light's position and the labels). */
CameraSetup frontCamera(osg::Node& scene, int width, int height);

/** For each scene, each item (its method on every object of the scene) and each light count:
 *  the median frame time headless (HeadlessRenderer, options.target without read-back). Calls
 *  `progress` after each measurement; `renderer` (if given) gets GL_RENDERER (GL_VERSION). */
std::vector<SceneFps> benchmarkScenes(const std::vector<BenchScene>& scenes,
                                      const std::vector<SceneItem>& items,
                                      const SceneBenchOptions& options,
                                      const std::function<void()>& progress = {},
                                      std::string* renderer = nullptr);

/** The results as a Markdown table: one row per scene and method, per light count the fps and
 *  the frame ms (and GPU ms where measured), with a line naming renderer, resolution, target. */
std::string sceneFpsMarkdown(const std::vector<SceneFps>& results, const SceneBenchOptions& options,
                             const std::string& renderer);

/** The same as CSV: scene,method,lights,frame_ms,fps,gpu_ms. */
std::string sceneFpsCsv(const std::vector<SceneFps>& results);

}  // namespace osgBTF::examples
