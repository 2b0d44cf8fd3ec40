// osgBTF harness: time per rendering pass of a material, and the calibration pass that turns a
// fetch count into a fetch-bound floor (harness/README.md, Table 3).
#pragma once

#include <string>
#include <vector>

#include <osg/Geode>
#include <osg/StateSet>

#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"

namespace osgBTF {

struct PassSettings {
    int width = 256, height = 256;  ///< viewport of the timed pass
    int lights = 1;                 ///< directional lights (1..8)
    int frames = 5;                 ///< timed frames; the median is reported
    int calibrationFetches = 64;    ///< N of the calibration pass
    float textureScale = 16;        ///< the material repeats this often across the viewport
};

/** One pass time and the clock it comes from. */
struct PassTime {
    double ms = -1;
    std::string clock;  ///< "GL_TIME_ELAPSED" (hardware GPU) or "wall+glFinish" (software)
    PassTiming timing;  ///< every clock, every frame
};

struct Calibration {
    PassTime empty;    ///< the same pass with 0 fetches (clear, raster, read-back)
    PassTime fetches;  ///< N fetches per pixel
    int fetchCount = 0;
    double fetchesPerSecond = 0;  ///< N * pixels / fetches.ms
};

/** Light directions (eye space, towards the light) used for `count` lights: the first one from
 *  the upper right front, the others spread around it. */
std::vector<osg::Vec3> defaultLightDirections(int count);

/** Sets osgBTF_lightCount / osgBTF_lightPosition (directional, w = 0) / osgBTF_lightColor (white)
 *  for up to 8 lights. Directions are normalised. */
void setDirectionalLights(osg::StateSet& stateSet, const std::vector<osg::Vec3>& directions);

/** A unit patch for orthoUnitSquare() with the tangent attribute (+X) every method needs. */
osg::ref_ptr<osg::Geode> createTangentPatch(osg::StateSet* stateSet);

/** Times the material on a full-viewport patch (PassSettings: size, lights, tiling, frames). The
 *  clock is GL_TIME_ELAPSED on a hardware renderer and wall time after glFinish on a software
 *  one (llvmpipe's timer queries are meaningless: docs/headless.md section 4). */
PassTime timeMaterialPass(HeadlessRenderer& renderer, const Material& material,
                          const PassSettings& settings);

/** The empty pass and the N-fetch pass of shaders/calibration/fetch.frag (512 x 512 RGBA32F
 *  texture) at the same viewport, same clock. */
Calibration runCalibration(HeadlessRenderer& renderer, const PassSettings& settings);

}  // namespace osgBTF
