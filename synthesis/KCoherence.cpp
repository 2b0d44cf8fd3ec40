#include "synthesis/KCoherence.h"

#include <algorithm>
#include <cmath>
#include <limits>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>
#include <Eigen/Core>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "core/Progress.h"

namespace osgBTF {

namespace {

using RowMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

// Fixed texel chunks for every parallel step whose floating-point result could depend on how the
// work is split (GEMM blocking, sums): the same chunk always holds the same texels, so results
// are bitwise the same whatever the thread count.
constexpr std::size_t kChunk = 256;
constexpr std::uint64_t kProjectionSeed = 0x5eed0002;
constexpr std::uint64_t kKmeansSeed = 0x7e7705;
// Similar texels kept per texel at least (jump targets), and the best of them a jump picks from.
constexpr int kJumpTargets = 4;
constexpr std::size_t kJumpChoices = 3;

std::uint64_t mix(std::uint64_t z) {
    z = (z ^ (z >> 30)) * 0xBF58476D1CE4E5B9ull;
    z = (z ^ (z >> 27)) * 0x94D049BB133111EBull;
    return z ^ (z >> 31);
}

/** splitmix64: the same sequence on every platform (std distributions are not). */
class Random {
public:
    explicit Random(std::uint64_t seed) : _state(mix(seed)) {}
    std::uint64_t next() {
        _state += 0x9E3779B97F4A7C15ull;
        return mix(_state);
    }
    int below(int n) { return int(next() % std::uint64_t(n)); }

private:
    std::uint64_t _state;
};

template <typename Body>
void forEachChunk(std::size_t count, const Body& body) {
    const std::size_t chunks = (count + kChunk - 1) / kChunk;
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, chunks, 1),
        [&](const tbb::blocked_range<std::size_t>& r) {
            for (std::size_t c = r.begin(); c != r.end(); ++c)
                body(c * kChunk, std::min(count, (c + 1) * kChunk));
        },
        tbb::simple_partitioner());
}

std::vector<std::size_t> selectImages(std::size_t count, std::size_t wanted) {
    std::vector<std::size_t> images;
    if (wanted == 0 || wanted >= count) {
        images.resize(count);
        for (std::size_t i = 0; i < count; ++i) images[i] = i;
    } else {
        for (std::size_t i = 0; i < wanted; ++i) images.push_back(i * count / wanted);
    }
    return images;
}

/** texels x d vectors: the selected images' values, or their random projection when there are
 *  more than d of them. */
std::vector<float> appearanceVectors(const BtfSource& source,
                                     const std::vector<std::size_t>& images, int dimensions,
                                     int& outDimensions) {
    const std::size_t n = source.texelCount();
    const std::size_t values = 3 * images.size();
    const bool project = values > std::size_t(dimensions);
    const int d = project ? dimensions : int(values);
    outDimensions = d;
    checkMemory(std::uint64_t(n) * d * sizeof(float), "synthesis: appearance vectors");
    RowMatrix features = RowMatrix::Zero(Eigen::Index(n), d);

    const std::size_t block = std::min<std::size_t>(images.size(), 64);
    checkMemory(std::uint64_t(n) * 3 * block * sizeof(float) * 2, "synthesis: image block");
    std::vector<float> buffer(n * 3 * block);
    RowMatrix x(Eigen::Index(n), Eigen::Index(3 * block));
    // Achlioptas' dense projection: entries +-1/sqrt(d) keep every squared distance unbiased
    // (E ||R^T a||^2 = ||a||^2); each entry is a hash of (image, channel, component), so an image
    // contributes the same whatever the selection's blocking.
    const float scale = 1.0f / std::sqrt(float(d));
    RowMatrix projection(Eigen::Index(3 * block), d);
    Progress progress("synthesis: appearance vectors", images.size());
    for (std::size_t first = 0; first < images.size(); first += block) {
        const std::size_t count = std::min(block, images.size() - first);
        for (std::size_t j = 0; j < count;) {
            std::size_t run = 1;  // consecutive images are read in one call
            while (j + run < count && images[first + j + run] == images[first + j] + run) ++run;
            source.readImages(images[first + j], run, buffer.data() + j * n * 3);
            j += run;
        }
        forEachChunk(n, [&](std::size_t begin, std::size_t end) {
            for (std::size_t p = begin; p < end; ++p)
                for (std::size_t j = 0; j < count; ++j)
                    for (int c = 0; c < 3; ++c)
                        x(Eigen::Index(p), Eigen::Index(3 * j + c)) = buffer[(j * n + p) * 3 + c];
        });
        const Eigen::Index columns = Eigen::Index(3 * count);
        if (project) {
            for (std::size_t j = 0; j < count; ++j)
                for (int c = 0; c < 3; ++c)
                    for (int e = 0; e < d; ++e) {
                        const std::uint64_t key =
                            (std::uint64_t(images[first + j]) * 3 + c) * std::uint64_t(d) + e;
                        projection(Eigen::Index(3 * j + c), e) =
                            (mix(kProjectionSeed ^ mix(key)) & 1) ? scale : -scale;
                    }
            forEachChunk(n, [&](std::size_t begin, std::size_t end) {
                const Eigen::Index rows = Eigen::Index(end - begin);
                features.middleRows(Eigen::Index(begin), rows).noalias() +=
                    x.block(Eigen::Index(begin), 0, rows, columns) * projection.topRows(columns);
            });
        } else {
            features.middleCols(Eigen::Index(3 * first), columns) = x.leftCols(columns);
        }
        progress.advance(count);
    }
    progress.finish();
    return std::vector<float>(features.data(), features.data() + features.size());
}

