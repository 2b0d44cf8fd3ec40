#include "streaming/TileScheduler.h"

#include <algorithm>
#include <cmath>
#include <string>
#include <utility>

#include "core/Error.h"

namespace osgBTF {

namespace {

constexpr std::uint8_t kAddedNow = 1;    // inserted in the current step
constexpr std::uint8_t kRemovedNow = 2;  // removed in the current step

std::string gridName(const TileLayout& l) {
    return std::to_string(l.width()) + "x" + std::to_string(l.height()) + " texels in " +
           std::to_string(l.tileSize()) + "-texel tiles";
}

/** The tile of `level` (<= t.level) containing t. */
TileId ancestorAt(const TileId& t, int level) {
    const int shift = t.level - level;
    return {t.group, level, t.x >> shift, t.y >> shift};
}

/** A candidate in one of the step's heaps: an add (key P) or an eviction (key: its cost c). */
struct Candidate {
    double key = 0;
    int material = 0;
    std::size_t index = 0;  // TileLayout::index of `tile`
    TileId tile;
    bool swap = false;  // eviction: a swap inserting `tile`, else a drop of `tile`
};

/** Max-heap order for adds: highest P first, then lowest material and index (determinism). */
bool addAfter(const Candidate& a, const Candidate& b) {
    if (a.key != b.key) return a.key < b.key;
    if (a.material != b.material) return a.material > b.material;
    return a.index > b.index;
}

/** Min-heap order for evictions: lowest cost first, then lowest material and index, drops first. */
bool evictionAfter(const Candidate& a, const Candidate& b) {
    if (a.key != b.key) return a.key > b.key;
    if (a.material != b.material) return a.material > b.material;
    if (a.index != b.index) return a.index > b.index;
    return a.swap && !b.swap;
}

/** The tiles an eviction removes, cheapest first. */
struct Victims {
    TileId tiles[2];
    int count = 0;
};

}  // namespace

// ---------------------------------------------------------------------------------------------
// TileVotes

int TileVotes::addMaterial(const TileLayout& layout) {
    _materials.push_back({layout, std::vector<std::uint64_t>(layout.tilesPerGroup(), 0)});
    return int(_materials.size()) - 1;
}

void TileVotes::add(int material, int level, int tileX, int tileY, std::uint32_t count) {
    if (material < 0 || material >= materialCount() || count == 0 || tileX < 0 || tileY < 0) return;
    Material& m = _materials[std::size_t(material)];
    const int finest = m.layout.finestLevel();
    if (level > finest) {
        const int shift = std::min(level - finest, 30);
        tileX >>= shift;
        tileY >>= shift;
        level = finest;
    } else if (level < 0) {
        if (tileX != 0 || tileY != 0) return;
        level = 0;
    }
    TileId t{0, level, tileX, tileY};
    if (!m.layout.contains(t)) return;
    for (;;) {
        m.counts[m.layout.index(t)] += count;
        if (t.level == 0) break;
        t = TileLayout::parent(t);
    }
}

std::uint64_t TileVotes::votes(int material, const TileId& tile) const {
    if (material < 0 || material >= materialCount()) return 0;
    const Material& m = _materials[std::size_t(material)];
    const TileId t{0, tile.level, tile.x, tile.y};
    return m.layout.contains(t) ? m.counts[m.layout.index(t)] : 0;
}

void TileVotes::clear() {
    for (Material& m : _materials) std::fill(m.counts.begin(), m.counts.end(), 0);
}

// ---------------------------------------------------------------------------------------------
// TileScheduler::Material

bool TileScheduler::Material::contains(const TileId& t) const {
    return t.group >= 0 && t.group < layout.groups() && t.level >= 0 &&
           t.level <= layout.finestLevel() && t.x >= 0 && t.x < tilesX[std::size_t(t.level)] &&
           t.y >= 0 && t.y < tilesY[std::size_t(t.level)];
}

std::size_t TileScheduler::Material::indexInGroup(const TileId& t) const {
    const auto l = std::size_t(t.level);
    return levelOffset[l] + std::size_t(t.y) * std::size_t(tilesX[l]) + std::size_t(t.x);
}

std::size_t TileScheduler::Material::index(const TileId& t) const {
    return std::size_t(t.group) * layout.tilesPerGroup() + indexInGroup(t);
}

bool TileScheduler::Material::covered(std::size_t i) const {
    return childCount[i] > 0 && solidChildren[i] == childCount[i];
}

double TileScheduler::Material::priority(const TileId& t,
                                         const std::vector<std::uint64_t>* counts) const {
    if (!counts) return 0;
    return double(weights[index(t)]) * double((*counts)[indexInGroup(t)]);
}

void TileScheduler::Material::setSlot(const TileId& t, int newSlot) {
    const std::size_t i = index(t);
    // A tile is "solid" when resident or covered; a change propagates to the parents' counts of
    // solid children as long as it changes the parent's own solidity.
    const bool wasSolid = slot[i] >= 0 || covered(i);
    const int belowDelta = (newSlot >= 0) - (slot[i] >= 0);
    slot[i] = newSlot;
    const bool isSolid = slot[i] >= 0 || covered(i);
    bool solidChanged = wasSolid != isSolid;
    const int solidDelta = isSolid ? 1 : -1;
    for (TileId a = t; a.level > 0;) {
        a = TileLayout::parent(a);
        const std::size_t p = index(a);
        residentBelow[p] += belowDelta;
        if (solidChanged) {
            const bool parentWas = slot[p] >= 0 || covered(p);
            solidChildren[p] = std::uint8_t(int(solidChildren[p]) + solidDelta);
            solidChanged = parentWas != (slot[p] >= 0 || covered(p));
        }
    }
}

void TileScheduler::Material::updateLutAfterInsert(const TileId& t, int newSlot) {
    // Only the finest tiles inside t change, and only those shown by a coarser tile so far.
    const int finest = layout.finestLevel(), shift = finest - t.level;
    const int fw = tilesX[std::size_t(finest)], fh = tilesY[std::size_t(finest)];
    std::vector<LutEntry>& table = lut[std::size_t(t.group)];
    for (int y = t.y << shift; y < std::min((t.y + 1) << shift, fh); ++y)
        for (int x = t.x << shift; x < std::min((t.x + 1) << shift, fw); ++x) {
            LutEntry& e = table[std::size_t(y) * std::size_t(fw) + std::size_t(x)];
            if (e.level < t.level) e = {t.level, newSlot};
        }
    lutDirty = true;
}

void TileScheduler::Material::updateLutAfterRemove(const TileId& t) {
    // The entries t showed fall back to its deepest resident ancestor; none can be missing after
    // a whole step (a swap inserts its coarser tile right after removing the two victims).
    LutEntry fallback;
    for (TileId a = t; a.level > 0;) {
        a = TileLayout::parent(a);
        const int s = slot[index(a)];
        if (s >= 0) {
            fallback = {a.level, s};
            break;
        }
    }
    const int finest = layout.finestLevel(), shift = finest - t.level;
    const int fw = tilesX[std::size_t(finest)], fh = tilesY[std::size_t(finest)];
    std::vector<LutEntry>& table = lut[std::size_t(t.group)];
    for (int y = t.y << shift; y < std::min((t.y + 1) << shift, fh); ++y)
        for (int x = t.x << shift; x < std::min((t.x + 1) << shift, fw); ++x) {
            LutEntry& e = table[std::size_t(y) * std::size_t(fw) + std::size_t(x)];
            if (e.level == t.level) e = fallback;
        }
    lutDirty = true;
}

// ---------------------------------------------------------------------------------------------
// One step

struct TileScheduler::StepState {
    TileScheduler& scheduler;
    VoteCounts counts;
    const Availability* available = nullptr;  // null: everything is available
    std::vector<TileOperation> ops;
    std::vector<Candidate> adds;       // heap, addAfter
    std::vector<Candidate> evictions;  // heap, evictionAfter

