// BSVTF tile scheduler (streaming/TileScheduler.h, Schwartz et al. 2013 sections 5.1 and 5.2):
// refusals with their messages, hand-worked steps on a 7-tile pyramid (adds, drops, the LUT with
// the parents' slots), and randomized runs over several materials checked after every step against
// brute force: the ancestor chain (a tile resident only with its parent, level 0 always), slots,
// LUT (deepest resident tile and its parent's slot), every add and drop against the rules and
// priorities recomputed here from the raw feedback, the budget, and that a step only stops when
// no allowed operation lowers the error. Then convergence, a cache big enough for everything, and
// the scale of a 100-material scene.
#include <algorithm>
#include <chrono>
#include <cstdint>
#include <functional>
#include <iostream>
#include <random>
#include <set>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "core/Error.h"
#include "streaming/TileLayout.h"
#include "streaming/TileScheduler.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

using Kind = TileOperation::Kind;
using Reason = TileOperation::Reason;

std::string messageOf(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no error)";
}

std::string describe(const TileOperation& op) {
    static const char* reasons[] = {"Refine", "Evicted"};
    return std::string(op.kind == Kind::Add ? "Add " : "Remove ") + reasons[int(op.reason)] + " m" +
           std::to_string(op.material) + " g" + std::to_string(op.tile.group) + " l" +
           std::to_string(op.tile.level) + " (" + std::to_string(op.tile.x) + "," +
           std::to_string(op.tile.y) + ") @" + std::to_string(op.slot);
}

std::vector<std::string> describe(const std::vector<TileOperation>& ops) {
    std::vector<std::string> out;
    for (const TileOperation& op : ops) out.push_back(describe(op));
    return out;
}

bool allAvailable(int, const TileId&) {
    return true;
}

// ---- the hand-worked pyramid -------------------------------------------------------------------
// 32 x 8 texels in 8-texel tiles, one group: level 2 is 4 x 1 tiles, level 1 (16 x 4) 2 x 1,
// level 0 (8 x 2) one tile. Names and weights w(i,l,l-1):
//            R (w 1)
//      A (w 5)      B (w 4)
//   a0 (3) a1 (2)  b0 (6) b1 (1)
const TileId R{0, 0, 0, 0}, A{0, 1, 0, 0}, B{0, 1, 1, 0};
const TileId a0{0, 2, 0, 0}, a1{0, 2, 1, 0}, b0{0, 2, 2, 0}, b1{0, 2, 3, 0};

TileLayout handLayout() {
    return TileLayout(32, 8, 1, 8, 0);
}

std::vector<float> handWeights() {
    // TileLayout::index order: R, A, B, a0, a1, b0, b1.
    return {1, 5, 4, 3, 2, 6, 1};
}

/** Votes of finest tiles a0, a1, b0, b1 (level 2). */
TileVotes handVotes(const TileScheduler& s, std::uint32_t va0, std::uint32_t va1, std::uint32_t vb0,
                    std::uint32_t vb1) {
    TileVotes v = s.makeVotes();
    v.add(0, 2, 0, 0, va0);
    v.add(0, 2, 1, 0, va1);
    v.add(0, 2, 2, 0, vb0);
    v.add(0, 2, 3, 0, vb1);
    return v;
}

std::string op(Kind kind, Reason reason, const TileId& t, int slot) {
    TileOperation o;
    o.kind = kind;
    o.reason = reason;
    o.tile = t;
    o.slot = slot;
    return describe(o);
}
std::string add(const TileId& t, int slot) {
    return op(Kind::Add, Reason::Refine, t, slot);
}
std::string evicted(const TileId& t, int slot) {
    return op(Kind::Remove, Reason::Evicted, t, slot);
}

// ---- brute force over a scheduler's queries
// ------------------------------------------------------

bool hasResidentDescendant(const TileScheduler& s, int m, const TileId& t) {
    for (const TileId& c : s.layout(m).children(t))
        if (s.resident(m, c) || hasResidentDescendant(s, m, c)) return true;
    return false;
}

/** The deepest resident tile over a finest tile, by walking every level, with the slot of the
 *  tile one level up (whatever it holds: the check that it is resident is separate). */
LutEntry deepestResident(const TileScheduler& s, int m, int g, int fx, int fy) {
    const int L = s.layout(m).finestLevel();
    for (int l = L; l >= 0; --l) {
        const TileId t{g, l, fx >> (L - l), fy >> (L - l)};
        if (!s.resident(m, t)) continue;
        const int parentSlot =
            l > 0 ? s.slotOf(m, {g, l - 1, fx >> (L - l + 1), fy >> (L - l + 1)}) : -1;
        return {l, s.slotOf(m, t), parentSlot};
    }
    return {};
}

/** One feedback record as the runtime hands it over. */
struct Feedback {
    int material, level, x, y;
    std::uint32_t count;
};

/** v(i,l) of eq. 9 straight from the records: those at level >= l whose tile at l is i. Levels
 *  above the finest count for the finest tile containing them, levels below 0 (tile (0, 0)) for
 *  the root (TileVotes::add). */
std::uint64_t bruteVotes(const std::vector<Feedback>& feedback, const TileLayout& layout, int m,
                         const TileId& t) {
    std::uint64_t v = 0;
    const int L = layout.finestLevel();
    for (const Feedback& f : feedback) {
        if (f.material != m) continue;
        int level = f.level, x = f.x, y = f.y;
        if (level > L) {
            x >>= level - L;
            y >>= level - L;
            level = L;
        } else if (level < 0) {
            if (x != 0 || y != 0) continue;
            level = 0;
        }
        if (x < 0 || y < 0 || x >= layout.tilesX(level) || y >= layout.tilesY(level)) continue;
        if (level >= t.level && (x >> (level - t.level)) == t.x && (y >> (level - t.level)) == t.y)
            v += f.count;
    }
    return v;
}