/** The level below: 2x2 box averages (the vectors are linear in the values, so this equals the
 *  vectors of the box-filtered images, the paper's image pyramid). */
std::vector<float> halve(const std::vector<float>& features, int width, int height, int d) {
    const int w = width / 2, h = height / 2;
    std::vector<float> out(std::size_t(w) * h * d);
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int e = 0; e < d; ++e) {
                auto at = [&](int xx, int yy) {
                    return features[(std::size_t(yy) * width + xx) * d + e];
                };
                out[(std::size_t(y) * w + x) * d + e] =
                    0.25f * (at(2 * x, 2 * y) + at(2 * x + 1, 2 * y) + at(2 * x, 2 * y + 1) +
                             at(2 * x + 1, 2 * y + 1));
            }
    return out;
}

/** Lloyd's k-means from `textons` distinct random texels; the texels themselves when there are
 *  no more texels than textons (then texton distances are exact). Sets texton, textonCount and
 *  textonDistance. */
void clusterTextons(SynthesisLevel& level, int textons, int iterations, int levelIndex) {
    const std::size_t n = level.texels();
    const int d = level.dimensions;
    const int t = int(std::min<std::size_t>(std::size_t(textons), n));
    level.textonCount = t;
    level.texton.assign(n, 0);
    Eigen::Map<const RowMatrix> f(level.features.data(), Eigen::Index(n), d);
    RowMatrix centres(t, d);
    if (std::size_t(t) == n) {
        centres = f;
        for (std::size_t p = 0; p < n; ++p) level.texton[p] = std::int32_t(p);
    } else {
        std::vector<std::int32_t> order(n);
        for (std::size_t p = 0; p < n; ++p) order[p] = std::int32_t(p);
        Random random(kKmeansSeed + std::uint64_t(levelIndex));
        for (int i = 0; i < t; ++i) {  // partial Fisher-Yates: t distinct texels
            std::swap(order[i], order[i + random.below(int(n) - i)]);
            centres.row(i) = f.row(order[i]);
        }
        std::fill(level.texton.begin(), level.texton.end(), -1);
        Progress progress("synthesis: textons (level " + std::to_string(levelIndex) + ")",
                          std::size_t(iterations));
        for (int iteration = 0; iteration < iterations; ++iteration) {
            const Eigen::VectorXf norms = centres.rowwise().squaredNorm();
            std::vector<char> changedChunk((n + kChunk - 1) / kChunk, 0);
            forEachChunk(n, [&](std::size_t begin, std::size_t end) {
                const Eigen::Index rows = Eigen::Index(end - begin);
                const RowMatrix dots =
                    f.middleRows(Eigen::Index(begin), rows) * centres.transpose();
                for (Eigen::Index r = 0; r < rows; ++r) {
                    int best = 0;
                    float bestValue = std::numeric_limits<float>::infinity();
                    for (int c = 0; c < t; ++c) {
                        const float value = norms[c] - 2.0f * dots(r, c);
                        if (value < bestValue) bestValue = value, best = c;
                    }
                    std::int32_t& assigned = level.texton[begin + std::size_t(r)];
                    if (assigned != best) {
                        assigned = best;
                        changedChunk[begin / kChunk] = 1;
                    }
                }
            });
            progress.advance();
            if (std::find(changedChunk.begin(), changedChunk.end(), 1) == changedChunk.end()) break;
            Eigen::MatrixXd sums = Eigen::MatrixXd::Zero(t, d);
            std::vector<std::size_t> members(std::size_t(t), 0);
            for (std::size_t p = 0; p < n; ++p) {
                sums.row(level.texton[p]) += f.row(Eigen::Index(p)).cast<double>();
                ++members[std::size_t(level.texton[p])];
            }
            for (int c = 0; c < t; ++c)  // an empty cluster keeps its centre
                if (members[std::size_t(c)])
                    centres.row(c) = (sums.row(c) / double(members[std::size_t(c)])).cast<float>();
        }
        progress.finish();
    }
    // The paper's matrix of texton dot products M, stored as the distances it gives.
    checkMemory(std::uint64_t(t) * t * sizeof(float), "synthesis: texton matrix");
    const RowMatrix dots = centres * centres.transpose();
    level.textonDistance.resize(std::size_t(t) * t);
    for (int i = 0; i < t; ++i)
        for (int j = 0; j < t; ++j)
            level.textonDistance[std::size_t(i) * t + j] =
                std::max(0.0f, dots(i, i) - 2.0f * dots(i, j) + dots(j, j));
}