    StepState(TileScheduler& s, VoteCounts c) : scheduler(s), counts(std::move(c)) {}

    Material& mat(int m) { return scheduler._materials[std::size_t(m)]; }
    double priority(int m, const TileId& t) { return mat(m).priority(t, counts[std::size_t(m)]); }
    bool isAvailable(int m, const TileId& t) const { return !available || (*available)(m, t); }

    void pushAdd(int m, const TileId& t) {
        const double p = priority(m, t);
        if (p <= 0) return;
        adds.push_back({p, m, mat(m).index(t), t, false});
        std::push_heap(adds.begin(), adds.end(), addAfter);
    }

    void pushEviction(const Candidate& c) {
        evictions.push_back(c);
        std::push_heap(evictions.begin(), evictions.end(), evictionAfter);
    }

    /** An add candidate: not resident, parent resident, some texel not covered by resident
     *  descendants, not removed in this step. */
    bool addable(int m, const TileId& t) {
        Material& mt = mat(m);
        const std::size_t i = mt.index(t);
        return t.level > 0 && mt.slot[i] < 0 && !(mt.stepFlags[i] & kRemovedNow) &&
               !mt.covered(i) && mt.isResident(TileLayout::parent(t));
    }

    /** A leaf that may be evicted in this step. */
    bool evictable(const Material& mt, std::size_t i) const {
        return mt.leaf(i) && !(mt.stepFlags[i] & kAddedNow);
    }

