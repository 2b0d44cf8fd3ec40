// osgBTF harness: time per rendering pass of a material against the empty pass of the same run,
// in the colour targets a viewer draws into, and the calibration pass that turns a fetch count
// into a fetch-bound floor (harness/README.md, Table 3).
#pragma once

#include <string>
#include <vector>

#include <osg/Geode>
#include <osg/StateSet>

#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"

namespace osgBTF {

/** A colour buffer the timed passes draw into (a renderbuffer, never read back). */
struct PassTarget {
    std::string name;  ///< "RGBA8", "RGBA16F" or "RGBA32F"
    GLenum format = GL_RGBA8;
};

/** "rgba8", "rgba16f" or "rgba32f" (any case). Throws Error
 *  "pass target 'NAME': must be rgba8, rgba16f or rgba32f". */
PassTarget passTarget(const std::string& name);

struct PassSettings {
    int width = 256, height = 256;  ///< viewport of the timed pass
    int lights = 1;                 ///< directional lights (1..8)
    int frames = 5;                 ///< timed frames; the median is reported
    int warmupFrames = 2;           ///< untimed frames before them (compilation, uploads, caches)
    int calibrationFetches = 64;    ///< N of the calibration pass
    float textureScale = 16;        ///< the material repeats this often across the viewport
    /** Targets, each timed on its own (empty pass, calibration, every method); the first is the
     *  one the time budget of `btf compare` reads. A viewer draws into RGBA8 (a window) or
     *  RGBA16F (an HDR buffer); RGBA32F costs several times more per pixel on GPUs. */
    std::vector<PassTarget> targets = {passTarget("rgba8"), passTarget("rgba16f")};
};

/** One pass time and the clock it comes from. */
struct PassTime {
    double ms = -1;
    std::string clock;  ///< "GL_TIME_ELAPSED" (hardware GPU) or "wall+glFinish" (software)
    PassTiming timing;  ///< every clock, every frame
};

/** The passes without a material, in one target. */
struct Calibration {
    PassTarget target;
    PassTime empty;    ///< the same patch with a constant colour: clear, raster, blend-free write
    PassTime fetches;  ///< N RGBA32F texelFetch per pixel
    int fetchCount = 0;
    /** N * pixels / (fetches - empty): the empty pass is subtracted, so this is the rate of the
     *  reads alone. 0 when the difference is not positive (too noisy to say). */
    double fetchesPerSecond = 0;
};

/** One method's pass in one target, against that target's calibration. */
struct MethodPass {
    PassTarget target;
    PassTime pass;
    double emptyMs = -1;    ///< the calibration's empty pass
    double shadingMs = 0;   ///< pass - empty: what the material's shading costs (may be < 0: noise)
    double floorMs = -1;    ///< TEX x pixels / calibrated fetch rate; -1: not counted
    double floorRatio = 0;  ///< shadingMs / floorMs (when floorMs > 0)
    bool measured() const { return pass.ms >= 0; }
};

/** Light directions (eye space, towards the light) used for `count` lights: the first one from
 *  the upper right front, the others spread around it. */
std::vector<osg::Vec3> defaultLightDirections(int count);

/** Sets osgBTF_lightCount / osgBTF_lightPosition (directional, w = 0) / osgBTF_lightColor (white)
 *  for up to 8 lights. Directions are normalised. */
void setDirectionalLights(osg::StateSet& stateSet, const std::vector<osg::Vec3>& directions);

/** A unit patch for orthoUnitSquare() with the tangent attribute (+X) every method needs. */
osg::ref_ptr<osg::Geode> createTangentPatch(osg::StateSet* stateSet);

/** Times the material on a full-viewport patch (PassSettings: size, lights, tiling, frames) into
 *  `target`. The clock is GL_TIME_ELAPSED on a hardware renderer and wall time after glFinish on
 *  a software one (llvmpipe's timer queries are meaningless: docs/headless.md section 4). The
 *  renderer's colour target is restored to the read-back RGBA32F one afterwards. */
PassTime timeMaterialPass(HeadlessRenderer& renderer, const Material& material,
                          const PassSettings& settings, const PassTarget& target);

/** The empty pass and the N-fetch pass of shaders/calibration/fetch.frag (512 x 512 RGBA32F
 *  texture) at the same viewport, same clock, into `target`. */
Calibration runCalibration(HeadlessRenderer& renderer, const PassSettings& settings,
                           const PassTarget& target);

/** timeMaterialPass into calibration.target, set against the calibration: shading = pass -
 *  empty, floor = `texPerPixel` x pixels / calibrated rate (texPerPixel < 0: no floor). */
MethodPass timeMethodPass(HeadlessRenderer& renderer, const Material& material,
                          const PassSettings& settings, const Calibration& calibration,
                          int texPerPixel);

}  // namespace osgBTF
