// osgBTF BSVTF (Schwartz et al. 2013 sections 3 and 5): the tile pyramid of a factored BTF's
// Eigen-Textures.
//
// Every group of 4 Eigen-Texture components (one RGBA16F texel each, Schwartz et al. 2013 section
// 7) is its own virtual texture with its own level-of-detail quadtree, which is the paper's
// side-by-side layout with no tile straddling two groups. Level L (the finest) is the texture
// itself; level l < L has ceil(width / 2^(L-l)) x ceil(height / 2^(L-l)) texels (texel k of level l
// is the box mean of texels 2k, 2k+1 of level l+1 that exist), and L is the smallest level count
// with both sides of level 0 at most T, so level 0 is one tile (Schwartz et al. 2013: max(M, N) /
// 2^L <= T). A texel (x, y) of the finest level is texel (x >> (L-l), y >> (L-l)) of level l.
//
// Why ceil-halved levels instead of padding to a power of two (400 -> 512): the levels then are
// exactly the box-filtered texture (no resampling, so a cache holding every finest tile renders
// exactly the FMF), and the quadtree still holds: tile i of level l+1 lies inside tile i / 2 of
// level l. Tiles at the right or top edge are partly outside their level; their outside texels and
// the padding (P texels on each side, for filtering in the cache) repeat the level with
// wrap-around, as the material tiles on a surface.
//
// Tile texel rows run from the bottom (y up), as everywhere in osgBTF.
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <vector>

namespace osgBTF {

/** One tile of a material's pyramid: group of 4 components, level (0 = coarsest), tile column
 *  and row within the level. */
struct TileId {
    int group = 0, level = 0, x = 0, y = 0;
    bool operator==(const TileId& o) const {
        return group == o.group && level == o.level && x == o.x && y == o.y;
    }
    bool operator!=(const TileId& o) const { return !(*this == o); }
};

class TileLayout {
public:
    static constexpr int kDefaultTileSize = 64;  ///< T (Schwartz et al. 2013 section 7)
    static constexpr int kDefaultPadding = 4;    ///< texels of padding on each side
    static constexpr int kChannels = 4;          ///< components per texel (RGBA16F)

    TileLayout() = default;
    /** Throws Error for sizes < 1, groups < 1, tileSize < 8 or not a multiple of 8 (the codec's
     *  DCT blocks), padding < 0 or with (tileSize + 2 padding) not a multiple of 8. */
    TileLayout(int width, int height, int groups, int tileSize = kDefaultTileSize,
               int padding = kDefaultPadding);

    int width() const { return _width; }
    int height() const { return _height; }
    int groups() const { return _groups; }
    int tileSize() const { return _tileSize; }
    int padding() const { return _padding; }
    /** T + 2 P: the side of a tile as stored and in the cache (72 for the defaults). */
    int paddedTileSize() const { return _tileSize + 2 * _padding; }
    /** Bytes of one uncompressed tile: (T + 2P)^2 x 4 half floats (41,472 for the defaults). */
    std::size_t tileBytes() const;

    /** L + 1 levels, 0 the coarsest (one tile), L = finestLevel() the texture itself. */
    int levels() const { return _finestLevel + 1; }
    int finestLevel() const { return _finestLevel; }
    int levelWidth(int level) const;
    int levelHeight(int level) const;
    int tilesX(int level) const;
    int tilesY(int level) const;

    bool contains(const TileId& tile) const;
    /** Level - 1, tile / 2 (the tile's level must be > 0). */
    static TileId parent(const TileId& tile);
    /** The 1 to 4 tiles of level + 1 inside `tile` (none for the finest level). */
    std::vector<TileId> children(const TileId& tile) const;
    /** The tile of `level` holding finest-level texel (x, y) (0 <= x < width, 0 <= y < height). */
    TileId tileOfTexel(int group, int level, int x, int y) const;

    /** Tiles of one group over all levels, and of all groups. */
    std::size_t tilesPerGroup() const { return _tilesPerGroup; }
    std::size_t tileCount() const { return _tilesPerGroup * std::size_t(_groups); }
    /** Dense index of a tile in [0, tileCount()): group-major, then level, then row, column. */
    std::size_t index(const TileId& tile) const;
    TileId tileAt(std::size_t index) const;

private:
    int _width = 0, _height = 0, _groups = 0;
    int _tileSize = kDefaultTileSize, _padding = kDefaultPadding, _finestLevel = 0;
    std::vector<std::size_t> _levelOffset;  ///< first index of each level within a group
    std::size_t _tilesPerGroup = 0;
};

}  // namespace osgBTF

template <>
struct std::hash<osgBTF::TileId> {
    std::size_t operator()(const osgBTF::TileId& t) const noexcept {
        return (std::size_t(t.group) * 73856093u) ^ (std::size_t(t.level) * 19349663u) ^
               (std::size_t(t.x) * 83492791u) ^ (std::size_t(t.y) * 2654435761u);
    }
};