    /** Recomputes an eviction's validity, cost and victims from the current state. */
    bool evaluate(Candidate& c, Victims& v) {
        Material& mt = mat(c.material);
        const std::vector<std::uint64_t>* votes = counts[std::size_t(c.material)];
        v.count = 0;
        if (!c.swap) {
            // Drop: a leaf under a resident parent; the parent shows its texels afterwards.
            if (c.tile.level == 0 || !evictable(mt, c.index) ||
                !mt.isResident(TileLayout::parent(c.tile)))
                return false;
            c.key = mt.priority(c.tile, votes);
            v.tiles[v.count++] = c.tile;
            return true;
        }
        // Swap: T' = c.tile not resident, at least two evictable leaf children; the two cheapest.
        if (mt.slot[c.index] >= 0 || (mt.stepFlags[c.index] & kRemovedNow) ||
            mt.childCount[c.index] == 0 || mt.residentBelow[c.index] < 2)
            return false;
        double cost[2] = {0, 0};
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
                const TileId ch{c.tile.group, c.tile.level + 1, 2 * c.tile.x + dx,
                                2 * c.tile.y + dy};
                if (!mt.contains(ch) || !evictable(mt, mt.index(ch))) continue;
                const double w = mt.priority(ch, votes);
                // Children come in index order, so '<' keeps the lower index first on ties.
                if (v.count < 2) {
                    v.tiles[v.count] = ch;
                    cost[v.count++] = w;
                    if (v.count == 2 && cost[1] < cost[0]) {
                        std::swap(v.tiles[0], v.tiles[1]);
                        std::swap(cost[0], cost[1]);
                    }
                } else if (w < cost[1]) {
                    if (w < cost[0]) {
                        v.tiles[1] = v.tiles[0];
                        cost[1] = cost[0];
                        v.tiles[0] = ch;
                        cost[0] = w;
                    } else {
                        v.tiles[1] = ch;
                        cost[1] = w;
                    }
                }
            }
        if (v.count < 2) return false;
        c.key = cost[0] + cost[1];
        return true;
    }

    /** Pushes the eviction a leaf takes part in: a drop when its parent is resident, else the
     *  swap of its parent. */
    void pushEvictionOfLeaf(int m, const TileId& leaf) {
        Material& mt = mat(m);
        if (leaf.level == 0 || !evictable(mt, mt.index(leaf))) return;
        const TileId parent = TileLayout::parent(leaf);
        Candidate c;
        c.material = m;
        c.swap = !mt.isResident(parent);
        c.tile = c.swap ? parent : leaf;
        c.index = mt.index(c.tile);
        Victims v;
        if (evaluate(c, v)) pushEviction(c);
    }

