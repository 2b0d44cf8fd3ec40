// osgBTF BSVTF (Schwartz et al. 2013 sections 3, 5.1, 5.2): which tiles of which materials live in
// the shared tile cache. Pure logic: no OpenGL, no I/O; the runtime uploads what the operations say
// and re-uploads the lookup tables of the materials whose LUT changed.
//
// Priorities (Schwartz et al. 2013 section 5.2): a non-resident tile i of level l whose parent is
// resident has P = w(i,l,l-1) v(i,l) (eq. 8, 9): its mean squared difference to the upsampled
// parent times the feedback pixels it would serve. While slots are free the highest P is added.
// When the cache is full, a drop frees one slot if its cost c* (the error it brings back) is below
// the best P*; otherwise the cache already holds the best set and the step ends.
//
// Residency is closed under parents: a tile is resident only while its parent is, so the
// resident tiles of a group form a tree under its level-0 tile, and a region shows its deepest
// resident tile with every coarser one above it still in the cache. The shader needs that: a
// minified fragment blends its deepest resident level with the next coarser one (trilinear,
// streaming/bsvtf.frag), and the LUT gives both slots. Schwartz et al. 2013 5.1 instead removes a
// tile once its children cover it and swaps two leaves for their missing parent; neither exists
// here (no resident tile is ever covered, no non-resident tile has resident children). The price is
// the slots of the interior tiles: a third of the finest ones in a large square pyramid, more in
// small or elongated ones.
//
// Evictions: only drops. A resident leaf (no resident child) below level 0 is removed at cost
// c = w v, eq. 10 restricted to l' = l - 1: exactly the priority it gets back as an add candidate.
// With the approximate error E = sum of w v over the non-resident tiles, every add lowers E by
// its P and every drop raises it by its c, so each drop followed by its add lowers E by at least
// P* - c* > 0 and the scheduler converges (fixed votes: the operations stop after finitely many
// steps). Drops let stale tiles (v = 0) leave after the viewer moves on. The level-0 tiles are
// never removed: every texel of every material is always shown by some resident tile.
//
// Within one step no tile is removed and then added again, and no tile added in the step is
// removed in it (its upload would be wasted).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "streaming/TileLayout.h"

namespace osgBTF {

/** Feedback votes v(i,l) of Schwartz et al. 2013 eq. 9 for several materials. One count per tile
 * position of one group: the votes apply to every group of a material (Schwartz et al. 2013 5.2).
 */
class TileVotes {
public:
    TileVotes() = default;
    /** Adds a material with the tile grid of `layout` (its group count does not matter); returns
     *  its index. TileScheduler::makeVotes() adds the scheduler's materials in order. */
    int addMaterial(const TileLayout& layout);
    int materialCount() const { return int(_materials.size()); }

    /** Counts `count` feedback pixels showing tile (tileX, tileY) of `level`, and so every ancestor
     *  of it (eq. 9: a tile's vote includes its descendants'). A level above the finest counts for
     *  the finest tile containing it (the index is halved once per level too many); a level below
     *  0 for the level-0 tile (the index doubled once per level, so only (0, 0) is in range).
     *  Unknown materials and tiles outside the level are ignored. */
    void add(int material, int level, int tileX, int tileY, std::uint32_t count = 1);
    /** v(i,l) of `tile` (its group is ignored); 0 for unknown materials and tiles. */
    std::uint64_t votes(int material, const TileId& tile) const;
    /** Zeroes every count, keeping the materials. */
    void clear();

private:
    friend class TileScheduler;
    struct Material {
        TileLayout layout;
        std::vector<std::uint64_t> counts;  ///< per tile of group 0, TileLayout::index order
    };
    std::vector<Material> _materials;
};

/** One change of the tile cache, to be applied by the runtime in the order given. */
struct TileOperation {
    enum class Kind { Add, Remove };
    enum class Reason {
        Refine,  ///< Add: Schwartz et al. 2013's add, the tile's parent is resident
        Evicted  ///< Remove: a dropped leaf, followed by the Add it makes room for
    };
    Kind kind = Kind::Add;
    Reason reason = Reason::Refine;
    int material = 0;
    TileId tile;
    int slot = -1;  ///< the cache slot the tile goes to (Add) or leaves (Remove)
};

/** LUT entry of one finest-level tile position (Schwartz et al. 2013 section 3): the deepest
 * resident tile containing it, and the slot of that tile's parent (resident with it), from which a
 * minified fragment takes its coarser level. */
struct LutEntry {
    int level = -1;
    int slot = -1;
    int parentSlot = -1;  ///< -1 at level 0
    bool operator==(const LutEntry& o) const {
        return level == o.level && slot == o.slot && parentSlot == o.parentSlot;
    }
    bool operator!=(const LutEntry& o) const { return !(*this == o); }
};

class TileScheduler {
public:
    /** True when the tile's data are decoded and can be uploaded now. */
    using Availability = std::function<bool(int material, const TileId& tile)>;

