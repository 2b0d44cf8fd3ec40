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

/** A candidate in one of the step's heaps: an add (key P) or a drop (key: its cost c). */
struct Candidate {
    double key = 0;
    int material = 0;
    std::size_t index = 0;  // TileLayout::index of `tile`
    TileId tile;
};

/** Max-heap order for adds: highest P first, then lowest material and index (determinism). */
bool addAfter(const Candidate& a, const Candidate& b) {
    if (a.key != b.key) return a.key < b.key;
    if (a.material != b.material) return a.material > b.material;
    return a.index > b.index;
}

/** Min-heap order for drops: lowest cost first, then lowest material and index. */
bool dropAfter(const Candidate& a, const Candidate& b) {
    if (a.key != b.key) return a.key > b.key;
    if (a.material != b.material) return a.material > b.material;
    return a.index > b.index;
}

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

double TileScheduler::Material::priority(const TileId& t,
                                         const std::vector<std::uint64_t>* counts) const {
    if (!counts) return 0;
    return double(weights[index(t)]) * double((*counts)[indexInGroup(t)]);
}

void TileScheduler::Material::setSlot(const TileId& t, int newSlot) {
    const std::size_t i = index(t);
    const int delta = (newSlot >= 0) - (slot[i] >= 0);
    slot[i] = newSlot;
    if (t.level > 0) {
        std::uint8_t& count = residentChildren[index(TileLayout::parent(t))];
        count = std::uint8_t(int(count) + delta);
    }
}

void TileScheduler::Material::updateLutAfterInsert(const TileId& t, int newSlot) {
    // Only the finest tiles inside t change: they showed t's parent (resident, as every
    // ancestor of a resident tile), and t was not resident, so nothing deeper was.
    const LutEntry entry{t.level, newSlot, slot[index(TileLayout::parent(t))]};
    const int finest = layout.finestLevel(), shift = finest - t.level;
    const int fw = tilesX[std::size_t(finest)], fh = tilesY[std::size_t(finest)];
    std::vector<LutEntry>& table = lut[std::size_t(t.group)];
    for (int y = t.y << shift; y < std::min((t.y + 1) << shift, fh); ++y)
        for (int x = t.x << shift; x < std::min((t.x + 1) << shift, fw); ++x) {
            LutEntry& e = table[std::size_t(y) * std::size_t(fw) + std::size_t(x)];
            if (e.level < t.level) e = entry;
        }
    lutDirty = true;
}