struct Offset {
    int dx, dy;
};

/** The (2r+1)^2 - 1 offsets of a neighbourhood, nearest first (the candidate of the nearest
 *  neighbour wins ties; early termination cuts more with the nearest terms first). */
std::vector<Offset> neighbourhoodOffsets(int r) {
    std::vector<Offset> offsets;
    for (int dy = -r; dy <= r; ++dy)
        for (int dx = -r; dx <= r; ++dx)
            if (dx || dy) offsets.push_back({dx, dy});
    std::stable_sort(offsets.begin(), offsets.end(), [](const Offset& a, const Offset& b) {
        return a.dx * a.dx + a.dy * a.dy < b.dx * b.dx + b.dy * b.dy;
    });
    return offsets;
}

std::int32_t wrappedTexel(const SynthesisLevel& level, std::int32_t texel, int dx, int dy) {
    const int x = (texel % level.width + dx + level.width) % level.width;
    const int y = (texel / level.width + dy + level.height) % level.height;
    return std::int32_t(y * level.width + x);
}

/** For each texel, the m texels with the smallest sum of texton distances over the whole wrapped
 *  neighbourhood (centre included), by brute force as the paper (fine up to ~128x128 samples). */
void findSimilar(SynthesisLevel& level, int m, int r, int levelIndex) {
    const std::size_t n = level.texels();
    m = int(std::min<std::size_t>(std::size_t(m), n - 1));
    level.similarCount = m;
    if (m <= 0) return;
    const int side = 2 * r + 1, terms = side * side;
    checkMemory(std::uint64_t(n) * terms * sizeof(std::int32_t) + std::uint64_t(n) * m * 4,
                "synthesis: neighbourhood table");
    std::vector<std::int32_t> table(n * terms);  // texton at each offset of each texel
    for (std::size_t p = 0; p < n; ++p)
        for (int i = 0; i < terms; ++i)
            table[p * terms + i] =
                level.texton[wrappedTexel(level, std::int32_t(p), i % side - r, i / side - r)];
    level.similar.assign(n * m, 0);
    Progress progress("synthesis: similar texels (level " + std::to_string(levelIndex) + ")", n);
    const int t = level.textonCount;
    forEachChunk(n, [&](std::size_t begin, std::size_t end) {
        std::vector<const float*> rows(terms);
        std::vector<float> bestDistance(m);
        std::vector<std::int32_t> best(m);
        for (std::size_t p = begin; p < end; ++p) {
            for (int i = 0; i < terms; ++i)
                rows[i] = level.textonDistance.data() + std::size_t(table[p * terms + i]) * t;
            std::fill(bestDistance.begin(), bestDistance.end(),
                      std::numeric_limits<float>::infinity());
            std::fill(best.begin(), best.end(), -1);
            for (std::size_t q = 0; q < n; ++q) {
                if (q == p) continue;
                const std::int32_t* other = table.data() + q * terms;
                const float bound = bestDistance[m - 1];
                float sum = 0;
                int i = 0;
                for (; i < terms && sum < bound; ++i) sum += rows[i][other[i]];
                if (i < terms || sum >= bound) continue;
                int j = m - 1;  // insertion into the sorted list; ties keep the lower index
                while (j > 0 && bestDistance[j - 1] > sum) {
                    bestDistance[j] = bestDistance[j - 1];
                    best[j] = best[j - 1];
                    --j;
                }
                bestDistance[j] = sum;
                best[j] = std::int32_t(q);
            }
            std::copy(best.begin(), best.end(), level.similar.begin() + p * m);
        }
        progress.advance(end - begin);
    });
    progress.finish();
}