    /** An eviction that would break the add of x or exceed the budget. */
    bool conflicts(const Candidate& x, const Candidate& e, const Victims& v, int addsLeft) const {
        if (e.swap && addsLeft < 2) return true;  // T' and x are two uploads
        if (e.material != x.material) return false;
        const TileId parent = TileLayout::parent(x.tile);
        for (int k = 0; k < v.count; ++k)
            if (v.tiles[k] == parent) return true;  // x needs its parent resident
        // Inserting x itself, or a tile inside x (it could cover x, which then adds nothing).
        // Cannot happen while the invariant in the header holds (x has no resident
        // descendants, T' has resident children); checked because the cost of a mistake would
        // be a tile added twice.
        return e.swap && e.tile.group == x.tile.group && e.tile.level >= x.tile.level &&
               ancestorAt(e.tile, x.tile.level) == x.tile;
    }

    /** The best add candidate that is still valid and available; false when none is left. */
    bool popAdd(Candidate& out) {
        while (!adds.empty()) {
            std::pop_heap(adds.begin(), adds.end(), addAfter);
            const Candidate c = adds.back();
            adds.pop_back();
            if (addable(c.material, c.tile) && isAvailable(c.material, c.tile)) {
                out = c;
                return true;
            }
        }
        return false;
    }

    /** The cheapest valid eviction compatible with adding x whose cost is below P* = x.key. */
    bool findEviction(const Candidate& x, int addsLeft, Candidate& out) {
        std::vector<Candidate> setAside;
        bool found = false;
        while (!evictions.empty() && evictions.front().key < x.key) {
            std::pop_heap(evictions.begin(), evictions.end(), evictionAfter);
            Candidate e = evictions.back();
            evictions.pop_back();
            const double stored = e.key;
            Victims v;
            if (!evaluate(e, v)) continue;
            if (e.key != stored) {  // stale cost: back in at the current one
                pushEviction(e);
                continue;
            }
            if (conflicts(x, e, v, addsLeft)) {
                setAside.push_back(e);
                continue;
            }
            if (e.swap && !isAvailable(e.material, e.tile)) continue;
            out = e;
            found = true;
            break;
        }
        for (const Candidate& c : setAside) pushEviction(c);
        return found;
    }