// ---- randomized runs
// -----------------------------------------------------------------------------

struct World {
    std::vector<TileLayout> layouts;
    std::vector<std::vector<float>> weights;
    TileScheduler scheduler;
    explicit World(int capacity) : scheduler(capacity) {}

    void addMaterial(const TileLayout& layout, std::mt19937& rng, bool allPositive) {
        std::uniform_real_distribution<float> uni(0.f, 1.f);
        std::vector<float> w(layout.tileCount()), n(layout.tileCount());
        for (std::size_t i = 0; i < w.size(); ++i) {
            w[i] = (!allPositive && uni(rng) < 0.1f) ? 0.f : 0.01f + uni(rng);
            n[i] = uni(rng);
        }
        layouts.push_back(layout);
        weights.push_back(w);
        scheduler.addMaterial(layout, w, n);
    }
    std::size_t totalTiles() const {
        std::size_t n = 0;
        for (const TileLayout& l : layouts) n += l.tileCount();
        return n;
    }
};

/** Availability that changes from step to step but is fixed within one. */
bool pseudoAvailable(std::uint64_t seed, int step, int m, std::size_t index) {
    std::uint64_t h = seed * 0x9E3779B97F4A7C15ull + std::uint64_t(step) * 0xBF58476D1CE4E5B9ull +
                      std::uint64_t(m) * 0x94D049BB133111EBull + index;
    h ^= h >> 31;
    h *= 0xD6E8FEB86CA6F1D3ull;
    h ^= h >> 29;
    return (h % 100) < 75;
}

/** Everything that must hold after a step, from the scheduler's queries alone. */
void checkState(const World& w, const char* where) {
    SCOPED_TRACE(where);
    const TileScheduler& s = w.scheduler;
    std::set<int> slots;
    int residentCount = 0;
    for (int m = 0; m < int(w.layouts.size()); ++m) {
        const TileLayout& layout = w.layouts[std::size_t(m)];
        for (std::size_t i = 0; i < layout.tileCount(); ++i) {
            const TileId t = layout.tileAt(i);
            if (!s.resident(m, t)) continue;
            ++residentCount;
            const int slot = s.slotOf(m, t);
            EXPECT_TRUE(slot >= 0 && slot < s.capacity()) << slot;
            EXPECT_TRUE(slots.insert(slot).second) << "slot " << slot << " used twice";
        }
        // The ancestor chain: every level-0 tile resident, every other tile only with its parent
        // (so every ancestor of a resident tile is resident).
        for (std::size_t i = 0; i < layout.tileCount(); ++i) {
            const TileId t = layout.tileAt(i);
            if (t.level == 0) {
                EXPECT_TRUE(s.resident(m, t)) << "material " << m << " level-0 tile " << i;
            } else if (s.resident(m, t)) {
                EXPECT_TRUE(s.resident(m, TileLayout::parent(t)))
                    << "material " << m << " tile " << i << " is resident without its parent";
            }
        }
        const int L = layout.finestLevel();
        for (int g = 0; g < layout.groups(); ++g)
            for (int fy = 0; fy < layout.tilesY(L); ++fy)
                for (int fx = 0; fx < layout.tilesX(L); ++fx) {
                    const LutEntry want = deepestResident(s, m, g, fx, fy);
                    ASSERT_GE(want.level, 0)
                        << "material " << m << " group " << g << " finest tile " << fx << "," << fy
                        << " is not covered";
                    const LutEntry got = s.lookup(m, g, fx, fy);
                    EXPECT_EQ(got.level, want.level) << m << " " << g << " " << fx << "," << fy;
                    EXPECT_EQ(got.slot, want.slot) << m << " " << g << " " << fx << "," << fy;
                    EXPECT_EQ(got.parentSlot, want.parentSlot)
                        << m << " " << g << " " << fx << "," << fy;
                    if (want.level > 0) {
                        EXPECT_GE(want.parentSlot, 0) << "the parent of a resident tile is not";
                    }
                }
    }
    EXPECT_EQ(s.used(), residentCount);
    EXPECT_LE(s.used(), s.capacity());
}

struct StepCheck {
    const World& world;
    const std::vector<Feedback>& feedback;
    std::function<bool(int, const TileId&)> available;
    int maxAdds;

    double priority(int m, const TileId& t) const {
        const TileLayout& l = world.layouts[std::size_t(m)];
        return double(world.weights[std::size_t(m)][l.index(t)]) *
               double(bruteVotes(feedback, l, m, t));
    }