int coarsestFactor(const SynthesisOptions& options) {
    return 1 << (options.levels - 1);
}

}  // namespace

void validateSynthesisOptions(const SynthesisOptions& o, int sampleWidth, int sampleHeight,
                              std::size_t imageCount) {
    auto require = [](bool ok, const std::string& message) {
        if (!ok) throw Error(message);
    };
    require(o.width > 0 && o.height > 0, "--size must be positive, got " + std::to_string(o.width) +
                                             "x" + std::to_string(o.height));
    require(o.k >= 1 && o.k <= 64, "--k must be in 1..64, got " + std::to_string(o.k));
    require(o.neighbourhood >= 1 && o.neighbourhood <= 8,
            "--neighbourhood must be in 1..8, got " + std::to_string(o.neighbourhood));
    require(o.levels >= 1 && o.levels <= 8,
            "--levels must be in 1..8, got " + std::to_string(o.levels));
    require(o.textons >= 1, "--textons must be positive, got " + std::to_string(o.textons));
    require(o.dimensions >= 1,
            "--dimensions must be positive, got " + std::to_string(o.dimensions));
    require(o.patch >= -1, "--patch must be 0 or more, got " + std::to_string(o.patch));
    require(o.images <= imageCount, "--images " + std::to_string(o.images) +
                                        ": the sample has only " + std::to_string(imageCount) +
                                        " images");
    const std::string size = std::to_string(sampleWidth) + "x" + std::to_string(sampleHeight);
    const int factor = coarsestFactor(o);
    require(sampleWidth % factor == 0 && sampleHeight % factor == 0,
            "--levels " + std::to_string(o.levels) + ": the sample's sides (" + size +
                ") must be multiples of " + std::to_string(factor));
    const int side = 2 * o.neighbourhood + 1;
    require(sampleWidth / factor >= side && sampleHeight / factor >= side,
            "--levels " + std::to_string(o.levels) + ": the coarsest level of the " + size +
                " sample is " + std::to_string(sampleWidth / factor) + "x" +
                std::to_string(sampleHeight / factor) + ", smaller than the " +
                std::to_string(side) + "x" + std::to_string(side) +
                " neighbourhood of --neighbourhood " + std::to_string(o.neighbourhood) +
                "; use fewer levels");
}

SampleAnalysis analyseSample(const BtfSource& source, const SynthesisOptions& options) {
    validateSynthesisOptions(options, source.width(), source.height(), source.imageCount());
    SampleAnalysis analysis;
    analysis.width = source.width();
    analysis.height = source.height();
    analysis.images = selectImages(source.imageCount(), options.images);
    analysis.valuesPerTexel = 3 * analysis.images.size();
    analysis.levels.resize(std::size_t(options.levels));
    SynthesisLevel& finest = analysis.levels.back();
    finest.width = source.width();
    finest.height = source.height();
    finest.features =
        appearanceVectors(source, analysis.images, options.dimensions, finest.dimensions);
    for (int l = options.levels - 2; l >= 0; --l) {
        const SynthesisLevel& finer = analysis.levels[std::size_t(l) + 1];
        SynthesisLevel& level = analysis.levels[std::size_t(l)];
        level.width = finer.width / 2;
        level.height = finer.height / 2;
        level.dimensions = finer.dimensions;
        level.features = halve(finer.features, finer.width, finer.height, finer.dimensions);
    }
    for (int l = 0; l < options.levels; ++l) {
        SynthesisLevel& level = analysis.levels[std::size_t(l)];
        clusterTextons(level, options.textons, options.kmeansIterations, l);
        findSimilar(level, std::max(options.k - 1, kJumpTargets), options.neighbourhood, l);
    }
    return analysis;
}

