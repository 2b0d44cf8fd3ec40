#include "core/MipPyramid.h"

#include <algorithm>
#include <cmath>

#include "core/Error.h"

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

MipAtlasSource::MipAtlasSource(const BtfSource& base)
    : BtfSource(0, 0, base.views(), base.lights()),
      _base(base),
      _layout(MipLayout::forBase(base.width(), base.height())) {
    _width = _layout.atlasWidth();
    _height = _layout.atlasHeight();
    source = base.source + " (mip-map atlas)";
}

void MipAtlasSource::readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const {
    const std::size_t values = imageCount() * 3;
    // The footprints of every requested texel are read together, in chunks of base texels: one
    // read covers many atlas texels (a source out of core reads a chunk's rows once), and a
    // coarse level's texel, whose footprint is the whole base, never needs it all at once. Each
    // texel's sum runs over its footprint in row order, whatever the chunks.
    const std::size_t chunk = std::max<std::size_t>(
        std::max<std::size_t>(16, _base.abrdfBlockTexels()),
        std::min<std::size_t>(std::size_t(1) << 16,
                              (std::size_t(32) << 20) / std::max<std::size_t>(values * 4, 1)));
    std::vector<std::size_t> baseTexels, owners;
    baseTexels.reserve(chunk);
    owners.reserve(chunk);
    std::vector<float> read;
    std::vector<double> sums(count * values, 0.0);
    const auto flush = [&] {
        read.resize(baseTexels.size() * values);
        _base.readAbrdfs(baseTexels.data(), baseTexels.size(), read.data());
        for (std::size_t i = 0; i < baseTexels.size(); ++i) {
            double* sum = sums.data() + owners[i] * values;
            const float* value = read.data() + i * values;
            for (std::size_t v = 0; v < values; ++v) sum[v] += value[v];
        }
        baseTexels.clear();
        owners.clear();
    };
    for (std::size_t t = 0; t < count; ++t) {
        const int x = int(texels[t] % std::size_t(_width)),
                  y = int(texels[t] / std::size_t(_width));
        int x0, y0, x1, y1;
        _layout.footprint(x, y, x0, y0, x1, y1);
        for (int by = y0; by < y1; ++by)
            for (int bx = x0; bx < x1; ++bx) {
                baseTexels.push_back(std::size_t(by) * std::size_t(_base.width()) + bx);
                owners.push_back(t);
                if (baseTexels.size() == chunk) flush();
            }
    }
    if (!baseTexels.empty()) flush();
    for (std::size_t t = 0; t < count; ++t) {
        const int x = int(texels[t] % std::size_t(_width)),
                  y = int(texels[t] / std::size_t(_width));
        int x0, y0, x1, y1;
        _layout.footprint(x, y, x0, y0, x1, y1);
        const double n = double(x1 - x0) * double(y1 - y0);
        for (std::size_t v = 0; v < values; ++v)
            out[t * values + v] = float(sums[t * values + v] / n);
    }
}

void MipAtlasSource::readImages(std::size_t first, std::size_t count, float* out) const {
    const std::size_t baseTexels = _base.texelCount(), atlasTexels = texelCount();
    std::vector<float> image(baseTexels * 3);
    for (std::size_t i = 0; i < count; ++i) {
        _base.readImages(first + i, 1, image.data());
        float* atlas = out + i * atlasTexels * 3;
        for (int y = 0; y < _height; ++y)
            for (int x = 0; x < _width; ++x) {
                int x0, y0, x1, y1;
                _layout.footprint(x, y, x0, y0, x1, y1);
                double rgb[3] = {0, 0, 0};
                for (int by = y0; by < y1; ++by)
                    for (int bx = x0; bx < x1; ++bx)
                        for (int c = 0; c < 3; ++c)
                            rgb[c] += image[(std::size_t(by) * _base.width() + bx) * 3 + c];
                const double n = double(x1 - x0) * double(y1 - y0);
                for (int c = 0; c < 3; ++c)
                    atlas[(std::size_t(y) * _width + x) * 3 + c] = float(rgb[c] / n);
            }
    }
}

}  // namespace osgBTF