    /** Replays `ops` on a copy of the residency before the step (`before`: slot per material
     *  and tile) and checks every operation against the rules. */
    void replay(std::vector<std::vector<int>> shadow, const std::vector<TileOperation>& ops,
                std::set<std::pair<int, std::size_t>>& removedNow) const {
        const int capacity = world.scheduler.capacity();
        auto used = [&] {
            int n = 0;
            for (const auto& v : shadow)
                for (int x : v) n += x >= 0;
            return n;
        };
        auto residentIn = [&](int m, const TileId& t) {
            return shadow[std::size_t(m)][world.layouts[std::size_t(m)].index(t)] >= 0;
        };
        std::function<bool(int, const TileId&)> anyBelow = [&](int m, const TileId& t) {
            for (const TileId& c : world.layouts[std::size_t(m)].children(t))
                if (residentIn(m, c) || anyBelow(m, c)) return true;
            return false;
        };
        std::set<std::pair<int, std::size_t>> addedNow;
        int adds = 0;
        for (std::size_t k = 0; k < ops.size(); ++k) {
            const TileOperation& o = ops[k];
            SCOPED_TRACE("operation " + std::to_string(k) + ": " + describe(o));
            ASSERT_TRUE(o.material >= 0 && o.material < int(world.layouts.size()));
            const TileLayout& layout = world.layouts[std::size_t(o.material)];
            ASSERT_TRUE(layout.contains(o.tile));
            const std::size_t i = layout.index(o.tile);
            const auto key = std::make_pair(o.material, i);
            int& slot = shadow[std::size_t(o.material)][i];
            if (o.kind == Kind::Add) {
                ++adds;
                EXPECT_LT(slot, 0) << "added while resident";
                EXPECT_TRUE(o.slot >= 0 && o.slot < capacity);
                for (const auto& v : shadow)
                    for (int x : v) EXPECT_NE(x, o.slot) << "slot still in use";
                EXPECT_EQ(removedNow.count(key), 0u) << "re-added in the step that removed it";
                EXPECT_TRUE(available(o.material, o.tile)) << "data not available";
                ASSERT_EQ(o.reason, Reason::Refine);
                ASSERT_GT(o.tile.level, 0);
                EXPECT_TRUE(residentIn(o.material, TileLayout::parent(o.tile)))
                    << "add without a resident parent";
                EXPECT_FALSE(anyBelow(o.material, o.tile)) << "a resident tile below a missing one";
                slot = o.slot;
                addedNow.insert(key);
            } else {
                EXPECT_EQ(slot, o.slot) << "removes a tile that is not in that slot";
                ASSERT_EQ(o.reason, Reason::Evicted);
                EXPECT_EQ(addedNow.count(key), 0u) << "dropped in the step that added it";
                EXPECT_FALSE(anyBelow(o.material, o.tile)) << "victim is not a leaf";
                EXPECT_GT(o.tile.level, 0);
                EXPECT_EQ(used(), capacity) << "drops with free slots";
                slot = -1;
                removedNow.insert(key);
            }
        }
        EXPECT_LE(adds, maxAdds) << "over the upload budget";
    }

    /** Every drop pays for the add right after it: c < P of that add (c* < P*), and it is not
     *  that add's parent. */
    void checkEvictionCosts(const std::vector<TileOperation>& ops) const {
        for (std::size_t k = 0; k < ops.size(); ++k) {
            if (ops[k].kind != Kind::Remove) continue;
            SCOPED_TRACE("drop at operation " + std::to_string(k));
            ASSERT_LT(k + 1, ops.size()) << "a drop without the add it makes room for";
            const TileOperation& add = ops[k + 1];
            EXPECT_EQ(add.kind, Kind::Add);
            EXPECT_LT(priority(ops[k].material, ops[k].tile), priority(add.material, add.tile))
                << "c* >= P*";
            EXPECT_FALSE(add.material == ops[k].material &&
                         TileLayout::parent(add.tile) == ops[k].tile)
                << "dropped the parent of the tile it makes room for";
            ++k;
        }
    }

    /** When a step ends under budget, no allowed operation was left that lowers the error: no
     *  free slot with an available candidate, and, when full, no drop cheaper than the best
     *  candidate that the rules allow (mirrors the rules, from the queries only). */
    void checkStoppedAtOptimum(const std::vector<TileOperation>& ops,
                               const std::set<std::pair<int, std::size_t>>& removedNow,
                               const std::set<std::pair<int, std::size_t>>& addedNow) const {
        int adds = 0;
        for (const TileOperation& o : ops) adds += o.kind == Kind::Add;
        if (adds >= maxAdds) return;
        const TileScheduler& s = world.scheduler;
        double bestP = 0;
        int bestM = -1;
        TileId best;
        for (int m = 0; m < int(world.layouts.size()); ++m) {
            const TileLayout& layout = world.layouts[std::size_t(m)];
            for (std::size_t i = 0; i < layout.tileCount(); ++i) {
                const TileId t = layout.tileAt(i);
                if (t.level == 0 || s.resident(m, t) || !s.resident(m, TileLayout::parent(t)) ||
                    removedNow.count({m, i}) || !available(m, t))
                    continue;
                const double p = priority(m, t);
                if (p > bestP) {
                    bestP = p;
                    bestM = m;
                    best = t;
                }
            }
        }
        if (bestM < 0) return;
        ASSERT_EQ(s.used(), s.capacity()) << "stopped with a free slot and a candidate";
        const TileId bestParent = TileLayout::parent(best);
        for (int m = 0; m < int(world.layouts.size()); ++m) {
            const TileLayout& layout = world.layouts[std::size_t(m)];
            for (std::size_t i = 0; i < layout.tileCount(); ++i) {
                const TileId t = layout.tileAt(i);
                const bool droppable = t.level > 0 && s.resident(m, t) &&
                                       !hasResidentDescendant(s, m, t) && !addedNow.count({m, i});
                if (droppable && !(m == bestM && t == bestParent)) {
                    EXPECT_GE(priority(m, t), bestP)
                        << "a cheaper drop was left: m" << m << " " << i;
                }
            }
        }
    }
};

std::vector<std::vector<int>> residency(const World& w) {
    std::vector<std::vector<int>> out;
    for (int m = 0; m < int(w.layouts.size()); ++m) {
        const TileLayout& layout = w.layouts[std::size_t(m)];
        std::vector<int> slots(layout.tileCount());
        for (std::size_t i = 0; i < slots.size(); ++i)
            slots[i] = w.scheduler.slotOf(m, layout.tileAt(i));
        out.push_back(slots);
    }
    return out;
}

