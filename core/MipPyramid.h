// osgBTF: mip-mapped BTFs. Minified surfaces must show the average of the
// measured data over a pixel's footprint, not one texel of it: the averaged ABRDFs of every level
// are laid out in one atlas and fitted like any measured texels, so every method gets prefiltered
// data its own way (per-texel methods fit each level's averages, LPCA assigns clusters and weights
// per level, the linear methods fit a basis that covers the averages) and its shader picks the
// level from screen-space derivatives (shaders/common/surface_frame.glsl, as GL_LINEAR_MIPMAP_
// LINEAR does) and blends two.
#pragma once

#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include "core/BtfSource.h"
#include "core/ScratchFile.h"

namespace osgBTF {

/** Where a level lies in the atlas, in atlas texels (y from the bottom). */
struct MipLevel {
    int x = 0, y = 0, width = 0, height = 0;
};

/** The atlas of a base of W x H texels: level 0 at (0, 0), level l >= 1 of ceil(W / 2^l) x
 *  ceil(H / 2^l) texels stacked from the bottom in a column right of it, down to 1 x 1. The
 *  atlas is W + ceil(W / 2) wide: 1.5x the base texels instead of an ideal pyramid's 4/3, for
 *  addressing that stays a single rectangle per level. */
class MipLayout {
public:
    /** Not mip-mapped: no levels. */
    MipLayout() = default;
    /** Throws Error for a base that is not positive or has more than kMaxLevels levels. */
    static MipLayout forBase(int width, int height);

    /** The most levels a shader addresses (a 32768-texel base). */
    static constexpr int kMaxLevels = 16;

    bool mipMapped() const { return _levels.size() > 1; }
    const std::vector<MipLevel>& levels() const { return _levels; }
    int levelCount() const { return int(_levels.size()); }
    int baseWidth() const { return _levels.empty() ? 0 : _levels[0].width; }
    int baseHeight() const { return _levels.empty() ? 0 : _levels[0].height; }
    int atlasWidth() const { return _atlasWidth; }
    int atlasHeight() const { return _atlasHeight; }

    /** The atlas texel of level `level` that covers texture coordinate uv (wrapped, as the
     *  shader's btfLevelTexel). */
    void texelAt(float u, float v, int level, int& x, int& y) const;

    /** Which base texels atlas texel (x, y) averages: [x0, x1) x [y0, y1); a texel outside
     *  every level (the atlas's unused corner) maps to the one base texel (x % W, y % H). */
    void footprint(int x, int y, int& x0, int& y0, int& x1, int& y1) const;

private:
    std::vector<MipLevel> _levels;
    int _atlasWidth = 0, _atlasHeight = 0;
};

/** The atlas of `base` as a BtfSource: each atlas texel's values are the mean of its footprint's
 *  measured values (a box filter, exactly what a pixel covering those texels should show). The
 *  sums run as a quadtree: a level-l texel sums its four level-(l-1) children in the order (2x,
 *  2y), (2x+1, 2y), (2x, 2y+1), (2x+1, 2y+1), in double, so that every way of reading gives the
 *  same floats. Image reads build each image's levels from the level below (1.33 reads of the
 *  base). ABRDF reads of base texels read the base; of coarser texels, for a one-view base not in
 *  memory (an RTI capture out of core), a scratch file of every coarse level built on the first
 *  such read in one pass over the base (a third of the base's values; ScratchFile), else the
 *  texel's footprint from the base (one base read per base texel and level). `base` must outlive
 *  it. */
class MipAtlasSource : public BtfSource {
public:
    explicit MipAtlasSource(const BtfSource& base);
    ~MipAtlasSource() override;

    const MipLayout& layout() const { return _layout; }

    void readImages(std::size_t first, std::size_t count, float* out) const override;
    void readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const override;
    std::size_t abrdfBlockTexels() const override { return _base.abrdfBlockTexels(); }
    std::size_t imageBlock() const override { return _base.imageBlock(); }
    bool inMemory() const override { return false; }
    std::uint64_t residentBytes() const override { return _base.residentBytes(); }

private:
    /** The quadtree sum of level-l texel (x, y) (level coordinates) into `sum` (values
     *  doubles), from the base. */
    void sumFootprint(int level, int x, int y, double* sum) const;
    /** Builds the scratch file of the coarse levels (once). */
    void buildCoarseLevels() const;

    const BtfSource& _base;
    MipLayout _layout;
    bool _cacheCoarseLevels = false;
    mutable std::once_flag _coarseBuilt;
    mutable std::unique_ptr<ScratchFile> _coarse;
    /** Offsets of each level's values in _coarse, in texels (level 0: unused). */
    std::vector<std::uint64_t> _coarseStart;
};

}  // namespace osgBTF