namespace {

/** One level of the output being synthesised: sample texel per output texel, -1 = not yet. */
struct OutputLevel {
    int width, height;
    std::vector<std::int32_t> source;
    std::vector<char> preset;  // assigned before the scanline pass, re-synthesised after it
};

class LevelSynthesizer {
public:
    LevelSynthesizer(const SynthesisLevel& level, const SynthesisOptions& options, Random& random)
        : _level(level),
          _k(options.k),
          _offsets(neighbourhoodOffsets(options.neighbourhood)),
          _random(random),
          _stamp(level.texels(), 0) {}

    std::int32_t synthesize(const OutputLevel& out, int x, int y) {
        gatherNeighbours(out, x, y);
        if (_known.empty()) return std::int32_t(_random.below(int(_level.texels())));
        nextGeneration();
        _candidates.clear();
        const int m = std::min(_k - 1, _level.similarCount);
        for (const Known& known : _known) {
            // The texel that continues this neighbour's source coherently (Ashikhmin, k = 1)...
            const std::int32_t c = continuation(known);
            addCandidate(c);
            // ...and the k-1 texels whose neighbourhoods are most like its own.
            for (int j = 0; j < m; ++j) addCandidate(similar(c, j));
        }
        std::int32_t best = _candidates.front();
        float bestDistance = std::numeric_limits<float>::infinity();
        for (const std::int32_t c : _candidates) {
            const float sum = distance(c, bestDistance);
            if (sum < bestDistance) bestDistance = sum, best = c;
        }
        return best;
    }

    /** A jump: the source for (x, y) among the texels similar to the neighbours' continuations
     *  that lie at least `minimum` texels (toroidal, per axis) from every continuation, chosen at
     *  random among the best kJumpChoices of them; -1 when there is none. */
    std::int32_t jump(const OutputLevel& out, int x, int y, int minimum) {
        gatherNeighbours(out, x, y);
        if (_known.empty()) return -1;
        nextGeneration();
        _continuations.clear();
        for (const Known& known : _known) _continuations.push_back(continuation(known));
        _scored.clear();
        for (const std::int32_t c : _continuations)
            for (int j = 0; j < _level.similarCount; ++j) {
                const std::int32_t candidate = similar(c, j);
                if (_stamp[std::size_t(candidate)] == _generation) continue;
                _stamp[std::size_t(candidate)] = _generation;
                bool far = true;
                for (const std::int32_t d : _continuations)
                    far = far && !near(candidate, d, minimum);
                if (far)
                    _scored.push_back(
                        {distance(candidate, std::numeric_limits<float>::infinity()), candidate});
            }
        if (_scored.empty()) return -1;
        std::sort(_scored.begin(), _scored.end());
        return _scored[std::size_t(
                           _random.below(int(std::min<std::size_t>(_scored.size(), kJumpChoices))))]
            .second;
    }

private:
    struct Known {
        Offset offset;
        std::int32_t source;
    };
    void gatherNeighbours(const OutputLevel& out, int x, int y) {
        _known.clear();
        for (const Offset& o : _offsets) {
            const int nx = x + o.dx, ny = y + o.dy;
            if (nx < 0 || ny < 0 || nx >= out.width || ny >= out.height) continue;
            const std::int32_t s = out.source[std::size_t(ny) * out.width + nx];
            if (s >= 0) _known.push_back({o, s});
        }
    }
    void nextGeneration() {
        if (++_generation == 0) {  // the stamps wrapped: start over
            std::fill(_stamp.begin(), _stamp.end(), 0);
            _generation = 1;
        }
    }
    std::int32_t continuation(const Known& known) const {
        return wrappedTexel(_level, known.source, -known.offset.dx, -known.offset.dy);
    }
    std::int32_t similar(std::int32_t texel, int j) const {
        return _level.similar[std::size_t(texel) * _level.similarCount + j];
    }
    /** Sum of texton distances over the known neighbours, stopped once it reaches `bound`. */
    float distance(std::int32_t c, float bound) const {
        float sum = 0;
        for (std::size_t i = 0; i < _known.size() && sum < bound; ++i) {
            const Known& known = _known[i];
            sum += _level.distance(wrappedTexel(_level, c, known.offset.dx, known.offset.dy),
                                   known.source);
        }
        return sum;
    }
    bool near(std::int32_t a, std::int32_t b, int minimum) const {
        auto axis = [](int u, int v, int size) {
            const int d = std::abs(u - v);
            return std::min(d, size - d);
        };
        const int w = _level.width, h = _level.height;
        return axis(a % w, b % w, w) < minimum && axis(a / w, b / w, h) < minimum;
    }
    void addCandidate(std::int32_t c) {
        if (_stamp[std::size_t(c)] == _generation) return;
        _stamp[std::size_t(c)] = _generation;
        _candidates.push_back(c);
    }