std::vector<Feedback> randomFeedback(const World& w, std::mt19937& rng, int records) {
    std::vector<Feedback> out;
    for (int r = 0; r < records; ++r) {
        const int m = int(rng() % w.layouts.size());
        const TileLayout& layout = w.layouts[std::size_t(m)];
        const int L = layout.finestLevel();
        // Mostly real levels, sometimes beyond either end, rarely out of range tiles.
        const int level = int(rng() % std::uint32_t(L + 3)) - 1;
        const int clamped = std::clamp(level, 0, L);
        int x = int(rng() % std::uint32_t(layout.tilesX(clamped)));
        int y = int(rng() % std::uint32_t(layout.tilesY(clamped)));
        if (level > L) {
            x = (x << (level - L)) + int(rng() % 2);
            y = (y << (level - L)) + int(rng() % 2);
        }
        if (rng() % 20 == 0) x += layout.tilesX(clamped) << 1;
        out.push_back({m, level, x, y, std::uint32_t(1 + rng() % 50)});
    }
    if (rng() % 10 == 0) out.push_back({int(w.layouts.size()) + 2, 0, 0, 0, 5});  // no material
    return out;
}

TileVotes votesOf(const World& w, const std::vector<Feedback>& feedback) {
    TileVotes v = w.scheduler.makeVotes();
    for (const Feedback& f : feedback) v.add(f.material, f.level, f.x, f.y, f.count);
    return v;
}

/** The approximate error E the scheduler lowers: w v summed over the tiles that are not
 *  resident. */
double approximateError(const World& w, const std::vector<Feedback>& feedback) {
    double e = 0;
    for (int m = 0; m < int(w.layouts.size()); ++m) {
        const TileLayout& layout = w.layouts[std::size_t(m)];
        for (std::size_t i = 0; i < layout.tileCount(); ++i) {
            const TileId t = layout.tileAt(i);
            if (w.scheduler.resident(m, t)) continue;
            e += double(w.weights[std::size_t(m)][i]) * double(bruteVotes(feedback, layout, m, t));
        }
    }
    return e;
}

}  // namespace

// ---- refusals ----------------------------------------------------------------------------------

TEST(TileScheduler, RefusesWhatCannotWork) {
    EXPECT_EQ(messageOf([] { TileScheduler s(0); }),
              "tile scheduler: the cache needs at least one slot, got 0");

    const TileLayout three(32, 8, 3, 8, 0);  // 7 tiles per group, 21 in all
    const std::vector<float> ok(three.tileCount(), 1.f);
    {
        TileScheduler s(2);
        EXPECT_EQ(messageOf([&] { s.addMaterial(three, ok, ok); }),
                  "tile scheduler: material 0 needs 3 level-0 tiles (one per group) but only 2 of "
                  "2 cache slots are free");
        EXPECT_EQ(s.used(), 0);
        EXPECT_EQ(s.materialCount(), 0);
    }
    {
        TileScheduler s(4);
        EXPECT_EQ(s.addMaterial(three, ok, ok), 0);
        const TileLayout two(32, 8, 2, 8, 0);
        const std::vector<float> ok2(two.tileCount(), 1.f);
        EXPECT_EQ(messageOf([&] { s.addMaterial(two, ok2, ok2); }),
                  "tile scheduler: material 1 needs 2 level-0 tiles (one per group) but only 1 of "
                  "4 cache slots are free");
        EXPECT_EQ(s.used(), 3);
    }
    TileScheduler s(100);
    std::vector<float> shortWeights(20, 1.f);
    EXPECT_EQ(messageOf([&] { s.addMaterial(three, shortWeights, ok); }),
              "tile scheduler: material 0 has 21 tiles but 20 weights");
    EXPECT_EQ(messageOf([&] { s.addMaterial(three, ok, std::vector<float>(22, 1.f)); }),
              "tile scheduler: material 0 has 21 tiles but 22 norms");
    std::vector<float> negative = ok;
    negative[2] = -1.f;
    EXPECT_EQ(messageOf([&] { s.addMaterial(three, negative, ok); }),
              "tile scheduler: material 0: weight 2 is -1.000000 (weights must be finite and >= "
              "0)");
    EXPECT_EQ(s.used(), 0);

    s.addMaterial(three, ok, ok);
    EXPECT_EQ(messageOf([&] { s.step(s.makeVotes(), allAvailable, -1); }),
              "tile scheduler: the add budget must be >= 0, got -1");
    TileVotes tooMany = s.makeVotes();
    tooMany.addMaterial(three);
    EXPECT_EQ(messageOf([&] { s.step(tooMany, allAvailable, 4); }),
              "tile scheduler: the votes are for 2 materials, the scheduler has 1");
    TileVotes otherGrid;
    otherGrid.addMaterial(TileLayout(64, 8, 1, 8, 0));
    EXPECT_EQ(messageOf([&] { s.step(otherGrid, allAvailable, 4); }),
              "tile scheduler: the votes of material 0 are for 64x8 texels in 8-texel tiles, the "
              "material has 32x8 texels in 8-texel tiles");
    EXPECT_EQ(messageOf([&] { s.lookup(0, 3, 0, 0); }),
              "tile scheduler: material 0 has no group 3 finest tile (0, 0); it has 3 groups of "
              "4x1 finest tiles");
    EXPECT_EQ(messageOf([&] { s.resident(1, R); }), "tile scheduler: no material 1 (there are 1)");
}

