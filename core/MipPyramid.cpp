#include "core/MipPyramid.h"

#include <algorithm>
#include <cmath>
#include <functional>
#include <utility>

#include "core/Error.h"
#include "core/Progress.h"

namespace osgBTF {

MipLayout MipLayout::forBase(int width, int height) {
    if (width <= 0 || height <= 0)
        throw Error("a mip pyramid needs a positive base size, got " + std::to_string(width) + "x" +
                    std::to_string(height));
    MipLayout layout;
    layout._levels.push_back({0, 0, width, height});
    int y = 0;
    while (layout._levels.back().width > 1 || layout._levels.back().height > 1) {
        const MipLevel& previous = layout._levels.back();
        const MipLevel level{width, y, (previous.width + 1) / 2, (previous.height + 1) / 2};
        y += level.height;
        layout._levels.push_back(level);
        if (layout.levelCount() > kMaxLevels)
            throw Error("a mip pyramid of " + std::to_string(width) + "x" + std::to_string(height) +
                        " texels has more than " + std::to_string(kMaxLevels) + " levels");
    }
    layout._atlasWidth = width + (layout.mipMapped() ? layout._levels[1].width : 0);
    layout._atlasHeight = std::max(height, y);
    return layout;
}

void MipLayout::texelAt(float u, float v, int level, int& x, int& y) const {
    const MipLevel& l = _levels.at(std::size_t(level));
    const float fu = u - std::floor(u), fv = v - std::floor(v);
    x = l.x + std::clamp(int(std::floor(fu * float(l.width))), 0, l.width - 1);
    y = l.y + std::clamp(int(std::floor(fv * float(l.height))), 0, l.height - 1);
}

void MipLayout::footprint(int x, int y, int& x0, int& y0, int& x1, int& y1) const {
    const int w = baseWidth(), h = baseHeight();
    for (std::size_t i = 0; i < _levels.size(); ++i) {
        const MipLevel& l = _levels[i];
        if (x < l.x || x >= l.x + l.width || y < l.y || y >= l.y + l.height) continue;
        const int scale = 1 << i;
        x0 = (x - l.x) * scale;
        y0 = (y - l.y) * scale;
        x1 = std::min(x0 + scale, w);
        y1 = std::min(y0 + scale, h);
        return;
    }
    // Never rendered; a real ABRDF keeps fitters' statistics (clusters, bases) meaningful.
    x0 = x % w;
    y0 = y % h;
    x1 = x0 + 1;
    y1 = y0 + 1;
}

namespace {

/** One level up: output texel (X, Y) of ceil(w / 2) x ceil(h / 2) is in(2X, 2Y) + in(2X + 1, 2Y)
 *  + in(2X, 2Y + 1) + in(2X + 1, 2Y + 1), `n` values each, summed in that order where the input
 *  exists: the one order every reading of the atlas uses (MipAtlasSource). */
void sumQuads(const double* in, int w, int h, std::size_t n, double* out) {
    const int ow = (w + 1) / 2, oh = (h + 1) / 2;
    for (int y = 0; y < oh; ++y)
        for (int x = 0; x < ow; ++x) {
            double* o = out + (std::size_t(y) * std::size_t(ow) + std::size_t(x)) * n;
            bool first = true;
            for (const auto& [dx, dy] : {std::pair{0, 0}, {1, 0}, {0, 1}, {1, 1}}) {
                const int ix = 2 * x + dx, iy = 2 * y + dy;
                if (ix >= w || iy >= h) continue;
                const double* v = in + (std::size_t(iy) * std::size_t(w) + std::size_t(ix)) * n;
                if (first)
                    std::copy_n(v, n, o);
                else
                    for (std::size_t k = 0; k < n; ++k) o[k] += v[k];
                first = false;
            }
        }
}

/** Base texels a level-l texel (x, y) covers. */
double footprintArea(int level, int x, int y, int baseWidth, int baseHeight) {
    const int side = 1 << level;
    return double(std::min(x * side + side, baseWidth) - x * side) *
           double(std::min(y * side + side, baseHeight) - y * side);
}

/** Base texels read at once: at least what the source reads efficiently, about 32 MiB. */
std::size_t chunkTexels(const BtfSource& base, std::size_t values) {
    return std::max<std::size_t>(
        std::max<std::size_t>(16, base.abrdfBlockTexels()),
        std::min<std::size_t>(std::size_t(1) << 16,
                              (std::size_t(32) << 20) / std::max<std::size_t>(values * 4, 1)));
}

}  // namespace

MipAtlasSource::MipAtlasSource(const BtfSource& base)
    : BtfSource(0, 0, base.views(), base.lights()),
      _base(base),
      _layout(MipLayout::forBase(base.width(), base.height())) {
    _width = _layout.atlasWidth();
    _height = _layout.atlasHeight();
    source = base.source + " (mip-map atlas)";
    // The block fits of a one-view capture out of core read every atlas texel once: from the
    // base, each coarse level would cost a whole read of the base again (13 for 12.7
    // megapixels).
    _cacheCoarseLevels = !base.inMemory() && base.viewCount() == 1 && _layout.mipMapped();
    _coarseStart.assign(std::size_t(_layout.levelCount()) + 1, 0);
    for (int l = 1; l < _layout.levelCount(); ++l) {
        const MipLevel& level = _layout.levels()[std::size_t(l)];
        _coarseStart[std::size_t(l) + 1] =
            _coarseStart[std::size_t(l)] + std::uint64_t(level.width) * std::uint64_t(level.height);
    }
}

MipAtlasSource::~MipAtlasSource() = default;

void MipAtlasSource::sumFootprint(int level, int x, int y, double* sum) const {
    const std::size_t values = imageCount() * 3;
    const int side = 1 << level, w = _base.width(), h = _base.height();
    const int x0 = x * side, y0 = y * side;
    const int x1 = std::min(x0 + side, w), y1 = std::min(y0 + side, h);
    if (std::size_t(side) * std::size_t(side) <= chunkTexels(_base, values)) {
        // The whole footprint in one read, summed level by level as the quadtree does.
        std::vector<std::size_t> texels;
        for (int by = y0; by < y1; ++by)
            for (int bx = x0; bx < x1; ++bx)
                texels.push_back(std::size_t(by) * std::size_t(w) + std::size_t(bx));
        std::vector<float> read(texels.size() * values);
        _base.readAbrdfs(texels.data(), texels.size(), read.data());
        std::vector<double> a(read.begin(), read.end()), b;
        int bw = x1 - x0, bh = y1 - y0;
        for (int l = 0; l < level; ++l) {
            b.resize(std::size_t((bw + 1) / 2) * std::size_t((bh + 1) / 2) * values);
            sumQuads(a.data(), bw, bh, values, b.data());
            a.swap(b);
            bw = (bw + 1) / 2;
            bh = (bh + 1) / 2;
        }
        std::copy_n(a.data(), values, sum);
        return;
    }
    std::vector<double> child(values);
    bool first = true;
    for (const auto& [dx, dy] : {std::pair{0, 0}, {1, 0}, {0, 1}, {1, 1}}) {
        const int cx = 2 * x + dx, cy = 2 * y + dy;
        if (cx * (side / 2) >= w || cy * (side / 2) >= h) continue;
        sumFootprint(level - 1, cx, cy, first ? sum : child.data());
        if (!first)
            for (std::size_t k = 0; k < values; ++k) sum[k] += child[k];
        first = false;
    }
}

void MipAtlasSource::buildCoarseLevels() const {
    const std::size_t values = imageCount() * 3;
    const int levels = _layout.levelCount(), w = _base.width(), h = _base.height();
    _coarse = std::make_unique<ScratchFile>(_coarseStart.back() * values * sizeof(float),
                                            _base.source, "mip-map levels");
    // Each level gathers rows of the one below until it has two (or the last), sums them into
    // its next row, writes that row's means and hands its sums up: one pass over the base, two
    // rows per level held.
    std::vector<std::vector<double>> pending(static_cast<std::size_t>(levels));
    std::vector<int> pendingRows(std::size_t(levels), 0), rowsDone(std::size_t(levels), 0);
    std::vector<float> means;
    std::vector<double> row;
    const std::function<void(int)> climb = [&](int l) {
        // Level l - 1's pending rows -> level l's next row.
        const MipLevel& below = _layout.levels()[std::size_t(l - 1)];
        const MipLevel& level = _layout.levels()[std::size_t(l)];
        row.resize(std::size_t(level.width) * values);
        sumQuads(pending[std::size_t(l - 1)].data(), below.width, pendingRows[std::size_t(l - 1)],
                 values, row.data());
        pending[std::size_t(l - 1)].clear();
        pendingRows[std::size_t(l - 1)] = 0;
        const int y = rowsDone[std::size_t(l)]++;
        means.resize(row.size());
        for (int x = 0; x < level.width; ++x) {
            const double area = footprintArea(l, x, y, w, h);
            for (std::size_t k = 0; k < values; ++k)
                means[std::size_t(x) * values + k] = float(row[std::size_t(x) * values + k] / area);
        }
        _coarse->write(
            means.data(), means.size() * sizeof(float),
            (_coarseStart[std::size_t(l)] + std::uint64_t(y) * std::uint64_t(level.width)) *
                values * sizeof(float));
        if (l + 1 >= levels) return;
        std::vector<double>& up = pending[std::size_t(l)];
        up.insert(up.end(), row.begin(), row.end());
        if (++pendingRows[std::size_t(l)] == 2 || y == level.height - 1) climb(l + 1);
    };
    // The base in bands of an even number of rows, about 32 MiB of floats each.
    const int band =
        std::max(2, int(chunkTexels(_base, values) / std::size_t(std::max(1, w))) / 2 * 2);
    Progress progress("mip-map levels of " + _base.source, std::size_t(h));
    std::vector<float> read;
    for (int y = 0; y < h; y += band) {
        const int rows = std::min(band, h - y);
        read.resize(std::size_t(rows) * std::size_t(w) * values);
        _base.readAbrdfRange(std::size_t(y) * std::size_t(w), std::size_t(rows) * std::size_t(w),
                             read.data());
        for (int r = 0; r < rows; ++r) {
            std::vector<double>& base = pending[0];
            const float* from = read.data() + std::size_t(r) * std::size_t(w) * values;
            base.insert(base.end(), from, from + std::size_t(w) * values);
            if (++pendingRows[0] == 2 || y + r == h - 1) climb(1);
        }
        progress.advance(std::size_t(rows));
    }
    progress.finish();
}

void MipAtlasSource::readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const {
    const std::size_t values = imageCount() * 3;
    // Base texels (and the unused corner's, which repeat one) are read from the base together,
    // in chunks; coarse texels from the scratch file of the coarse levels, or from their
    // footprints.
    const std::size_t chunk = chunkTexels(_base, values);
    std::vector<std::size_t> baseTexels, owners;
    std::vector<float> read;
    const auto flush = [&] {
        read.resize(baseTexels.size() * values);
        _base.readAbrdfs(baseTexels.data(), baseTexels.size(), read.data());
        for (std::size_t i = 0; i < baseTexels.size(); ++i)
            std::copy_n(read.data() + i * values, values, out + owners[i] * values);
        baseTexels.clear();
        owners.clear();
    };
    std::vector<double> sum(values);
    for (std::size_t t = 0; t < count; ++t) {
        const int x = int(texels[t] % std::size_t(_width)),
                  y = int(texels[t] / std::size_t(_width));
        int level = -1;
        for (int l = 0; l < _layout.levelCount(); ++l) {
            const MipLevel& m = _layout.levels()[std::size_t(l)];
            if (x >= m.x && x < m.x + m.width && y >= m.y && y < m.y + m.height) level = l;
        }
        if (level <= 0) {
            int x0, y0, x1, y1;
            _layout.footprint(x, y, x0, y0, x1, y1);
            baseTexels.push_back(std::size_t(y0) * std::size_t(_base.width()) + std::size_t(x0));
            owners.push_back(t);
            if (baseTexels.size() == chunk) flush();
            continue;
        }
        const MipLevel& m = _layout.levels()[std::size_t(level)];
        const int lx = x - m.x, ly = y - m.y;
        if (_cacheCoarseLevels) {
            std::call_once(_coarseBuilt, [this] { buildCoarseLevels(); });
            // Consecutive texels of one level row are one read.
            std::size_t run = 1;
            while (t + run < count && texels[t + run] == texels[t] + run && lx + int(run) < m.width)
                ++run;
            _coarse->read(out + t * values, run * values * sizeof(float),
                          (_coarseStart[std::size_t(level)] +
                           std::uint64_t(ly) * std::uint64_t(m.width) + std::uint64_t(lx)) *
                              values * sizeof(float));
            t += run - 1;
            continue;
        }
        sumFootprint(level, lx, ly, sum.data());
        const double area = footprintArea(level, lx, ly, _base.width(), _base.height());
        for (std::size_t v = 0; v < values; ++v) out[t * values + v] = float(sum[v] / area);
    }
    if (!baseTexels.empty()) flush();
}

void MipAtlasSource::readImages(std::size_t first, std::size_t count, float* out) const {
    const int w = _base.width(), h = _base.height();
    const std::size_t atlasTexels = texelCount();
    std::vector<float> image(std::size_t(w) * std::size_t(h) * 3);
    std::vector<double> a, b;
    for (std::size_t i = 0; i < count; ++i) {
        _base.readImages(first + i, 1, image.data());
        float* atlas = out + i * atlasTexels * 3;
        // Level 0 and the unused corner: base texels.
        for (int y = 0; y < _height; ++y)
            for (int x = 0; x < _width; ++x) {
                int x0, y0, x1, y1;
                _layout.footprint(x, y, x0, y0, x1, y1);
                if (x1 - x0 != 1 || y1 - y0 != 1) continue;  // a coarse texel, below
                std::copy_n(image.data() + (std::size_t(y0) * std::size_t(w) + std::size_t(x0)) * 3,
                            3, atlas + (std::size_t(y) * std::size_t(_width) + std::size_t(x)) * 3);
            }
        // Each level from the one below.
        a.assign(image.begin(), image.end());
        int lw = w, lh = h;
        for (int l = 1; l < _layout.levelCount(); ++l) {
            const MipLevel& m = _layout.levels()[std::size_t(l)];
            b.resize(std::size_t(m.width) * std::size_t(m.height) * 3);
            sumQuads(a.data(), lw, lh, 3, b.data());
            a.swap(b);
            lw = m.width;
            lh = m.height;
            for (int y = 0; y < lh; ++y)
                for (int x = 0; x < lw; ++x) {
                    const double area = footprintArea(l, x, y, w, h);
                    for (int c = 0; c < 3; ++c)
                        atlas[(std::size_t(m.y + y) * std::size_t(_width) + std::size_t(m.x + x)) *
                                  3 +
                              std::size_t(c)] =
                            float(a[(std::size_t(y) * std::size_t(lw) + std::size_t(x)) * 3 +
                                    std::size_t(c)] /
                                  area);
                }
        }
    }
}

}  // namespace osgBTF
