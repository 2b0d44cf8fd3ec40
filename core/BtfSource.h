// osgBTF: where a fitter reads measured data from.
//
// Two kinds of input exist: a MeasuredBtf, every value in memory, and a FactoredBtf, a UBO2014
// file's factors B = U * SxV^T, which are ~100 MB where the values would be 22 GB. Fitters only
// read through this interface, in the two shapes every method needs: blocks of images (the
// per-view methods: PCA, FMF) and the ABRDFs of blocks of texels (per-texel methods: lambert,
// LAF, SLAF, RF; LPCA's training sample and projection). A FactoredBtf decodes each block on the
// fly with one GEMM, so a full-size file is fitted without ever being materialised.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include "core/Directions.h"

namespace osgBTF {

class BtfSource {
public:
    virtual ~BtfSource() = default;

    int width() const { return _width; }
    int height() const { return _height; }
    std::size_t texelCount() const { return std::size_t(_width) * std::size_t(_height); }
    const DirectionSet& views() const { return _views; }
    const DirectionSet& lights() const { return _lights; }
    std::size_t viewCount() const { return _views.size(); }
    std::size_t lightCount() const { return _lights.size(); }
    /** (view, light) images; image i is view i / lightCount(), light i % lightCount(). */
    std::size_t imageCount() const { return _views.size() * _lights.size(); }
    bool empty() const { return _width == 0 || _height == 0; }

    /** Images [first, first + count) into `out`: count * texels * 3 floats, each laid out as
     *  MeasuredBtf::image (rows bottom-up, RGB). Safe to call from several threads at once. */
    virtual void readImages(std::size_t first, std::size_t count, float* out) const = 0;
    /** The ABRDFs of `count` texels (indices y * width + x, y from the bottom) into `out`: count *
     *  views * lights * 3 floats, each laid out as MeasuredBtf::abrdf ([view][light][rgb]).
     *  Ascending texels read fastest. Safe to call from several threads at once. */
    virtual void readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const = 0;
    /** readAbrdfs of the texels [first, first + count). */
    void readAbrdfRange(std::size_t first, std::size_t count, float* out) const;

    /** Texels per readAbrdfs call from which reading is efficient: a few for data in memory
     *  (cache lines), more for factored data (one GEMM per call). Methods that work texel by
     *  texel read blocks of this many. */
    virtual std::size_t abrdfBlockTexels() const = 0;
    /** Images per readImages call from which reading is efficient. */
    virtual std::size_t imageBlock() const = 0;
    /** True when the values are in memory and reading is a copy; false when every read decodes
     *  (then a method should read each value as few times as it can). */
    virtual bool inMemory() const = 0;

    /** Bytes this source holds in memory while it is read (a MeasuredBtf's values, a factored
     *  BTF's factors; 0 for data kept on disk): what a fit allocates comes on top of it. */
    virtual std::uint64_t residentBytes() const = 0;

    /** Bytes of the values as floats (texels x images x 3 x 4): what materialising would need. */
    std::uint64_t decodedBytes() const {
        return std::uint64_t(texelCount()) * imageCount() * 3 * sizeof(float);
    }

    /** Human-readable origin, e.g. the file it was loaded from. */
    std::string source;
    /** How a loader turned 8/16-bit image values into radiance ("linear", "sRGB", "gamma 2.2");
     *  empty for float data and for what was not read from images. */
    std::string decoding;

protected:
    BtfSource() = default;
    BtfSource(int width, int height, DirectionSet views, DirectionSet lights)
        : _width(width), _height(height), _views(std::move(views)), _lights(std::move(lights)) {}

    int _width = 0, _height = 0;
    DirectionSet _views, _lights;
};

/** `count` distinct texels of `source` drawn at random (deterministic for `seed`), ascending; all
 *  texels when count >= texelCount(). For statistics over a stated subsample. */
std::vector<std::size_t> randomTexels(const BtfSource& source, std::size_t count,
                                      unsigned seed = 1);

/** How many texels error tables cover (`btf fit` and `btf compare --error-texels`): `requested`
 *  when positive (at most all), all for 0, and for a negative request the default: all texels of
 *  data in memory, 4096 of factored input (an exact error over a full-size UBO2014 file decodes
 *  all its ~11 G values once per method). */
std::size_t errorTexelCount(const BtfSource& source, long long requested);

/** checkMemory for what a fit allocates beside the measured data it reads: refused when `bytes`
 *  and held.residentBytes() together exceed the memory limit ("<what>: needs N beside the M of
 *  measured values held in memory, more than the memory limit of L ..."), with checkMemory's own
 *  message when `bytes` alone does. Each allocation checked alone let a 12.7-megapixel capture's
 *  11 GB of floats and a ptm fit's 11 GB of images pass a 17.6 GB limit, to the OOM killer. */
void checkMemoryBeside(const BtfSource& held, std::uint64_t bytes, const std::string& what);

}  // namespace osgBTF