// ---- hand-worked steps
// ---------------------------------------------------------------------------

TEST(TileScheduler, VotesAccumulateIntoAncestors) {
    TileScheduler s(4);
    s.addMaterial(handLayout(), handWeights(), std::vector<float>(7, 1.f));
    TileVotes v = s.makeVotes();
    v.add(0, 2, 1, 0, 3);   // a1
    v.add(0, 1, 1, 0, 4);   // B
    v.add(0, 3, 5, 1, 2);   // a level above the finest: tile (5,1)/2 = (2,0) = b0
    v.add(0, -1, 0, 0, 1);  // below level 0: the root
    v.add(0, -1, 1, 0, 9);  // ignored: only (0, 0) exists there
    v.add(0, 2, 4, 0, 9);   // ignored: outside
    v.add(1, 0, 0, 0, 9);   // ignored: no material 1
    EXPECT_EQ(v.votes(0, a1), 3u);
    EXPECT_EQ(v.votes(0, a0), 0u);
    EXPECT_EQ(v.votes(0, A), 3u);
    EXPECT_EQ(v.votes(0, b0), 2u);
    EXPECT_EQ(v.votes(0, B), 6u);
    EXPECT_EQ(v.votes(0, R), 10u);
    EXPECT_EQ(v.votes(0, TileId{5, 2, 1, 0}), 3u);  // the group does not matter
    v.clear();
    EXPECT_EQ(v.votes(0, R), 0u);
}

TEST(TileScheduler, HandWorkedAddsDropsAndLut) {
    TileScheduler s(4);
    std::vector<float> norms = {1, 2, 3, 4, 5, 6, 7};
    ASSERT_EQ(s.addMaterial(handLayout(), handWeights(), norms), 0);
    // addMaterial: the root takes slot 0; free slots are handed out lowest first, and a freed
    // slot is the next one handed out (a stack).
    EXPECT_EQ(s.slotOf(0, R), 0);
    EXPECT_EQ(s.used(), 1);
    EXPECT_EQ(s.lookup(0, 0, 2, 0), (LutEntry{0, 0, -1}));
    EXPECT_TRUE(s.lutDirty(0));
    s.clearLutDirty(0);

    // Step 1, votes a0 10, a1 10: v(A) = 20, v(B) = 0. Candidates: A with P = 5 * 20 = 100
    // (B has P = 0). Add A -> slot 1; its children become candidates a0 (3 * 10 = 30) and a1
    // (2 * 10 = 20). Add a0 -> 2, add a1 -> 3. A stays: its children need it resident, and
    // the shader blends it in where a fragment's footprint is larger than a texel of a0, a1.
    TileVotes v1 = handVotes(s, 10, 10, 0, 0);
    EXPECT_EQ(describe(s.step(v1, allAvailable, 8)),
              (std::vector<std::string>{add(A, 1), add(a0, 2), add(a1, 3)}));
    EXPECT_TRUE(s.lutDirty(0));
    EXPECT_EQ(s.used(), 4);
    EXPECT_TRUE(s.resident(0, A));
    // LUT: the deepest resident tile and its parent's slot.
    EXPECT_EQ(s.lookup(0, 0, 0, 0), (LutEntry{2, 2, 1}));
    EXPECT_EQ(s.lookup(0, 0, 1, 0), (LutEntry{2, 3, 1}));
    EXPECT_EQ(s.lookup(0, 0, 2, 0), (LutEntry{0, 0, -1}));
    EXPECT_EQ(s.lookup(0, 0, 3, 0), (LutEntry{0, 0, -1}));
    EXPECT_TRUE(s.step(v1, allAvailable, 8).empty());  // nothing with P > 0 left

    // Step 2, votes a0 1, a1 1, b0 20, b1 20: P(B) = 4 * 40 = 160, then b0 120, b1 20. Full.
    // Drops: the leaves a0 (c = 3) and a1 (c = 2); A is not a leaf, R is level 0. Drop a1 (slot
    // 3) for B; drop a0 (slot 2) for b0 (120). A is now a leaf, c = 5 * 2 = 10 < P(b1) = 20:
    // drop A (slot 1) for b1. No candidate is left (a0 and a1 lost their parent).
    TileVotes v2 = handVotes(s, 1, 1, 20, 20);
    EXPECT_EQ(describe(s.step(v2, allAvailable, 8)),
              (std::vector<std::string>{evicted(a1, 3), add(B, 3), evicted(a0, 2), add(b0, 2),
                                        evicted(A, 1), add(b1, 1)}));
    EXPECT_EQ(s.used(), 4);
    EXPECT_TRUE(s.resident(0, R));
    EXPECT_EQ(s.lookup(0, 0, 0, 0), (LutEntry{0, 0, -1}));
    EXPECT_EQ(s.lookup(0, 0, 1, 0), (LutEntry{0, 0, -1}));
    EXPECT_EQ(s.lookup(0, 0, 2, 0), (LutEntry{2, 2, 3}));
    EXPECT_EQ(s.lookup(0, 0, 3, 0), (LutEntry{2, 1, 3}));

    // Step 3: A (P 10) is a candidate again (removed only in the previous step). Full; the
    // cheapest drop, b1, costs 20 >= 10: stop.
    EXPECT_TRUE(s.step(v2, allAvailable, 8).empty());

    // wanted: A is the only candidate; group priority = sum of v * norm over resident tiles:
    // R 42 * 1 + B 40 * 3 + b0 20 * 6 + b1 20 * 7 = 422.
    EXPECT_EQ(s.wanted(v2, 5), (std::vector<std::pair<int, TileId>>{{0, A}}));
    EXPECT_DOUBLE_EQ(s.groupPriority(0, 0, v2), 422.0);
    EXPECT_DOUBLE_EQ(s.priority(0, b0, v2), 120.0);

    // Step 4, votes move to a1 (100) and away from b: P(A) = 5 * 101 = 505. Drops b0 and b1
    // cost 0 (b0 first: lower index): b0 (slot 2) for A, b1 (slot 1) for a1 (200); B is then a
    // leaf of cost 0 < P(a0) = 3: B (slot 3) for a0.
    s.clearLutDirty(0);
    TileVotes v4 = handVotes(s, 1, 100, 0, 0);
    EXPECT_EQ(describe(s.step(v4, allAvailable, 8)),
              (std::vector<std::string>{evicted(b0, 2), add(A, 2), evicted(b1, 1), add(a1, 1),
                                        evicted(B, 3), add(a0, 3)}));
    EXPECT_TRUE(s.lutDirty(0));
    EXPECT_TRUE(s.step(v4, allAvailable, 8).empty());
    EXPECT_EQ(s.lookup(0, 0, 0, 0), (LutEntry{2, 3, 2}));
    EXPECT_EQ(s.lookup(0, 0, 1, 0), (LutEntry{2, 1, 2}));
    EXPECT_EQ(s.lookup(0, 0, 3, 0), (LutEntry{0, 0, -1}));
}