    const SynthesisLevel& _level;
    int _k;
    std::vector<Offset> _offsets;
    Random& _random;
    std::vector<std::uint32_t> _stamp;
    std::uint32_t _generation = 0;
    std::vector<Known> _known;
    std::vector<std::int32_t> _candidates, _continuations;
    std::vector<std::pair<float, std::int32_t>> _scored;
};

/** A block x block square from (x, y) on, continuing `source` coherently, over texels not yet
 *  synthesised: preset, so the pass goes around it and re-synthesises it afterwards. */
void presetBlock(OutputLevel& out, const SynthesisLevel& level, int x, int y, int block,
                 std::int32_t source) {
    for (int j = 0; j < block && y + j < out.height; ++j)
        for (int i = 0; i < block && x + i < out.width; ++i) {
            const std::size_t o = std::size_t(y + j) * out.width + x + i;
            if ((i || j) && (out.source[o] >= 0 || out.preset[o])) continue;
            out.source[o] = wrappedTexel(level, source, i, j);
            out.preset[o] = 1;
        }
}

/** One jump site per spacing x spacing cell of the output, at a random place in the cell. */
std::vector<char> jumpSites(int width, int height, int spacing, Random& random) {
    std::vector<char> sites(std::size_t(width) * height, 0);
    for (int cy = 0; cy < height; cy += spacing)
        for (int cx = 0; cx < width; cx += spacing) {
            const int x = cx + random.below(spacing), y = cy + random.below(spacing);
            if (x < width && y < height) sites[std::size_t(y) * width + x] = 1;
        }
    return sites;
}

}  // namespace

CoordinateMap synthesizeMap(const SampleAnalysis& analysis, const SynthesisOptions& options) {
    validateSynthesisOptions(options, analysis.width, analysis.height,
                             analysis.images.size() /* already selected */);
    if (int(analysis.levels.size()) != options.levels)
        throw Error("synthesis: the analysis has " + std::to_string(analysis.levels.size()) +
                    " levels, the options ask for " + std::to_string(options.levels));
    CoordinateMap map(options.width, options.height, analysis.width, analysis.height);
    Random random(options.seed);
    const int factor = coarsestFactor(options);
    std::size_t total = 0;
    for (int l = 0; l < options.levels; ++l) {
        const int shrink = factor >> l;
        total += std::size_t((options.width + shrink - 1) / shrink) *
                 std::size_t((options.height + shrink - 1) / shrink);
    }
    checkMemory(std::uint64_t(options.width) * options.height * 5 * 2, "synthesis: output levels");
    Progress progress("synthesis", total);
    OutputLevel previous{0, 0, {}, {}};
    for (int l = 0; l < options.levels; ++l) {
        const SynthesisLevel& level = analysis.levels[std::size_t(l)];
        const int shrink = factor >> l;
        OutputLevel out{
            (options.width + shrink - 1) / shrink, (options.height + shrink - 1) / shrink, {}, {}};
        out.source.assign(std::size_t(out.width) * out.height, -1);
        out.preset.assign(out.source.size(), 0);
        std::vector<char> sites;
        int block = 0, minimum = 0;
        if (l == 0) {
            const int patch =
                options.patch < 0 ? std::min(analysis.width, analysis.height) / 2 : options.patch;
            if (patch > 0) {
                const int spacing = std::max(2, patch / factor);
                sites = jumpSites(out.width, out.height, spacing, random);
                block = std::min(2 * options.neighbourhood + 1, std::max(1, spacing / 2));
                minimum = std::max(1, std::min(level.width, level.height) / 4);
            }
        } else {
            // Boßerhoff and Nicoll 2003: a quarter of the texels take the coarser output's
            // coordinates times 2.
            const SynthesisLevel& coarser = analysis.levels[std::size_t(l) - 1];
            for (int y = 0; y < previous.height; ++y)
                for (int x = 0; x < previous.width; ++x) {
                    if (2 * x >= out.width || 2 * y >= out.height) continue;
                    const std::int32_t s = previous.source[std::size_t(y) * previous.width + x];
                    const int sx = 2 * (s % coarser.width), sy = 2 * (s / coarser.width);
                    const std::size_t o = std::size_t(2 * y) * out.width + 2 * x;
                    out.source[o] = std::int32_t(sy * level.width + sx);
                    out.preset[o] = 1;
                }
        }
        LevelSynthesizer synthesizer(level, options, random);
        for (int pass = 0; pass < 2; ++pass) {  // the new texels, then the preset ones again
            for (int y = 0; y < out.height; ++y) {
                for (int x = 0; x < out.width; ++x) {
                    const std::size_t o = std::size_t(y) * out.width + x;
                    if (out.preset[o] != pass) continue;
                    if (pass == 0 && !sites.empty() && sites[o]) {
                        const std::int32_t source = synthesizer.jump(out, x, y, minimum);
                        if (source >= 0) {
                            presetBlock(out, level, x, y, block, source);
                            continue;
                        }
                    }
                    out.source[o] = synthesizer.synthesize(out, x, y);
                }
                if (pass == 1) progress.advance(std::size_t(out.width));
            }
        }
        previous = std::move(out);
    }
    progress.finish();
    for (int y = 0; y < options.height; ++y)
        for (int x = 0; x < options.width; ++x) {
            const std::int32_t s = previous.source[std::size_t(y) * previous.width + x];
            map.sampleX(x, y) = s % analysis.width;
            map.sampleY(x, y) = s / analysis.width;
        }
    return map;
}

