// osgBTF: k-coherence BTF synthesis (Boßerhoff and Nicoll 2003 section 4, after Tong et al. 2002):
// a large surface is made of texels of a small measured sample, and the result is a CoordinateMap
// (which sample texel each output texel shows), rendered through dependent fetches (Boßerhoff and
// Nicoll 2003 section 5; filtered: the four map entries around a fragment).
//
// Two steps, each its own function so the analysis can be timed apart from the synthesis (seed
// 002 Table 1 times the synthesis alone):
//   analyseSample   per-texel appearance vectors of the sample's images (optionally a selection),
//                   reduced by a random projection; per pyramid level k-means textons, the texton
//                   dot-product matrix (as squared distances) and, per sample texel, the k-1
//                   texels with the most similar neighbourhoods (the k-coherence candidate lists)
//   synthesizeMap   hierarchical scanline k-coherence synthesis into a CoordinateMap
// measureSynthesis gives the quality figures the tool prints. The algorithm, the paper's equations
// and our choices: synthesis/README.md.
#pragma once

#include <cstdint>
#include <string>
#include <vector>

#include "core/BtfSource.h"
#include "core/CoordinateMap.h"

namespace osgBTF {

struct SynthesisOptions {
    int width = 512;  ///< output texels (--size)
    int height = 512;
    /** Candidates per synthesised neighbour: its shifted source and its k-1 most similar texels
     *  (--k; Boßerhoff and Nicoll 2003 use 1..6). */
    int k = 5;
    /** Neighbourhood radius r: a (2r+1)x(2r+1) square (--neighbourhood; Boßerhoff and Nicoll 2003
     * use 1..3). */
    int neighbourhood = 2;
    /** Pyramid levels (--levels; Boßerhoff and Nicoll 2003: 3). The sample's sides must be
     * multiples of 2^(levels-1). */
    int levels = 3;
    std::uint64_t seed = 1;  ///< everything random derives from it (--seed)
    /** Images used for the appearance vectors: 0 = all, else this many spread evenly over the
     *  (view, light) index (--images). */
    std::size_t images = 0;
    int textons = 1024;   ///< k-means clusters per level, at most the level's texels (--textons)
    int dimensions = 64;  ///< random-projection dimension of the vectors (--dimensions)
    int kmeansIterations = 20;
    /** Spacing in output texels of the jumps at the coarsest level (--patch): one per patch x
     *  patch cell, at a random place in it, the synthesis starts a block from a texel whose
     *  neighbourhood matches but which lies away from every coherent continuation, so the output
     *  is not one copy of the sample. 0: no jumps (the output then follows one random start).
     *  -1: half the sample's smaller side. */
    int patch = -1;
};

/** Throws Error "--option: problem" for options that cannot work with a sample of this size and
 *  image count (also checked by analyseSample). */
void validateSynthesisOptions(const SynthesisOptions& options, int sampleWidth, int sampleHeight,
                              std::size_t imageCount);

/** One pyramid level of the analysed sample (level 0 = the coarsest). */
struct SynthesisLevel {
    int width = 0, height = 0;  ///< sample texels at this level
    int dimensions = 0;
    /** texels x dimensions, rows bottom-up: the projected appearance vector of each texel. */
    std::vector<float> features;
    int textonCount = 0;
    std::vector<std::int32_t> texton;  ///< per texel
    /** textonCount^2: ||v_i - v_j||^2 = M_ii - 2 M_ij + M_jj from the dot products M. */
    std::vector<float> textonDistance;
    int similarCount = 0;  ///< max(k - 1, 4): the k-coherence candidates and the jump targets
    /** texels x similarCount: the texels with the smallest wrapped-neighbourhood distance, most
     *  similar first (never the texel itself). */
    std::vector<std::int32_t> similar;

    std::size_t texels() const { return std::size_t(width) * std::size_t(height); }
    float distance(std::int32_t texelA, std::int32_t texelB) const {
        return textonDistance[std::size_t(texton[texelA]) * textonCount + texton[texelB]];
    }
};

struct SampleAnalysis {
    int width = 0, height = 0;        ///< the sample's texels
    std::vector<std::size_t> images;  ///< the images the vectors were made of
    std::size_t valuesPerTexel = 0;   ///< 3 x images: the dimension before projection
    std::vector<SynthesisLevel> levels;
};

/** Reads the sample through `source` (blocks of images), checks memoryLimit() before each large
 *  allocation, reports progress. Deterministic: the projection and the k-means start derive from
 *  fixed seeds and every parallel step has a fixed partition. */
SampleAnalysis analyseSample(const BtfSource& source, const SynthesisOptions& options);

/** The hierarchical k-coherence synthesis. Deterministic for options.seed; every entry lies in
 *  the sample. `options` must be those the analysis was made with (k, neighbourhood, levels). */
CoordinateMap synthesizeMap(const SampleAnalysis& analysis, const SynthesisOptions& options);

struct SynthesisQuality {
    /** Share of adjacent output texel pairs (right and upper neighbours) whose sources are the
     *  same neighbours in the (wrapped) sample. */
    double coherenceRate = 0;
    /** Mean ||f(s(a)) - f(s(b))||^2 over adjacent output texels a, b (f: the finest level's
     *  vectors, s: the map) divided by the mean of ||f(p) - f(q)||^2 over adjacent sample texels
     *  p, q (not across the sample's edge); 1 when the sample holds a single value. */
    double seamRatio = 0;
    double outputMeanDistance = 0, sampleMeanDistance = 0;
};

SynthesisQuality measureSynthesis(const SampleAnalysis& analysis, const CoordinateMap& map);

}  // namespace osgBTF