TEST(TileScheduler, HandWorkedDropsAndRefusals) {
    // Capacity 3, votes a0 10, a1 10: add A -> 1, a0 -> 2 (P 30 before a1's 20); full, and no
    // drop exists (a0 was added in this step, A is not a leaf, R is level 0).
    TileScheduler s(3);
    s.addMaterial(handLayout(), handWeights(), std::vector<float>(7, 1.f));
    TileVotes v1 = handVotes(s, 10, 10, 0, 0);
    EXPECT_EQ(describe(s.step(v1, allAvailable, 8)),
              (std::vector<std::string>{add(A, 1), add(a0, 2)}));
    // Next step: the drop of a0 would cost 30 >= P(a1) = 20: nothing.
    EXPECT_TRUE(s.step(v1, allAvailable, 8).empty());
    EXPECT_EQ(s.wanted(v1, 5), (std::vector<std::pair<int, TileId>>{{0, a1}}));

    // Votes a0 10, a1 10, b0 20: P(B) = 4 * 20 = 80 is the best add; the drop of a0 costs
    // 30 < 80: a0 leaves (slot 2), B takes it. b0 (6 * 20 = 120) is next; A, a leaf now,
    // costs 5 * 20 = 100 < 120: A leaves (slot 1), b0 takes it. a1 (20) has no parent left.
    TileVotes v2 = handVotes(s, 10, 10, 20, 0);
    EXPECT_EQ(describe(s.step(v2, allAvailable, 8)),
              (std::vector<std::string>{evicted(a0, 2), add(B, 2), evicted(A, 1), add(b0, 1)}));

    // A tie is no gain: votes a0 10, a1 15 give P(a0) = 30 = P(a1) (a0 first: lower index);
    // then the drop of a0 would cost exactly P(a1) = 30, and c* < P* does not hold.
    TileScheduler tie(3);
    tie.addMaterial(handLayout(), handWeights(), std::vector<float>(7, 1.f));
    TileVotes vt = handVotes(tie, 10, 15, 0, 0);
    EXPECT_EQ(describe(tie.step(vt, allAvailable, 8)),
              (std::vector<std::string>{add(A, 1), add(a0, 2)}));
    EXPECT_TRUE(tie.step(vt, allAvailable, 8).empty());

    // The budget counts adds (a drop costs no upload), and an unavailable tile is not added.
    // Fresh scheduler in the state of HandWorkedAddsDropsAndLut after step 1 (A, a0, a1).
    TileScheduler t(4);
    t.addMaterial(handLayout(), handWeights(), std::vector<float>(7, 1.f));
    t.step(handVotes(t, 10, 10, 0, 0), allAvailable, 8);
    TileVotes v3 = handVotes(t, 1, 1, 20, 20);
    EXPECT_EQ(describe(t.step(v3, allAvailable, 1)),
              (std::vector<std::string>{evicted(a1, 3), add(B, 3)}));
    // b0 (120) not available: b1 (20) for a0 (3). Then A is a leaf (10), and a1 (2), whose
    // parent it is, is all that is left to add: stop.
    const auto noB0 = [](int, const TileId& tile) { return tile != b0; };
    EXPECT_EQ(describe(t.step(v3, noB0, 8)),
              (std::vector<std::string>{evicted(a0, 2), add(b1, 2)}));
    EXPECT_TRUE(t.step(v3, noB0, 8).empty());
    EXPECT_EQ(describe(t.step(v3, allAvailable, 8)),
              (std::vector<std::string>{evicted(A, 1), add(b0, 1)}));
}