SynthesisQuality measureSynthesis(const SampleAnalysis& analysis, const CoordinateMap& map) {
    validateCoordinateMap(map, "synthesis quality");
    if (map.sampleWidth != analysis.width || map.sampleHeight != analysis.height)
        throw Error("synthesis quality: the map points into a " + std::to_string(map.sampleWidth) +
                    "x" + std::to_string(map.sampleHeight) + " sample, the analysis is of a " +
                    std::to_string(analysis.width) + "x" + std::to_string(analysis.height) +
                    " one");
    const SynthesisLevel& level = analysis.levels.back();
    const int d = level.dimensions;
    auto distance = [&](std::size_t a, std::size_t b) {
        double sum = 0;
        for (int e = 0; e < d; ++e) {
            const double diff = double(level.features[a * d + e]) - level.features[b * d + e];
            sum += diff * diff;
        }
        return sum;
    };
    // Per-row partial sums, added in row order: the same figures for any thread count.
    struct Row {
        double distance = 0;
        std::size_t pairs = 0, coherent = 0;
    };
    std::vector<Row> rows(std::size_t(map.height));
    tbb::parallel_for(0, map.height, [&](int y) {
        Row& row = rows[std::size_t(y)];
        for (int x = 0; x < map.width; ++x) {
            const std::int32_t a = std::int32_t(map.sampleTexel(x, y));
            for (int axis = 0; axis < 2; ++axis) {
                const int nx = x + (axis == 0), ny = y + (axis == 1);
                if (nx >= map.width || ny >= map.height) continue;
                const std::int32_t b = std::int32_t(map.sampleTexel(nx, ny));
                row.distance += distance(std::size_t(a), std::size_t(b));
                ++row.pairs;
                if (wrappedTexel(level, a, axis == 0, axis == 1) == b) ++row.coherent;
            }
        }
    });
    SynthesisQuality quality;
    std::size_t pairs = 0, coherent = 0;
    for (const Row& row : rows) {
        quality.outputMeanDistance += row.distance;
        pairs += row.pairs;
        coherent += row.coherent;
    }
    quality.outputMeanDistance /= double(std::max<std::size_t>(pairs, 1));
    quality.coherenceRate = pairs ? double(coherent) / double(pairs) : 1.0;
    double sampleSum = 0;
    std::size_t samplePairs = 0;
    for (int y = 0; y < level.height; ++y)
        for (int x = 0; x < level.width; ++x) {
            const std::size_t p = std::size_t(y) * level.width + x;
            if (x + 1 < level.width) sampleSum += distance(p, p + 1), ++samplePairs;
            if (y + 1 < level.height) sampleSum += distance(p, p + level.width), ++samplePairs;
        }
    quality.sampleMeanDistance = sampleSum / double(std::max<std::size_t>(samplePairs, 1));
    quality.seamRatio = quality.sampleMeanDistance > 0
                            ? quality.outputMeanDistance / quality.sampleMeanDistance
                            : 1.0;
    return quality;
}

}  // namespace osgBTF
