// What the soaks (harness/Soak.h, harness/PagedScene.h) sample and how they judge it: the
// process's live memory, the GL objects alive in the context, and growth after a warm-up.
#pragma once

#include <string>
#include <vector>

#include <osg/Camera>

#include "harness/Soak.h"

namespace osgBTF {

/** The RSS after malloc_trim: free memory the allocator kept (how much depends on what the
 *  process did before, e.g. every other GL test in one process: swings of 7 MiB) goes back to
 *  the system first, so what is left is live memory (within ~0.1 MiB from sample to sample). */
double trimmedResidentMiB();

/** Counts the GL objects alive in the context after the camera's draw, when `wanted`: every
 *  name up to beyond the newest one the driver hands out (a fresh name from glGen* bounds the
 *  names in use whether the driver reuses freed names or counts upward). Install it as the
 *  camera's post-draw callback; set `wanted` before a frame, read `counts` after it. */
class CountGlObjects : public osg::Camera::DrawCallback {
public:
    mutable bool wanted = false;
    mutable SoakSample counts;

    void operator()(osg::RenderInfo& info) const override;

private:
    mutable unsigned _bound = 16384;
};

/** "" when no sample after the warm-up (`warm(sample)` false) exceeds the largest warm-up sample
 *  by more than the tolerances (RSS in MiB, GL objects in objects); else what grew, by how
 *  much. Throws Error when there are no samples on either side of the warm-up. */
template <class Sample, class IsWarm>
std::string growthAfterWarmup(const std::vector<Sample>& samples, IsWarm warm,
                              double rssToleranceMiB, int glObjectTolerance);

/** The same for SoakSample-like samples, implemented once (SoakSampling.cpp). */
std::string judgeGrowth(const std::vector<const SoakSample*>& warmSamples,
                        const std::vector<const SoakSample*>& laterSamples, double rssToleranceMiB,
                        int glObjectTolerance);

template <class Sample, class IsWarm>
std::string growthAfterWarmup(const std::vector<Sample>& samples, IsWarm warm,
                              double rssToleranceMiB, int glObjectTolerance) {
    std::vector<const SoakSample*> before, after;
    for (const Sample& s : samples) (warm(s) ? before : after).push_back(&s);
    return judgeGrowth(before, after, rssToleranceMiB, glObjectTolerance);
}

}  // namespace osgBTF