TEST(TileScheduler, NoEvictionOfATileAddedInTheSameStep) {
    // 32 x 32 texels in 8-texel tiles: R, 2 x 2 tiles of level 1, 4 x 4 of level 2. Weights:
    // Q00 = (1,0,0) 10, Q10 = (1,1,0) 5, q = (2,2,0) (inside Q10) 30, the rest 1. Votes 10 at
    // (2,0,0) (inside Q00) and 10 at q: P(Q00) = 100, P(Q10) = 50, P(q) = 300. Capacity 3.
    const TileLayout layout(32, 32, 1, 8, 0);
    std::vector<float> w(layout.tileCount(), 1.f);
    const TileId q00{0, 1, 0, 0}, q10{0, 1, 1, 0}, q{0, 2, 2, 0};
    w[layout.index(q00)] = 10;
    w[layout.index(q10)] = 5;
    w[layout.index(q)] = 30;
    TileScheduler s(3);
    s.addMaterial(layout, w, std::vector<float>(layout.tileCount(), 1.f));
    TileVotes v = s.makeVotes();
    v.add(0, 2, 0, 0, 10);
    v.add(0, 2, 2, 0, 10);
    // Q00 -> 1, Q10 -> 2, full. q (300) would pay for dropping Q00 (100), but Q00 came in this
    // very step (its upload would be wasted), and dropping Q10 would orphan q: stop.
    EXPECT_EQ(describe(s.step(v, allAvailable, 8)),
              (std::vector<std::string>{add(q00, 1), add(q10, 2)}));
    // Next step Q00 is an old tile: drop it (100 < 300) and add q.
    EXPECT_EQ(describe(s.step(v, allAvailable, 8)),
              (std::vector<std::string>{evicted(q00, 1), add(q, 1)}));
    // Q00 (100) wants back in, but the only eviction left, dropping q, costs 300: nothing.
    EXPECT_TRUE(s.step(v, allAvailable, 8).empty());
}

// ---- randomized runs ---------------------------------------------------------------------------

TEST(TileScheduler, InvariantsHoldAfterEveryStep) {
    // What the runs went through, so that the checks above are not vacuous.
    int refines = 0, drops = 0, fullStops = 0;
    for (std::uint32_t seed = 1; seed <= 12; ++seed) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        std::mt19937 rng(seed);
        const int capacity = 8 + int(rng() % 40);
        World w(capacity);
        w.addMaterial(TileLayout(400, 300, 2, 64, 4), rng, false);  // 52 tiles per group
        w.addMaterial(TileLayout(1, 1, 1, 8, 0), rng, false);       // one tile
        w.addMaterial(TileLayout(40, 24, 1, 8, 0), rng, false);     // 5 x 3 finest tiles
        w.addMaterial(TileLayout(128, 128, 3, 32, 0), rng, false);  // 21 tiles per group
        checkState(w, "after addMaterial");
        std::vector<Feedback> feedback = randomFeedback(w, rng, 30);
        for (int step = 0; step < 120; ++step) {
            SCOPED_TRACE("step " + std::to_string(step));
            if (rng() % 4 == 0) feedback = randomFeedback(w, rng, 5 + int(rng() % 60));
            const TileVotes votes = votesOf(w, feedback);
            for (int m = 0; m < int(w.layouts.size()); ++m)
                for (std::size_t i = 0; i < w.layouts[std::size_t(m)].tilesPerGroup(); ++i) {
                    const TileId t = w.layouts[std::size_t(m)].tileAt(i);
                    ASSERT_EQ(votes.votes(m, t),
                              bruteVotes(feedback, w.layouts[std::size_t(m)], m, t));
                }
            const bool everything = rng() % 3 == 0;
            const std::uint64_t availSeed = seed;
            const World* world = &w;
            StepCheck check{w, feedback,
                            [availSeed, step, everything, world](int m, const TileId& t) {
                                const std::size_t i = world->layouts[std::size_t(m)].index(t);
                                return everything || pseudoAvailable(availSeed, step, m, i);
                            },
                            1 + int(rng() % 6)};
            for (int m = 0; m < int(w.layouts.size()); ++m) w.scheduler.clearLutDirty(m);
            const std::vector<std::vector<int>> before = residency(w);
            const std::vector<TileOperation> ops =
                w.scheduler.step(votes, check.available, check.maxAdds);
            std::set<std::pair<int, std::size_t>> removedNow;
            check.replay(before, ops, removedNow);
            check.checkEvictionCosts(ops);
            std::set<std::pair<int, std::size_t>> addedNow;
            std::set<int> touched;
            for (const TileOperation& o : ops) {
                touched.insert(o.material);
                if (o.kind == Kind::Add)
                    addedNow.insert({o.material, w.layouts[std::size_t(o.material)].index(o.tile)});
            }
            for (int m = 0; m < int(w.layouts.size()); ++m)
                EXPECT_EQ(w.scheduler.lutDirty(m), touched.count(m) > 0) << "material " << m;
            // The replayed residency equals the scheduler's.
            std::vector<std::vector<int>> replayed = before;
            for (const TileOperation& o : ops)
                replayed[std::size_t(o.material)]
                        [w.layouts[std::size_t(o.material)].index(o.tile)] =
                            o.kind == Kind::Add ? o.slot : -1;
            EXPECT_EQ(replayed, residency(w));
            checkState(w, "after step");
            check.checkStoppedAtOptimum(ops, removedNow, addedNow);
            if (HasFailure()) return;
            for (const TileOperation& o : ops) {
                refines += o.reason == Reason::Refine;
                drops += o.reason == Reason::Evicted;
            }
            fullStops += int(addedNow.size()) < check.maxAdds && w.scheduler.used() == capacity &&
                         !w.scheduler.wanted(votes, 1).empty();
        }
    }
    std::cout << "[ runs     ] " << refines << " adds, " << drops << " drops, " << fullStops
              << " steps stopped full under budget\n";
    EXPECT_GT(refines, 100);
    EXPECT_GT(drops, 5);
    EXPECT_GT(fullStops, 5);
}

