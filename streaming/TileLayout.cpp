#include "streaming/TileLayout.h"

#include <string>

#include "core/Error.h"

namespace osgBTF {

namespace {
int ceilShift(int size, int shift) {
    return int((std::int64_t(size) + (std::int64_t(1) << shift) - 1) >> shift);
}
}  // namespace

TileLayout::TileLayout(int width, int height, int groups, int tileSize, int padding)
    : _width(width), _height(height), _groups(groups), _tileSize(tileSize), _padding(padding) {
    if (width < 1 || height < 1)
        throw Error("tile layout: the texture must have at least 1 x 1 texels, got " +
                    std::to_string(width) + "x" + std::to_string(height));
    if (groups < 1)
        throw Error("tile layout: at least one group of components is needed, got " +
                    std::to_string(groups));
    if (tileSize < 8 || tileSize % 8 != 0)
        throw Error(
            "tile layout: the tile size must be a positive multiple of 8 (the codec's DCT "
            "blocks), got " +
            std::to_string(tileSize));
    if (padding < 0 || (tileSize + 2 * padding) % 8 != 0 || padding > tileSize)
        throw Error(
            "tile layout: the padding must be at most the tile size and make T + 2 P a "
            "multiple of 8, got " +
            std::to_string(padding));
    while (ceilShift(width, _finestLevel) > tileSize || ceilShift(height, _finestLevel) > tileSize)
        ++_finestLevel;
    for (int level = 0; level <= _finestLevel; ++level) {
        _levelOffset.push_back(_tilesPerGroup);
        _tilesPerGroup += std::size_t(tilesX(level)) * std::size_t(tilesY(level));
    }
}

std::size_t TileLayout::tileBytes() const {
    return std::size_t(paddedTileSize()) * std::size_t(paddedTileSize()) * kChannels * 2;
}

int TileLayout::levelWidth(int level) const {
    return ceilShift(_width, _finestLevel - level);
}
int TileLayout::levelHeight(int level) const {
    return ceilShift(_height, _finestLevel - level);
}
int TileLayout::tilesX(int level) const {
    return (levelWidth(level) + _tileSize - 1) / _tileSize;
}
int TileLayout::tilesY(int level) const {
    return (levelHeight(level) + _tileSize - 1) / _tileSize;
}

bool TileLayout::contains(const TileId& t) const {
    return t.group >= 0 && t.group < _groups && t.level >= 0 && t.level <= _finestLevel &&
           t.x >= 0 && t.x < tilesX(t.level) && t.y >= 0 && t.y < tilesY(t.level);
}

TileId TileLayout::parent(const TileId& t) {
    return {t.group, t.level - 1, t.x / 2, t.y / 2};
}

std::vector<TileId> TileLayout::children(const TileId& t) const {
    std::vector<TileId> out;
    if (t.level >= _finestLevel) return out;
    for (int dy = 0; dy < 2; ++dy)
        for (int dx = 0; dx < 2; ++dx) {
            const TileId c{t.group, t.level + 1, 2 * t.x + dx, 2 * t.y + dy};
            if (contains(c)) out.push_back(c);
        }
    return out;
}

TileId TileLayout::tileOfTexel(int group, int level, int x, int y) const {
    const int shift = _finestLevel - level;
    return {group, level, (x >> shift) / _tileSize, (y >> shift) / _tileSize};
}

std::size_t TileLayout::index(const TileId& t) const {
    return std::size_t(t.group) * _tilesPerGroup + _levelOffset[std::size_t(t.level)] +
           std::size_t(t.y) * std::size_t(tilesX(t.level)) + std::size_t(t.x);
}

TileId TileLayout::tileAt(std::size_t index) const {
    TileId t;
    t.group = int(index / _tilesPerGroup);
    std::size_t rest = index % _tilesPerGroup;
    t.level = _finestLevel;
    while (t.level > 0 && _levelOffset[std::size_t(t.level)] > rest) --t.level;
    rest -= _levelOffset[std::size_t(t.level)];
    t.x = int(rest % std::size_t(tilesX(t.level)));
    t.y = int(rest / std::size_t(tilesX(t.level)));
    return t;
}

}  // namespace osgBTF