    /** `capacity` cache slots 0 .. capacity - 1 (e.g. 56 x 56 = 3136 for a 4032^2 cache of 72^2
     *  tiles). Throws Error for capacity < 1. */
    explicit TileScheduler(int capacity);

    /** weights[layout.index(t)] = w(i,l,l-1) of Schwartz et al. 2013 eq. 8 (for level 0 the tile's
     * mean square); norms[layout.index(t)] = ||T||_F^2 / T^2 (groupPriority). Makes every group's
     *  level-0 tile resident at once (their slots: slotOf). Throws Error when the sizes do not
     *  match layout.tileCount(), a value is negative or not finite, or the level-0 tiles do not
     *  fit in the free slots. Returns the material index. */
    int addMaterial(const TileLayout& layout, std::vector<float> weights, std::vector<float> norms);
    int materialCount() const { return int(_materials.size()); }
    const TileLayout& layout(int material) const;
    /** Empty votes for every material added so far. */
    TileVotes makeVotes() const;

    /** One update (Schwartz et al. 2013 5.1, 5.2): adds by priority while slots are free, then
     * drops while cheaper than the best add; at most maxAdds Add operations (the upload budget;
     * removes are free). `available` empty means every tile is available. `votes` may hold fewer
     *  materials than the scheduler (the others have no votes). Slots: the lowest free one first,
     *  a freed one is the next handed out. Throws Error for maxAdds < 0, or votes of more
     *  materials or of another tile grid than the scheduler's. */
    std::vector<TileOperation> step(const TileVotes& votes, const Availability& available,
                                    int maxAdds);

    bool resident(int material, const TileId& tile) const;
    /** The tile's cache slot, -1 when it is not resident (or not in the material). */
    int slotOf(int material, const TileId& tile) const;
    int used() const { return _capacity - int(_freeSlots.size()); }
    int capacity() const { return _capacity; }

    /** The deepest resident tile containing finest-level tile (finestTileX, finestTileY). */
    LutEntry lookup(int material, int group, int finestTileX, int finestTileY) const;
    /** The whole LUT of a group: tilesX(L) x tilesY(L) entries, row by row from the bottom. */
    const std::vector<LutEntry>& lut(int material, int group) const;
    /** True when a LUT of the material changed since clearLutDirty (true after addMaterial). */
    bool lutDirty(int material) const;
    void clearLutDirty(int material);

    /** w(i,l,l-1) v(i,l) of a tile (0 for tiles outside the material). */
    double priority(int material, const TileId& tile, const TileVotes& votes) const;
    /** The add candidates (non-resident, parent resident, P > 0) of highest P, available or
     *  not: the fetcher requests those not yet decoded. At most maxCount, best first. */
    std::vector<std::pair<int, TileId>> wanted(const TileVotes& votes, std::size_t maxCount,
                                               const Availability& skip = {}) const;
    /** Sum over the group's resident tiles of v ||T||_F^2 / T^2: the priority of the group's U
     *  packet (Schwartz et al. 2013 section 6). */
    double groupPriority(int material, int group, const TileVotes& votes) const;

private:
    struct Material {
        TileLayout layout;
        std::vector<float> weights, norms;           ///< per tile, TileLayout::index order
        std::vector<int> slot;                       ///< per tile, -1 when not resident
        std::vector<std::uint8_t> residentChildren;  ///< per tile
        std::vector<std::uint8_t> stepFlags;         ///< added / removed in the current step
        std::vector<std::size_t> levelOffset;        ///< first within-group index of each level
        std::vector<int> tilesX, tilesY;             ///< per level
        std::vector<std::vector<LutEntry>> lut;      ///< per group, finest tiles row by row
        bool lutDirty = true;

        bool contains(const TileId& t) const;
        std::size_t indexInGroup(const TileId& t) const;
        std::size_t index(const TileId& t) const;
        bool isResident(const TileId& t) const { return slot[index(t)] >= 0; }
        bool leaf(std::size_t index) const {
            return slot[index] >= 0 && residentChildren[index] == 0;
        }
        /** w v, the add priority of Schwartz et al. 2013 5.2 (counts null: no votes). */
        double priority(const TileId& t, const std::vector<std::uint64_t>* counts) const;
        /** Sets the tile's slot (-1: not resident) and its parent's count of resident children. */
        void setSlot(const TileId& t, int slot);
        void updateLutAfterInsert(const TileId& t, int slot);
        void updateLutAfterRemove(const TileId& t);
    };
    struct StepState;
    using VoteCounts = std::vector<const std::vector<std::uint64_t>*>;

    /** Throws Error for an unknown material index. */
    const Material& materialAt(int material) const;
    Material& materialAt(int material);
    /** Per material the votes' counts (null when the votes lack it); throws Error on mismatch. */
    VoteCounts voteCounts(const TileVotes& votes) const;

    int _capacity = 0;
    std::vector<int> _freeSlots;  ///< a stack: the next Add takes back()
    std::vector<Material> _materials;
};

}  // namespace osgBTF
