// osgBTF BSVTF (seed 003 sections 3, 5.1, 5.2): which tiles of which materials live in the shared
// tile cache. Pure logic: no OpenGL, no I/O; the runtime uploads what the operations say and
// re-uploads the lookup tables of the materials whose LUT changed.
//
// Priorities (seed 003 section 5.2): a non-resident tile i of level l whose parent is resident has
// P = w(i,l,l-1) v(i,l) (eq. 8, 9): its mean squared difference to the upsampled parent times the
// feedback pixels it would serve. While slots are free the highest P is added. When the cache is
// full, an eviction frees one slot if its cost c* (the error it brings back) is below the best
// P*; otherwise the cache already holds the best set and the step ends.
//
// Evictions:
//  * swap (seed 003 5.1): two resident leaf children of a non-resident tile T' are replaced by T'.
//    The cost is eq. 10 restricted to l' = l - 1: c = w(c1) v(c1) + w(c2) v(c2). Why restricted:
//    the cost is then exactly the priority the two removed tiles get back as add candidates, so
//    with the approximate error E = sum of w v over tiles not covered by resident tiles of their
//    level or finer, every swap followed by its add lowers E by at least P* - c* > 0 and the
//    scheduler converges (fixed votes: the operations stop after finitely many steps).
//  * drop (extension): a resident leaf whose parent is resident is removed, cost w v. A swap always
//    inserts a tile, so without drops a leaf under a resident parent could never leave the cache:
//    after the viewer moves on, its stale tiles (v = 0) would stay resident for good. A drop is a
//    swap whose coarser tile is already resident; it keeps coverage and the same E argument.
// Both only ever remove leaves (resident tiles without resident descendants), so every texel
// stays covered.
//
// Post-condition of every insert (seed 003 5.1: "any ancestor ... completely covered"): a resident
// ancestor whose region is now entirely covered by resident descendants (all its children resident
// or themselves covered) no longer shows on screen and is removed. The level-0 tiles are not
// pinned: they are resident from addMaterial on and leave only when covered in this sense.
//
// Invariant: a non-resident tile with a resident descendant is covered. (Adds need a resident
// parent, a swap's T' covers its victims, a drop's parent covers its victim, so a covered
// region stays covered; a victim has no resident descendants.) Hence an add candidate has no
// resident descendants and P is exactly the drop in E its add brings.
//
// Within one step no tile is removed and then added again, and no tile added in the step is
// evicted in it (a tile added and then covered by its children in the same step is removed).
#pragma once

#include <cstddef>
#include <cstdint>
#include <functional>
#include <utility>
#include <vector>

#include "streaming/TileLayout.h"

namespace osgBTF {

/** Feedback votes v(i,l) of seed 003 eq. 9 for several materials. One count per tile position of
 *  one group: the votes apply to every group of a material (seed 003 5.2). */
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
        Refine,   ///< Add: seed 003's add, the tile's parent is resident
        SwapIn,   ///< Add: the coarser tile T' a swap inserts (preceded by its two Evicted)
        Covered,  ///< Remove: fully covered by resident descendants (post-condition of an insert)
        Evicted   ///< Remove: victim of a swap or drop, followed by the Add it makes room for
    };
    Kind kind = Kind::Add;
    Reason reason = Reason::Refine;
    int material = 0;
    TileId tile;
    int slot = -1;  ///< the cache slot the tile goes to (Add) or leaves (Remove)
};

/** LUT entry of one finest-level tile position (seed 003 section 3): the deepest resident tile
 *  containing it. */
struct LutEntry {
    int level = -1;
    int slot = -1;
    bool operator==(const LutEntry& o) const { return level == o.level && slot == o.slot; }
    bool operator!=(const LutEntry& o) const { return !(*this == o); }
};

class TileScheduler {
public:
    /** True when the tile's data are decoded and can be uploaded now. */
    using Availability = std::function<bool(int material, const TileId& tile)>;

    /** `capacity` cache slots 0 .. capacity - 1 (e.g. 56 x 56 = 3136 for a 4032^2 cache of 72^2
     *  tiles). Throws Error for capacity < 1. */
    explicit TileScheduler(int capacity);

    /** weights[layout.index(t)] = w(i,l,l-1) of seed 003 eq. 8 (for level 0 the tile's mean
     *  square); norms[layout.index(t)] = ||T||_F^2 / T^2 (groupPriority). Makes every group's
     *  level-0 tile resident at once (their slots: slotOf). Throws Error when the sizes do not
     *  match layout.tileCount(), a value is negative or not finite, or the level-0 tiles do not
     *  fit in the free slots. Returns the material index. */
    int addMaterial(const TileLayout& layout, std::vector<float> weights, std::vector<float> norms);
    int materialCount() const { return int(_materials.size()); }
    const TileLayout& layout(int material) const;
    /** Empty votes for every material added so far. */
    TileVotes makeVotes() const;

    /** One update (seed 003 5.1, 5.2): adds by priority while slots are free, then evictions
     *  while cheaper than the best add; at most maxAdds Add operations (the upload budget; removes
     *  are free). `available` empty means every tile is available. `votes` may hold fewer
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
    /** The add candidates (non-resident, parent resident, not covered, P > 0) of highest P,
     *  available or not: the fetcher requests those not yet decoded. At most maxCount, best
     *  first. (A swap's T' is not listed: it is an ancestor of resident tiles, whose data the
     *  runtime keeps anyway to decode them, seed 003 section 6.) */
    std::vector<std::pair<int, TileId>> wanted(const TileVotes& votes, std::size_t maxCount,
                                               const Availability& skip = {}) const;
    /** Sum over the group's resident tiles of v ||T||_F^2 / T^2: the priority of the group's U
     *  packet (seed 003 section 6). */
    double groupPriority(int material, int group, const TileVotes& votes) const;

private:
    struct Material {
        TileLayout layout;
        std::vector<float> weights, norms;        ///< per tile, TileLayout::index order
        std::vector<int> slot;                    ///< per tile, -1 when not resident
        std::vector<int> residentBelow;           ///< resident strict descendants per tile
        std::vector<std::uint8_t> childCount;     ///< existing children (0 at the finest level)
        std::vector<std::uint8_t> solidChildren;  ///< children resident or covered
        std::vector<std::uint8_t> stepFlags;      ///< added / removed in the current step
        std::vector<std::size_t> levelOffset;     ///< first within-group index of each level
        std::vector<int> tilesX, tilesY;          ///< per level
        std::vector<std::vector<LutEntry>> lut;   ///< per group, finest tiles row by row
        bool lutDirty = true;

        bool contains(const TileId& t) const;
        std::size_t indexInGroup(const TileId& t) const;
        std::size_t index(const TileId& t) const;
        bool isResident(const TileId& t) const { return slot[index(t)] >= 0; }
        /** All existing children resident or covered: no texel of the tile shows (finest: no). */
        bool covered(std::size_t index) const;
        bool leaf(std::size_t index) const { return slot[index] >= 0 && residentBelow[index] == 0; }
        /** w v, the add priority of seed 003 5.2 (counts null: no votes). */
        double priority(const TileId& t, const std::vector<std::uint64_t>* counts) const;
        /** Sets the tile's slot (-1: not resident) and the counts of its ancestors. */
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