    void insert(int m, const TileId& t, TileOperation::Reason reason) {
        Material& mt = mat(m);
        const int slot = scheduler._freeSlots.back();
        scheduler._freeSlots.pop_back();
        mt.setSlot(t, slot);
        mt.stepFlags[mt.index(t)] |= kAddedNow;
        mt.updateLutAfterInsert(t, slot);
        ops.push_back({TileOperation::Kind::Add, reason, m, t, slot});
        // The children: new add candidates, or (already resident) leaves now under a resident
        // parent, i.e. drop candidates.
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
                const TileId ch{t.group, t.level + 1, 2 * t.x + dx, 2 * t.y + dy};
                if (!mt.contains(ch)) continue;
                if (mt.isResident(ch))
                    pushEvictionOfLeaf(m, ch);
                else if (addable(m, ch))
                    pushAdd(m, ch);
            }
        // Post-condition (seed 003 5.1): ancestors now entirely covered no longer show.
        for (TileId a = t; a.level > 0;) {
            a = TileLayout::parent(a);
            const std::size_t i = mt.index(a);
            if (mt.slot[i] >= 0 && mt.covered(i)) remove(m, a, TileOperation::Reason::Covered);
        }
    }

    void remove(int m, const TileId& t, TileOperation::Reason reason) {
        Material& mt = mat(m);
        const std::size_t i = mt.index(t);
        const int slot = mt.slot[i];
        mt.setSlot(t, -1);
        mt.stepFlags[i] |= kRemovedNow;
        mt.updateLutAfterRemove(t);
        scheduler._freeSlots.push_back(slot);
        ops.push_back({TileOperation::Kind::Remove, reason, m, t, slot});
    }

    /** Performs an eviction found by findEviction; returns the Add operations it used. */
    int evict(Candidate e) {
        Victims v;
        evaluate(e, v);  // valid: findEviction just checked it
        for (int k = 0; k < v.count; ++k)
            remove(e.material, v.tiles[k], TileOperation::Reason::Evicted);
        if (e.swap) {
            insert(e.material, e.tile, TileOperation::Reason::SwapIn);
            return 1;
        }
        // The victim's parent may have become a leaf itself.
        pushEvictionOfLeaf(e.material, TileLayout::parent(e.tile));
        return 0;
    }

    /** Every candidate from the current state: one scan over all tiles. */
    void collect() {
        for (int m = 0; m < int(scheduler._materials.size()); ++m) {
            Material& mt = mat(m);
            std::fill(mt.stepFlags.begin(), mt.stepFlags.end(), std::uint8_t(0));
            const int finest = mt.layout.finestLevel();
            std::size_t i = 0;  // TileLayout::index order: group, level, row, column
            for (int g = 0; g < mt.layout.groups(); ++g)
                for (int l = 0; l <= finest; ++l)
                    for (int y = 0; y < mt.tilesY[std::size_t(l)]; ++y)
                        for (int x = 0; x < mt.tilesX[std::size_t(l)]; ++x, ++i) {
                            const TileId t{g, l, x, y};
                            if (mt.slot[i] >= 0) {
                                if (l > 0 && mt.residentBelow[i] == 0 &&
                                    mt.isResident(TileLayout::parent(t)))
                                    evictions.push_back({priority(m, t), m, i, t, false});
                                continue;
                            }
                            if (addable(m, t)) {
                                const double p = priority(m, t);
                                if (p > 0) adds.push_back({p, m, i, t, false});
                            }
                            if (mt.residentBelow[i] >= 2 && mt.childCount[i] > 0) {
                                Candidate c{0, m, i, t, true};
                                Victims v;
                                if (evaluate(c, v)) evictions.push_back(c);
                            }
                        }
        }
        std::make_heap(adds.begin(), adds.end(), addAfter);
        std::make_heap(evictions.begin(), evictions.end(), evictionAfter);
    }
};

// ---------------------------------------------------------------------------------------------
// TileScheduler

TileScheduler::TileScheduler(int capacity) : _capacity(capacity) {
    if (capacity < 1)
        throw Error("tile scheduler: the cache needs at least one slot, got " +
                    std::to_string(capacity));
    _freeSlots.reserve(std::size_t(capacity));
    for (int s = capacity - 1; s >= 0; --s) _freeSlots.push_back(s);
}

int TileScheduler::addMaterial(const TileLayout& layout, std::vector<float> weights,
                               std::vector<float> norms) {
    const std::string name = "tile scheduler: material " + std::to_string(_materials.size());
    if (layout.groups() < 1) throw Error(name + " has no tile layout");
    if (weights.size() != layout.tileCount())
        throw Error(name + " has " + std::to_string(layout.tileCount()) + " tiles but " +
                    std::to_string(weights.size()) + " weights");
    if (norms.size() != layout.tileCount())
        throw Error(name + " has " + std::to_string(layout.tileCount()) + " tiles but " +
                    std::to_string(norms.size()) + " norms");
    for (std::size_t i = 0; i < weights.size(); ++i) {
        if (!std::isfinite(weights[i]) || weights[i] < 0)
            throw Error(name + ": weight " + std::to_string(i) + " is " +
                        std::to_string(weights[i]) + " (weights must be finite and >= 0)");
        if (!std::isfinite(norms[i]) || norms[i] < 0)
            throw Error(name + ": norm " + std::to_string(i) + " is " + std::to_string(norms[i]) +
                        " (norms must be finite and >= 0)");
    }
    if (std::size_t(layout.groups()) > _freeSlots.size())
        throw Error(name + " needs " + std::to_string(layout.groups()) +
                    " level-0 tiles (one per group) but only " + std::to_string(_freeSlots.size()) +
                    " of " + std::to_string(_capacity) + " cache slots are free");

    Material m;
    m.layout = layout;
    m.weights = std::move(weights);
    m.norms = std::move(norms);
    const std::size_t n = layout.tileCount();
    m.slot.assign(n, -1);
    m.residentBelow.assign(n, 0);
    m.solidChildren.assign(n, 0);
    m.stepFlags.assign(n, 0);
    std::size_t offset = 0;
    for (int l = 0; l <= layout.finestLevel(); ++l) {
        m.levelOffset.push_back(offset);
        m.tilesX.push_back(layout.tilesX(l));
        m.tilesY.push_back(layout.tilesY(l));
        offset += std::size_t(m.tilesX.back()) * std::size_t(m.tilesY.back());
    }
    m.childCount.assign(n, 0);
    for (std::size_t i = 0; i < n; ++i) {
        const TileId t = layout.tileAt(i);
        if (t.level > 0) ++m.childCount[m.index(TileLayout::parent(t))];
    }
    const std::size_t finestTiles = std::size_t(m.tilesX.back()) * std::size_t(m.tilesY.back());
    for (int g = 0; g < layout.groups(); ++g) {
        const int slot = _freeSlots.back();
        _freeSlots.pop_back();
        m.setSlot({g, 0, 0, 0}, slot);
        m.lut.emplace_back(finestTiles, LutEntry{0, slot});
    }
    m.lutDirty = true;
    _materials.push_back(std::move(m));
    return int(_materials.size()) - 1;
}

