// A long headless viewer run that switches materials and reloads its scene, sampling the
// process's memory and the GL objects alive in the context: what must stay flat for an
// application that runs for days. bench/soak.cpp runs it for 10,000 frames,
// tests/gl/soak_test.cpp a short version.
#pragma once

#include <string>
#include <vector>

namespace osgBTF {

class HeadlessRenderer;

struct SoakOptions {
    int frames = 10000;
    int switchEvery = 10;     ///< frames between material switches (every node gets another one)
    int reloadEvery = 500;    ///< frames between scene reloads (the files read again via osgDB)
    int sampleEvery = 250;    ///< frames between samples
    int warmupFrames = 1000;  ///< samples before this frame are reported, not judged
    /** RSS may grow this much past its largest warm-up sample (allocator noise, caches that
     *  reach their size late), in MiB. */
    double rssToleranceMiB = 8.0;
    /** GL objects may exceed their largest warm-up count by this many (objects of the scene in
     *  flight at the sample: a reload's old and new objects both alive for a frame). */
    int glObjectTolerance = 0;
};

struct SoakSample {
    int frame = 0;
    double rssMiB = 0;
    int textures = 0;                ///< glIsTexture names alive in the context
    int programs = 0;                ///< glIsProgram
    int shaders = 0;                 ///< glIsShader
    int buffers = 0;                 ///< glIsBuffer
    unsigned osgTextureObjects = 0;  ///< OSG's TextureObjectManager: active + orphaned
};

struct SoakResult {
    std::vector<SoakSample> samples;
    double seconds = 0;
    int reloads = 0, switches = 0;
    int reloadsAfterWarmup = 0;
    /** What one load of the scene holds in its materials (Material::memory), in MiB: a scene
     *  leaked per reload would add reloadsAfterWarmup times this to the RSS. */
    double sceneMiB = 0;
    /** Empty when flat after warm-up; else what grew, by how much. */
    std::string growth;
};

/** Renders `options.frames` frames of the fitted-material files `materialFiles` (read through
 *  osgDB, so the osgBTF plugins must be on OSG's library path), one patch per file in a row.
 *  Throws Error when a file does not read as a MaterialNode. */
SoakResult runSoak(HeadlessRenderer& renderer, const std::vector<std::string>& materialFiles,
                   const SoakOptions& options);

/** One line per sample and a verdict, for people. */
std::string formatSoak(const SoakResult& result);

}  // namespace osgBTF