TEST(TileScheduler, ConvergesAndStaysConverged) {
    for (std::uint32_t seed = 11; seed <= 14; ++seed) {
        SCOPED_TRACE("seed " + std::to_string(seed));
        std::mt19937 rng(seed);
        World w(10 + int(rng() % 30));
        w.addMaterial(TileLayout(400, 300, 2, 64, 4), rng, false);
        w.addMaterial(TileLayout(40, 24, 1, 8, 0), rng, false);
        w.addMaterial(TileLayout(128, 128, 3, 32, 0), rng, false);
        // Votes that change now and then, then stay fixed: the run must settle each time.
        for (int round = 0; round < 3; ++round) {
            const std::vector<Feedback> feedback = randomFeedback(w, rng, 40);
            const TileVotes votes = votesOf(w, feedback);
            double error = approximateError(w, feedback);
            const int bound = int(w.totalTiles());
            int steps = 0;
            for (;; ++steps) {
                ASSERT_LE(steps, bound) << "no convergence";
                const std::vector<TileOperation> ops = w.scheduler.step(votes, allAvailable, 3);
                if (ops.empty()) break;
                const double now = approximateError(w, feedback);
                EXPECT_LT(now, error) << "a step with operations did not lower the error";
                error = now;
            }
            for (int k = 0; k < 3; ++k)
                EXPECT_TRUE(w.scheduler.step(votes, allAvailable, 3).empty());
            checkState(w, "converged");
        }
    }
}

TEST(TileScheduler, BigEnoughCacheShowsEveryVotedFinestTile) {
    std::mt19937 rng(7);
    const std::vector<TileLayout> layouts = {
        TileLayout(400, 300, 2, 64, 4), TileLayout(1, 1, 1, 8, 0), TileLayout(40, 24, 2, 8, 0)};
    std::size_t total = 0;
    for (const TileLayout& l : layouts) total += l.tileCount();
    World w{int(total)};
    for (const TileLayout& l : layouts) w.addMaterial(l, rng, true);
    std::vector<Feedback> feedback;
    for (int m = 0; m < int(layouts.size()); ++m) {
        const TileLayout& l = layouts[std::size_t(m)];
        const int L = l.finestLevel();
        for (int y = 0; y < l.tilesY(L); ++y)
            for (int x = 0; x < l.tilesX(L); ++x)
                if (rng() % 2) feedback.push_back({m, L, x, y, std::uint32_t(1 + rng() % 9)});
    }
    const TileVotes votes = votesOf(w, feedback);
    int steps = 0;
    while (!w.scheduler.step(votes, allAvailable, 5).empty()) ASSERT_LE(++steps, int(total));
    checkState(w, "converged");
    int shown = 0;
    for (const Feedback& f : feedback)
        for (int g = 0; g < layouts[std::size_t(f.material)].groups(); ++g) {
            const TileId t{g, f.level, f.x, f.y};
            EXPECT_TRUE(w.scheduler.resident(f.material, t))
                << "material " << f.material << " group " << g << " tile " << f.x << "," << f.y;
            EXPECT_EQ(w.scheduler.lookup(f.material, g, f.x, f.y).level, f.level);
            ++shown;
        }
    EXPECT_GT(shown, 10);
}

TEST(TileScheduler, HundredMaterialScene) {
    // Scene 1 of Schwartz et al. 2013: 100 materials of 512^2 texels (8 groups of 85 tiles: 68,000
    // tiles), a 3136-slot cache, 32 uploads per step, fresh votes every step.
    std::mt19937 rng(3);
    TileScheduler s(3136);
    const TileLayout layout(512, 512, 8);
    std::uniform_real_distribution<float> uni(0.f, 1.f);
    for (int m = 0; m < 100; ++m) {
        std::vector<float> w(layout.tileCount()), n(layout.tileCount());
        for (std::size_t i = 0; i < w.size(); ++i) {
            w[i] = uni(rng);
            n[i] = uni(rng);
        }
        s.addMaterial(layout, w, n);
    }
    EXPECT_EQ(s.used(), 800);
    // A quarter-resolution feedback buffer of 320 x 180 pixels over 30 of the materials (which
    // ones moves on every 10 steps), mostly at levels 2 and 3.
    const auto feedback = [&](int k) {
        TileVotes votes = s.makeVotes();
        for (int p = 0; p < 320 * 180 / 64; ++p)
            votes.add(int(rng() % 30) + (k / 10) * 10, 2 + int(rng() % 2), int(rng() % 8),
                      int(rng() % 8), 64);
        return votes;
    };
    s.step(feedback(0), allAvailable, 4000);  // fill the cache first
    EXPECT_EQ(s.used(), s.capacity());        // the scene wants more than the cache holds
    double worst = 0, total = 0;
    const int steps = 30;
    std::size_t operations = 0, evictions = 0;
    for (int k = 0; k < steps; ++k) {
        const TileVotes votes = feedback(k);
        const auto t0 = std::chrono::steady_clock::now();
        const std::vector<TileOperation> ops = s.step(votes, allAvailable, 32);
        const double ms =
            std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - t0)
                .count();
        worst = std::max(worst, ms);
        total += ms;
        operations += ops.size();
        int adds = 0;
        for (const TileOperation& o : ops) {
            adds += o.kind == Kind::Add;
            evictions += o.reason == Reason::Evicted;
        }
        EXPECT_LE(adds, 32);
        EXPECT_LE(s.used(), s.capacity());
    }
    EXPECT_GT(evictions, 0u);
    std::cout << "[ scale    ] 68,000 tiles, " << steps << " steps: mean " << total / steps
              << " ms, worst " << worst << " ms per step, " << operations << " operations, "
              << evictions << " evictions\n";
}

}  // namespace OSGBTF_TEST_FILE