const TileScheduler::Material& TileScheduler::materialAt(int material) const {
    if (material < 0 || material >= materialCount())
        throw Error("tile scheduler: no material " + std::to_string(material) + " (there are " +
                    std::to_string(materialCount()) + ")");
    return _materials[std::size_t(material)];
}

TileScheduler::Material& TileScheduler::materialAt(int material) {
    return const_cast<Material&>(std::as_const(*this).materialAt(material));
}

const TileLayout& TileScheduler::layout(int material) const {
    return materialAt(material).layout;
}

TileVotes TileScheduler::makeVotes() const {
    TileVotes votes;
    for (const Material& m : _materials) votes.addMaterial(m.layout);
    return votes;
}

TileScheduler::VoteCounts TileScheduler::voteCounts(const TileVotes& votes) const {
    if (votes.materialCount() > materialCount())
        throw Error("tile scheduler: the votes are for " + std::to_string(votes.materialCount()) +
                    " materials, the scheduler has " + std::to_string(materialCount()));
    VoteCounts counts(_materials.size(), nullptr);
    for (int i = 0; i < votes.materialCount(); ++i) {
        const TileLayout& v = votes._materials[std::size_t(i)].layout;
        const TileLayout& s = _materials[std::size_t(i)].layout;
        if (v.width() != s.width() || v.height() != s.height() || v.tileSize() != s.tileSize())
            throw Error("tile scheduler: the votes of material " + std::to_string(i) + " are for " +
                        gridName(v) + ", the material has " + gridName(s));
        counts[std::size_t(i)] = &votes._materials[std::size_t(i)].counts;
    }
    return counts;
}

std::vector<TileOperation> TileScheduler::step(const TileVotes& votes,
                                               const Availability& available, int maxAdds) {
    if (maxAdds < 0)
        throw Error("tile scheduler: the add budget must be >= 0, got " + std::to_string(maxAdds));
    StepState s(*this, voteCounts(votes));
    if (available) s.available = &available;
    if (maxAdds == 0) return {};
    s.collect();
    int addsLeft = maxAdds;
    while (addsLeft > 0) {
        Candidate x;
        if (!s.popAdd(x)) break;
        if (_freeSlots.empty()) {
            // Full: evict only when that costs less than the add gains (c* < P*, seed 003 5.2);
            // otherwise the cache already holds the best set it can.
            Candidate e;
            if (!s.findEviction(x, addsLeft, e)) break;
            addsLeft -= s.evict(e);
        }
        s.insert(x.material, x.tile, TileOperation::Reason::Refine);
        --addsLeft;
    }
    return std::move(s.ops);
}

bool TileScheduler::resident(int material, const TileId& tile) const {
    return slotOf(material, tile) >= 0;
}

int TileScheduler::slotOf(int material, const TileId& tile) const {
    const Material& m = materialAt(material);
    return m.contains(tile) ? m.slot[m.index(tile)] : -1;
}