void TileScheduler::Material::updateLutAfterRemove(const TileId& t) {
    // Only leaves below level 0 leave: the entries t showed fall back to its parent.
    const TileId parent = TileLayout::parent(t);
    LutEntry fallback{parent.level, slot[index(parent)], -1};
    if (parent.level > 0) fallback.parentSlot = slot[index(TileLayout::parent(parent))];
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
    std::vector<Candidate> adds;   // heap, addAfter
    std::vector<Candidate> drops;  // heap, dropAfter

    StepState(TileScheduler& s, VoteCounts c) : scheduler(s), counts(std::move(c)) {}

    Material& mat(int m) { return scheduler._materials[std::size_t(m)]; }
    double priority(int m, const TileId& t) { return mat(m).priority(t, counts[std::size_t(m)]); }
    bool isAvailable(int m, const TileId& t) const { return !available || (*available)(m, t); }

    void pushAdd(int m, const TileId& t) {
        const double p = priority(m, t);
        if (p <= 0) return;
        adds.push_back({p, m, mat(m).index(t), t});
        std::push_heap(adds.begin(), adds.end(), addAfter);
    }

    /** An add candidate: not resident, parent resident, not removed in this step. */
    bool addable(int m, const TileId& t) {
        Material& mt = mat(m);
        const std::size_t i = mt.index(t);
        return t.level > 0 && mt.slot[i] < 0 && !(mt.stepFlags[i] & kRemovedNow) &&
               mt.isResident(TileLayout::parent(t));
    }

    /** A leaf below level 0 that was not added in this step. */
    bool droppable(const Material& mt, const TileId& t, std::size_t i) const {
        return t.level > 0 && mt.leaf(i) && !(mt.stepFlags[i] & kAddedNow);
    }

    /** Queues the drop of t if it is droppable now (its cost w v is fixed within the step). */
    void pushDrop(int m, const TileId& t) {
        Material& mt = mat(m);
        const std::size_t i = mt.index(t);
        if (!droppable(mt, t, i)) return;
        drops.push_back({priority(m, t), m, i, t});
        std::push_heap(drops.begin(), drops.end(), dropAfter);
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

    /** The cheapest drop still valid whose cost is below P* = x.key, other than x's parent
     *  (which x needs resident). */
    bool findDrop(const Candidate& x, Candidate& out) {
        bool found = false, parentSetAside = false;
        Candidate parent;
        const TileId xParent = TileLayout::parent(x.tile);
        while (!drops.empty() && drops.front().key < x.key) {
            std::pop_heap(drops.begin(), drops.end(), dropAfter);
            const Candidate d = drops.back();
            drops.pop_back();
            // Stale entries: dropped already, or no longer a leaf (a child came in).
            if (!droppable(mat(d.material), d.tile, d.index)) continue;
            if (d.material == x.material && d.tile == xParent) {
                parent = d;
                parentSetAside = true;
                continue;
            }
            out = d;
            found = true;
            break;
        }
        if (parentSetAside) {
            drops.push_back(parent);
            std::push_heap(drops.begin(), drops.end(), dropAfter);
        }
        return found;
    }

    void insert(int m, const TileId& t) {
        Material& mt = mat(m);
        const int slot = scheduler._freeSlots.back();
        scheduler._freeSlots.pop_back();
        mt.setSlot(t, slot);
        mt.stepFlags[mt.index(t)] |= kAddedNow;
        mt.updateLutAfterInsert(t, slot);
        ops.push_back({TileOperation::Kind::Add, TileOperation::Reason::Refine, m, t, slot});
        // Its children become add candidates (none is resident: their parent was not). Its
        // parent is no longer a leaf; its queued drop, if any, is skipped when popped.
        for (int dy = 0; dy < 2; ++dy)
            for (int dx = 0; dx < 2; ++dx) {
                const TileId ch{t.group, t.level + 1, 2 * t.x + dx, 2 * t.y + dy};
                if (mt.contains(ch) && addable(m, ch)) pushAdd(m, ch);
            }
    }

    void drop(int m, const TileId& t) {
        Material& mt = mat(m);
        const std::size_t i = mt.index(t);
        const int slot = mt.slot[i];
        mt.setSlot(t, -1);
        mt.stepFlags[i] |= kRemovedNow;
        mt.updateLutAfterRemove(t);
        scheduler._freeSlots.push_back(slot);
        ops.push_back({TileOperation::Kind::Remove, TileOperation::Reason::Evicted, m, t, slot});
        // The parent may have become a leaf itself.
        pushDrop(m, TileLayout::parent(t));
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
                                if (droppable(mt, t, i)) drops.push_back({priority(m, t), m, i, t});
                            } else if (addable(m, t)) {
                                const double p = priority(m, t);
                                if (p > 0) adds.push_back({p, m, i, t});
                            }
                        }
        }
        std::make_heap(adds.begin(), adds.end(), addAfter);
        std::make_heap(drops.begin(), drops.end(), dropAfter);
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
    m.residentChildren.assign(n, 0);
    m.stepFlags.assign(n, 0);
    std::size_t offset = 0;
    for (int l = 0; l <= layout.finestLevel(); ++l) {
        m.levelOffset.push_back(offset);
        m.tilesX.push_back(layout.tilesX(l));
        m.tilesY.push_back(layout.tilesY(l));
        offset += std::size_t(m.tilesX.back()) * std::size_t(m.tilesY.back());
    }
    const std::size_t finestTiles = std::size_t(m.tilesX.back()) * std::size_t(m.tilesY.back());
    for (int g = 0; g < layout.groups(); ++g) {
        const int slot = _freeSlots.back();
        _freeSlots.pop_back();
        m.setSlot({g, 0, 0, 0}, slot);
        m.lut.emplace_back(finestTiles, LutEntry{0, slot, -1});
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
            // Full: drop only when that costs less than the add gains (c* < P*, Schwartz et al.
            // 2013 5.2); otherwise the cache already holds the best set it can.
            Candidate d;
            if (!s.findDrop(x, d)) break;
            s.drop(d.material, d.tile);
        }
        s.insert(x.material, x.tile);
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
            if (m.slot[i] >= 0) continue;
            const TileId t = m.layout.tileAt(i);
            if (t.level == 0 || !m.isResident(TileLayout::parent(t))) continue;
            const double p = m.priority(t, counts[std::size_t(mi)]);
            if (p > 0 && !(skip && skip(mi, t))) found.push_back({p, mi, i, t});
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