LutEntry TileScheduler::lookup(int material, int group, int finestTileX, int finestTileY) const {
    const Material& m = materialAt(material);
    const int fw = m.tilesX.back(), fh = m.tilesY.back();
    if (group < 0 || group >= m.layout.groups() || finestTileX < 0 || finestTileX >= fw ||
        finestTileY < 0 || finestTileY >= fh)
        throw Error("tile scheduler: material " + std::to_string(material) + " has no group " +
                    std::to_string(group) + " finest tile (" + std::to_string(finestTileX) + ", " +
                    std::to_string(finestTileY) + "); it has " + std::to_string(m.layout.groups()) +
                    " groups of " + std::to_string(fw) + "x" + std::to_string(fh) +
                    " finest tiles");
    return m.lut[std::size_t(group)]
                [std::size_t(finestTileY) * std::size_t(fw) + std::size_t(finestTileX)];
}

const std::vector<LutEntry>& TileScheduler::lut(int material, int group) const {
    const Material& m = materialAt(material);
    if (group < 0 || group >= m.layout.groups())
        throw Error("tile scheduler: material " + std::to_string(material) + " has no group " +
                    std::to_string(group) + " (it has " + std::to_string(m.layout.groups()) + ")");
    return m.lut[std::size_t(group)];
}

bool TileScheduler::lutDirty(int material) const {
    return materialAt(material).lutDirty;
}

void TileScheduler::clearLutDirty(int material) {
    materialAt(material).lutDirty = false;
}

double TileScheduler::priority(int material, const TileId& tile, const TileVotes& votes) const {
    const Material& m = materialAt(material);
    if (!m.contains(tile)) return 0;
    return m.priority(tile, voteCounts(votes)[std::size_t(material)]);
}

std::vector<std::pair<int, TileId>> TileScheduler::wanted(const TileVotes& votes,
                                                          std::size_t maxCount,
                                                          const Availability& skip) const {
    const VoteCounts counts = voteCounts(votes);
    std::vector<Candidate> found;
    for (int mi = 0; mi < materialCount(); ++mi) {
        const Material& m = _materials[std::size_t(mi)];
        if (!counts[std::size_t(mi)]) continue;
        for (std::size_t i = 0; i < m.slot.size(); ++i) {
            if (m.slot[i] >= 0 || m.covered(i)) continue;
            const TileId t = m.layout.tileAt(i);
            if (t.level == 0 || !m.isResident(TileLayout::parent(t))) continue;
            const double p = m.priority(t, counts[std::size_t(mi)]);
            if (p > 0 && !(skip && skip(mi, t))) found.push_back({p, mi, i, t, false});
        }
    }
    // addAfter(a, b): a ranks below b, so the reverse order sorts best first.
    const auto better = [](const Candidate& a, const Candidate& b) { return addAfter(b, a); };
    const std::size_t n = std::min(maxCount, found.size());
    std::partial_sort(found.begin(), found.begin() + std::ptrdiff_t(n), found.end(), better);
    std::vector<std::pair<int, TileId>> out;
    out.reserve(n);
    for (std::size_t k = 0; k < n; ++k) out.emplace_back(found[k].material, found[k].tile);
    return out;
}

double TileScheduler::groupPriority(int material, int group, const TileVotes& votes) const {
    const Material& m = materialAt(material);
    if (group < 0 || group >= m.layout.groups())
        throw Error("tile scheduler: material " + std::to_string(material) + " has no group " +
                    std::to_string(group) + " (it has " + std::to_string(m.layout.groups()) + ")");
    const std::vector<std::uint64_t>* counts = voteCounts(votes)[std::size_t(material)];
    if (!counts) return 0;
    const std::size_t first = std::size_t(group) * m.layout.tilesPerGroup();
    double sum = 0;
    for (std::size_t k = 0; k < m.layout.tilesPerGroup(); ++k)
        if (m.slot[first + k] >= 0) sum += double((*counts)[k]) * double(m.norms[first + k]);
    return sum;
}

}  // namespace osgBTF
