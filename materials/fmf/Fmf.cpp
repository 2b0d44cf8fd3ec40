#include "materials/fmf/Fmf.h"
#include "materials/CoordinateMapRendering.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <iomanip>
#include <limits>
#include <memory>
#include <sstream>
#include <type_traits>
#include <vector>

#include <Imath/half.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <osg/Uniform>

#include "core/Error.h"
#include "core/LowRank.h"
#include "materials/MaterialMath.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

namespace {

// GL limits every OpenGL 4 implementation offers (and llvmpipe): texture size and array layers.
constexpr float kHalfMax = 65504.0f;

int groupsOf(int components) {
    return (components + 3) / 4;
}

std::string floatList(const float* v, int n) {
    std::string text;
    for (int i = 0; i < n; ++i) text += (i ? "," : "") + floatText(v[i]);
    return text;
}

void checkHalfRange(float value, const std::string& source, const char* name) {
    if (std::abs(value) > kHalfMax)
        fail(source, std::string("fmf: ") + name + " value " + floatText(value) +
                         " exceeds the half range (65504); use storage=float");
}

/** Throws Error "<source>: fmf: ..." for unorm8 storage or a layout beyond the GPU's limits. */
void checkLayout(const FactoredBtf& factors, MaterialTexture::PixelKind storage) {
    const std::string& source = factors.source;
    if (storage == MaterialTexture::UNorm8)
        fail(source, "fmf: storage must be half or float, got unorm8");
    const bool fmf = factors.model == FactorModel::Fmf;
    int maxGroups = 0, layers = 0;
    for (int c = 0; c < 3; ++c) {
        const int g = groupsOf(factors.components(c));
        maxGroups = std::max(maxGroups, g);
        if (!fmf || c == 0) layers += g;
    }
    const std::size_t uRows = factors.lights.size() * 3;
    if (maxGroups > kMaxTextureSize || uRows > std::size_t(kMaxTextureSize) ||
        factors.views.size() > std::size_t(kMaxArrayLayers) || factors.width > kMaxTextureSize ||
        factors.height > kMaxTextureSize || layers > kMaxArrayLayers || layers == 0)
        fail(source,
             "fmf: " + std::to_string(factors.width) + "x" + std::to_string(factors.height) +
                 " texels, " + std::to_string(factors.views.size()) + " views x " +
                 std::to_string(factors.lights.size()) + " lights and " + std::to_string(layers) +
                 " Eigen-Texture layers exceed the GPU's texture limits (" +
                 std::to_string(kMaxTextureSize) + " texels, " + std::to_string(kMaxArrayLayers) +
                 " array layers)");
}

/** Calls visit with a pointer to the first value of `t`: its halves, else its floats. */
template <typename Visit>
void withValues(const MaterialTexture& t, Visit visit) {
    if (!t.halves.empty())
        visit(t.halves.data());
    else
        visit(t.data.data());
}

/** The SxV texture's size (no data): width x height texels, a layer per group of 4 components
 *  of each factor in turn, RGBA. */
MaterialTexture sxvShapeOf(const FactoredBtf& factors, MaterialTexture::PixelKind storage) {
    int layers = 0;
    for (std::size_t f = 0; f < factors.factors.size(); ++f)
        layers += groupsOf(factors.components(int(f)));
    return {"sxv", factors.width, factors.height, layers, 4, storage, {}};
}

/** SxV of `factors` as the GPU texture (sxvShapeOf): texels bottom-up, zero beyond a factor's
 *  rank; half storage rounds to half (throws when a value does not fit) and fills `halves`.
 *  Factor by factor, each factor's SxV matrix freed once copied, and the texture grown by that
 *  factor's layers only then: the floats and the texture are never held whole together (a
 *  full-size UBO2014 file: 183 MiB of floats, 92 of halves). */
MaterialTexture moveSxvToTexture(FactoredBtf& factors, MaterialTexture::PixelKind storage) {
    MaterialTexture t = sxvShapeOf(factors, storage);
    const bool half = storage == MaterialTexture::Half;
    if (half)
        t.halves.reserve(t.valueCount());  // address space only: pages are touched when grown
    else
        t.data.reserve(t.valueCount());
    const std::size_t texels = factors.texelCount(), width = std::size_t(factors.width);
    for (BtfFactor& factor : factors.factors) {
        const int k = int(factor.U.cols()), layers = groupsOf(k);
        const std::size_t first = half ? t.halves.size() : t.data.size();
        const std::size_t grown = first + std::size_t(layers) * texels * 4;
        if (half)
            t.halves.resize(grown, Imath::half(0.0f));
        else
            t.data.resize(grown, 0.0f);
        // In parallel over rows, a texel's SxV row read once and written to its layers: a
        // full-size UBO2014 file has 48 million values to convert.
        tbb::parallel_for(
            tbb::blocked_range<int>(0, factors.height), [&](const tbb::blocked_range<int>& rows) {
                for (int y = rows.begin(); y != rows.end(); ++y)
                    for (int x = 0; x < factors.width; ++x) {
                        const float* row =
                            factor.SxV.data() + factors.factorRow(x, y) * std::size_t(k);
                        const std::size_t texel = std::size_t(y) * width + std::size_t(x);
                        for (int j = 0; j < k; ++j) {
                            const std::size_t at = first +
                                                   (std::size_t(j / 4) * texels + texel) * 4 +
                                                   std::size_t(j % 4);
                            if (half) {
                                checkHalfRange(row[j], factors.source, "SxV");
                                t.halves[at] = Imath::half(row[j]);
                            } else {
                                t.data[at] = row[j];
                            }
                        }
                    }
            });
        factor.SxV.resize(0, k);  // frees the floats, factor by factor
    }
    return t;
}

/** The U texture's size (no data): a layer per measured view, a row per (light, channel), the
 *  largest factor's components in groups of 4, RGBA. */
MaterialTexture uShapeOf(const FactoredBtf& factors, MaterialTexture::PixelKind storage) {
    const int maxGroups =
        std::max({groupsOf(factors.components(0)), groupsOf(factors.components(1)),
                  groupsOf(factors.components(2))});
    return {"u",     maxGroups, int(factors.lights.size() * 3), int(factors.views.size()), 4,
            storage, {}};
}

/** U of `factors` as the GPU texture (uShapeOf): row image * 3 + c holds channel c's U row (Fmf:
 *  row image * 3 + c of the factor; Dfmf: row image of factor c), zero beyond its rank; half
 *  storage rounds to half (throws when a value does not fit) and fills `halves`. The factors' U
 *  matrices are left empty (0 rows). */
MaterialTexture moveUToTexture(FactoredBtf& factors, MaterialTexture::PixelKind storage) {
    MaterialTexture t = uShapeOf(factors, storage);
    const bool half = storage == MaterialTexture::Half;
    if (half)
        t.halves.assign(t.valueCount(), Imath::half(0.0f));
    else
        t.data.assign(t.valueCount(), 0.0f);
    const bool fmf = factors.model == FactorModel::Fmf;
    const std::size_t rowValues = std::size_t(t.width) * 4;
    for (std::size_t image = 0; image < factors.imageCount(); ++image)
        for (std::size_t c = 0; c < 3; ++c) {
            const BtfFactor& f = factors.factors[fmf ? 0 : c];
            const std::size_t k = std::size_t(f.U.cols());
            const float* row = f.U.data() + (fmf ? image * 3 + c : image) * k;
            const std::size_t first = (image * 3 + c) * rowValues;
            for (std::size_t j = 0; j < k; ++j) {
                if (half) {
                    checkHalfRange(row[j], factors.source, "U");
                    t.halves[first + j] = Imath::half(row[j]);
                } else {
                    t.data[first + j] = row[j];
                }
            }
        }
    for (BtfFactor& factor : factors.factors) factor.U = FactorMatrix(0, factor.U.cols());
    return t;
}

}  // namespace

int FmfMaterial::groups(int channel) const {
    return groupsOf(_factors->components(channel));
}

int FmfMaterial::layerOffset(int channel) const {
    if (_factors->model == FactorModel::Fmf) return 0;
    int offset = 0;
    for (int c = 0; c < channel; ++c) offset += groups(c);
    return offset;
}

void FmfMaterial::setFactors(FactoredBtf factors, MaterialTexture::PixelKind storage) {
    factors.validate();
    checkLayout(factors, storage);
    MaterialTexture u = moveUToTexture(factors, storage);
    MaterialTexture sxv = moveSxvToTexture(factors, storage);
    adopt(std::move(factors), std::move(u), std::move(sxv));
}

namespace {

/** The SxV texture (sxvShapeOf) filled as a reader reads the file (FactorHooks::receiver): the
 *  file's halves copied as they are, anything else converted as moveSxvToTexture converts it, so
 *  the material equals fromFactors' on the same file without the 192 MB of floats between. */
class SxvReceiver : public FactorReceiver {
public:
    explicit SxvReceiver(MaterialTexture::PixelKind storage) : _storage(storage) {}

    void beginFactor(const FactoredBtf& described, int /*factor*/, int components,
                     int scalarSize) override {
        if (!_started) {
            // As fromFactors' callers do: a file of halves is rendered from halves.
            _started = true;
            if (scalarSize == 2) _storage = MaterialTexture::Half;
            _sxv = {"sxv", described.width, described.height, 0, 4, _storage, {}};
            _source = described.source;
            // Address space for every factor at this one's rank (pages are touched only when
            // grown): growing factor by factor would copy the earlier factors' values each time.
            const std::size_t expected = std::size_t(described.model == FactorModel::Fmf ? 1 : 3) *
                                         std::size_t(groupsOf(components)) *
                                         std::size_t(described.width) *
                                         std::size_t(described.height) * 4;
            if (_storage == MaterialTexture::Half)
                _sxv.halves.reserve(expected);
            else
                _sxv.data.reserve(expected);
        }
        const std::size_t texels = std::size_t(_sxv.width) * std::size_t(_sxv.height);
        _first = std::size_t(_sxv.depth) * texels * 4;
        _sxv.depth += groupsOf(components);
        const std::size_t grown = std::size_t(_sxv.depth) * texels * 4;
        // Zeros beyond the rank; value-initialised halves are zero bits (a memset, where
        // resize(n, half(0)) assigns one by one: 13 % of the first image's time).
        static_assert(std::is_trivially_default_constructible_v<Imath::half>);
        if (_storage == MaterialTexture::Half)
            _sxv.halves.resize(grown);
        else
            _sxv.data.resize(grown);
    }

    void texelRows(int /*factor*/, int components, std::uint64_t first, std::uint64_t count,
                   const unsigned char* bytes, std::uint64_t rowBytes, int scalarSize) override {
        const std::size_t width = std::size_t(_sxv.width);
        const std::size_t texels = width * std::size_t(_sxv.height);
        const bool half = _storage == MaterialTexture::Half;
        const bool copyHalves = half && scalarSize == 2;
        tbb::parallel_for(std::uint64_t(0), count, [&](std::uint64_t r) {
            // File row first + r is texel (x, y) with y from the bottom (FactoredBtf::factorRow).
            const std::size_t row = std::size_t(first + r);
            const std::size_t y = std::size_t(_sxv.height) - 1 - row / width, x = row % width;
            const std::size_t texel = y * width + x;
            const unsigned char* src = bytes + r * rowBytes;
            const auto at = [&](int j) {
                return _first + (std::size_t(j / 4) * texels + texel) * 4 + std::size_t(j % 4);
            };
            if (copyHalves) {
                // The file's halves as they are; infinity is refused as the float path refuses
                // it (checkHalfRange).
                for (int j = 0; j < components; ++j) {
                    std::uint16_t bits;
                    std::memcpy(&bits, src + 2 * j, 2);
                    if ((bits & 0x7fff) == 0x7c00)
                        checkHalfRange(imath_half_to_float(bits), _source, "SxV");
                    _sxv.halves[at(j)].setBits(bits);
                }
                return;
            }
            std::vector<float> values(static_cast<std::size_t>(components));
            scalarsToFloats(src, std::uint64_t(components), scalarSize, values.data());
            for (int j = 0; j < components; ++j) {
                if (half) {
                    checkHalfRange(values[std::size_t(j)], _source, "SxV");
                    _sxv.halves[at(j)] = Imath::half(values[std::size_t(j)]);
                } else {
                    _sxv.data[at(j)] = values[std::size_t(j)];
                }
            }
        });
    }

    osg::ref_ptr<Material> finish(FactoredBtf&& factors) override {
        osg::ref_ptr<FmfMaterial> m = new FmfMaterial;
        m->setFactorsAndSxv(std::move(factors), std::move(_sxv));
        return m;
    }

private:
    MaterialTexture::PixelKind _storage;
    MaterialTexture _sxv;
    std::string _source;
    std::size_t _first = 0;  ///< the current factor's first value in _sxv
    bool _started = false;
};

}  // namespace

void FmfMaterial::setFactorsAndSxv(FactoredBtf factors, MaterialTexture sxv) {
    factors.validate(true);
    checkLayout(factors, sxv.kind);
    MaterialTexture u = moveUToTexture(factors, sxv.kind);
    adopt(std::move(factors), std::move(u), std::move(sxv));
}

void FmfMaterial::adopt(FactoredBtf factors, MaterialTexture u, MaterialTexture sxv) {
    setGeometry(factors.width, factors.height, factors.views, factors.lights);
    _storage = sxv.kind;
    _factors = std::make_shared<const FactoredBtf>(std::move(factors));
    _sxv = std::make_shared<const MaterialTexture>(std::move(sxv));
    _u = std::make_shared<const MaterialTexture>(std::move(u));
    try {
        _viewLookup = DirectionLookup(_views);
        _lightLookup = _lights == _views ? _viewLookup : DirectionLookup(_lights);
    } catch (const Error& e) {
        // A direction set the interpolation cannot triangulate is the file's problem: name it.
        fail(_factors->source, e.what());
    }
}

FactoredBtf FmfMaterial::completeFactors() const {
    FactoredBtf complete = *_factors;
    const bool fmf = complete.model == FactorModel::Fmf;
    const std::size_t images = complete.imageCount();
    for (std::size_t f = 0; f < complete.factors.size(); ++f) {
        FactorMatrix& u = complete.factors[f].U;
        u.resize(Eigen::Index(fmf ? images * 3 : images), u.cols());
        for (std::size_t image = 0; image < images; ++image)
            for (int c = fmf ? 0 : int(f); c < (fmf ? 3 : int(f) + 1); ++c)
                uRow(image, c,
                     u.row(Eigen::Index(fmf ? image * 3 + std::size_t(c) : image)).data());
        FactorMatrix& sxv = complete.factors[f].SxV;
        sxv.resize(Eigen::Index(complete.texelCount()), complete.factors[f].U.cols());
        for (Eigen::Index row = 0; row < sxv.rows(); ++row)
            sxvRow(f, std::size_t(row), sxv.row(row).data());
    }
    return complete;
}

void FmfMaterial::uRow(std::size_t image, int channel, float* out) const {
    const int k = _factors->components(channel);
    withValues(*_u, [&](const auto* values) {
        const auto* row = values + (image * 3 + std::size_t(channel)) * uRowValues();
        for (int j = 0; j < k; ++j) out[j] = float(row[j]);
    });
}

void FmfMaterial::sxvRow(std::size_t factor, std::size_t row, float* out) const {
    // Row `row` counts from the top image row (FactoredBtf::factorRow), the texture from the
    // bottom.
    const std::size_t width = std::size_t(_width), texels = texelCount();
    const std::size_t texel = (std::size_t(_height) - 1 - row / width) * width + row % width;
    int layer = 0;
    for (std::size_t f = 0; f < factor; ++f) layer += groupsOf(_factors->components(int(f)));
    const int k = int(_factors->factors[factor].U.cols());
    withValues(*_sxv, [&](const auto* values) {
        for (int j = 0; j < k; ++j)
            out[j] = float(
                values[(std::size_t(layer + j / 4) * texels + texel) * 4 + std::size_t(j % 4)]);
    });
}

osg::ref_ptr<FmfMaterial> FmfMaterial::fromFactors(FactoredBtf factors,
                                                   MaterialTexture::PixelKind storage) {
    osg::ref_ptr<FmfMaterial> m = new FmfMaterial;
    m->setFactors(std::move(factors), storage);
    return m;
}

// ---- evaluation --------------------------------------------------------------------------------

int FmfMaterial::directionCombinations(const glm::vec3& view, const glm::vec3& light,
                                       std::array<std::size_t, 9>& images,
                                       std::array<float, 9>& weights) const {
    // The shader's lookups: 3 view x 3 light neighbours, exact Delaunay weights.
    const InterpolationWeights wv = _viewLookup.weights(view);
    const InterpolationWeights wl = _lightLookup.weights(light);
    int count = 0;
    for (int i = 0; i < 3; ++i)
        for (int j = 0; j < 3; ++j) {
            const float w = wv.weight[std::size_t(i)] * wl.weight[std::size_t(j)];
            if (!(w > 0.0f)) continue;
            images[std::size_t(count)] = std::size_t(wv.index[std::size_t(i)]) * _lights.size() +
                                         std::size_t(wl.index[std::size_t(j)]);
            weights[std::size_t(count)] = w;
            ++count;
        }
    return count;
}

void FmfMaterial::factorSums(std::size_t texel, const std::size_t* images, const float* weights,
                             int count, float sums[3]) const {
    // As fmf.frag: per group of 4 components, the U rows blended over the combinations,
    // then one dot product with the texel's SxV (the same order of operations as the GPU).
    const std::size_t texels = texelCount(), rowValues = uRowValues();
    for (int c = 0; c < 3; ++c) {
        const int k = _factors->components(c);
        withValues(*_sxv, [&](const auto* values) {
            withValues(*_u, [&](const auto* uValues) {
                float sum = 0.0f;
                for (int g = 0; g < k; g += 4) {
                    const auto* group =
                        values + (std::size_t(layerOffset(c) + g / 4) * texels + texel) * 4;
                    float blended[4] = {0, 0, 0, 0};
                    const int n = std::min(4, k - g);
                    for (int i = 0; i < count; ++i) {
                        const auto* u =
                            uValues + (images[i] * 3 + std::size_t(c)) * rowValues + std::size_t(g);
                        for (int j = 0; j < n; ++j) blended[j] += weights[i] * float(u[j]);
                    }
                    for (int j = 0; j < n; ++j) sum += blended[j] * float(group[j]);
                }
                sums[c] = sum;
            });
        });
    }
}

glm::vec3 FmfMaterial::evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const {
    return finishLinear(evaluateLinear(x, y, view, light), view, light);
}

glm::vec3 FmfMaterial::evaluateLinear(int x, int y, const glm::vec3& view,
                                      const glm::vec3& light) const {
    // Schwartz et al. 2013 interpolates U, the factor rows, and the sums are linear in them:
    // blending the 9 rows and decoding (colour model / exp) once is cheaper than decoding 9 values,
    // and exact at measured directions, where one combination has weight 1. The cosine division
    // uses the query light's own z, so it is exact there too.
    std::array<std::size_t, 9> images;
    std::array<float, 9> weights;
    const int count = directionCombinations(view, light, images, weights);
    float sums[3];
    factorSums(sxvTexel(x, y), images.data(), weights.data(), count, sums);
    return glm::vec3(sums[0], sums[1], sums[2]);
}

void FmfMaterial::evaluateRow(int x0, int y, int count, const glm::vec3& view,
                              const glm::vec3& light, glm::vec3* out) const {
    // factorSums's blended[j] do not depend on the texel: made once here, in its order (per
    // group, combination by combination), then per texel its `sum += blended[j] * sxv[j]`.
    std::array<std::size_t, 9> images;
    std::array<float, 9> weights;
    const int combinations = directionCombinations(view, light, images, weights);
    const std::size_t texels = texelCount(), rowValues = uRowValues();
    std::vector<float> blended[3];
    for (int c = 0; c < 3; ++c) {
        const int k = _factors->components(c);
        blended[c].assign(std::size_t(k), 0.0f);
        withValues(*_u, [&](const auto* uValues) {
            for (int g = 0; g < k; g += 4) {
                const int n = std::min(4, k - g);
                for (int i = 0; i < combinations; ++i) {
                    const auto* u =
                        uValues + (images[i] * 3 + std::size_t(c)) * rowValues + std::size_t(g);
                    for (int j = 0; j < n; ++j)
                        blended[c][std::size_t(g + j)] += weights[i] * float(u[j]);
                }
            }
        });
    }
    std::vector<glm::vec3> sums(std::size_t(count), glm::vec3(0.0f));
    withValues(*_sxv, [&](const auto* values) {
        for (int c = 0; c < 3; ++c) {
            const int k = _factors->components(c);
            for (int i = 0; i < count; ++i) {
                const std::size_t texel = sxvTexel(x0 + i, y);
                float sum = 0.0f;
                for (int g = 0; g < k; g += 4) {
                    const auto* group =
                        values + (std::size_t(layerOffset(c) + g / 4) * texels + texel) * 4;
                    const int n = std::min(4, k - g);
                    for (int j = 0; j < n; ++j)
                        sum += blended[c][std::size_t(g + j)] * float(group[j]);
                }
                sums[std::size_t(i)][c] = sum;
            }
        }
    });
    for (int i = 0; i < count; ++i) out[i] = finishLinear(sums[std::size_t(i)], view, light);
}

glm::vec3 FmfMaterial::finishLinear(const glm::vec3& linear, const glm::vec3&,
                                    const glm::vec3& light) const {
    const float sums[3] = {linear.x, linear.y, linear.z};
    float rgb[3];
    _factors->decodeColor(sums, rgb);
    const float scale = _factors->cosineScale(light.z);
    return glm::vec3(rgb[0], rgb[1], rgb[2]) * scale;
}

void FmfMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    const int x = int(texel % std::size_t(_width)), y = int(texel / std::size_t(_width));
    const std::size_t row = _factors->factorRow(x, y), images = _factors->imageCount();
    const bool fmf = _factors->model == FactorModel::Fmf;
    std::vector<float> sxv[3];
    for (std::size_t f = 0; f < _factors->factors.size(); ++f) {
        sxv[f].resize(std::size_t(_factors->factors[f].U.cols()));
        sxvRow(f, row, sxv[f].data());
    }
    const std::size_t rowValues = uRowValues();
    withValues(*_u, [&](const auto* u) {
        for (std::size_t i = 0; i < images; ++i) {
            // Each channel's U row times the texel's SxV row of its factor.
            float sums[3];
            for (int c = 0; c < 3; ++c) {
                const std::vector<float>& s = sxv[fmf ? 0 : c];
                const auto* uRow = u + (i * 3 + std::size_t(c)) * rowValues;
                float sum = 0.0f;
                for (std::size_t j = 0; j < s.size(); ++j) sum += float(uRow[j]) * s[j];
                sums[c] = sum;
            }
            _factors->decodeColor(sums, abrdf);
            const float scale = _factors->cosineScale(_lights.vector(i % _lights.size()).z);
            for (int c = 0; c < 3; ++c) abrdf[c] *= scale;
            abrdf += 3;
        }
    });
}

// ---- textures, memory, files ---------------------------------------------------------------

namespace {

/** Layer `layer` of the RGBA texture `t` (U's or SxV's) as floats. */
void copyLayer(const MaterialTexture& t, int layer, float* out) {
    const std::size_t values = std::size_t(t.width) * std::size_t(t.height) * 4;
    withValues(
        t, [&](const auto* from) { std::copy_n(from + std::size_t(layer) * values, values, out); });
}

}  // namespace

MaterialTexture FmfMaterial::uShape() const {
    return uShapeOf(*_factors, _storage);
}

MaterialTexture FmfMaterial::sxvShape() const {
    return sxvShapeOf(*_factors, _storage);
}

MaterialTexture FmfMaterial::uTexture() const {
    MaterialTexture t = uShape();
    t.data.resize(t.valueCount());
    const std::size_t layerValues = std::size_t(t.width) * std::size_t(t.height) * 4;
    for (int view = 0; view < t.depth; ++view)
        copyLayer(*_u, view, t.data.data() + std::size_t(view) * layerValues);
    return t;
}

MaterialTexture FmfMaterial::sxvTexture() const {
    MaterialTexture t = sxvShape();
    t.data.resize(t.valueCount());
    const std::size_t layerValues = std::size_t(t.width) * std::size_t(t.height) * 4;
    for (int layer = 0; layer < t.depth; ++layer)
        copyLayer(*_sxv, layer, t.data.data() + std::size_t(layer) * layerValues);
    return t;
}

FmfMaterial::MemoryBreakdown FmfMaterial::memoryBreakdown() const {
    const double texels = double(texelCount()), bytes = bytesPerValue(_storage);
    const bool fmf = _factors->model == FactorModel::Fmf;
    const int maxGroups = std::max({groups(0), groups(1), groups(2)});
    const int layers = fmf ? groups(0) : groups(0) + groups(1) + groups(2);
    // As uploaded: groups of 4 components (a rank that is not a multiple of 4 pads with zeros).
    const double sxvValues = double(layers) * 4 * texels;
    const double uValues = double(_factors->imageCount()) * 3 * maxGroups * 4;
    MemoryBreakdown m;
    m.perTexelValues = sxvValues / texels;
    m.perTexelBytes = m.perTexelValues * bytes;
    m.sharedValues = uValues / texels;
    m.sharedBytes = m.sharedValues * bytes;
    m.uBytes = std::uint64_t(uValues * bytes);
    m.sxvBytes = std::uint64_t(sxvValues * bytes);
    return m;
}

MemoryFootprint FmfMaterial::memory() const {
    const MemoryBreakdown m = memoryBreakdown();
    return {m.perTexelValues + m.sharedValues, m.perTexelBytes + m.sharedBytes,
            m.uBytes + m.sxvBytes, m.uBytes};
}

FittedMaterial FmfMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    const bool fmf = _factors->model == FactorModel::Fmf;
    file.parameters["model"] = fmf ? kFmfPlainModel : "dfmf";
    const int ks[3] = {_factors->components(0), _factors->components(1), _factors->components(2)};
    file.parameters["components"] =
        fmf ? std::to_string(ks[0])
            : std::to_string(ks[0]) + "," + std::to_string(ks[1]) + "," + std::to_string(ks[2]);
    file.parameters["cosine"] = _factors->cosine ? "1" : "0";
    file.parameters["colorModel"] = std::to_string(_factors->colorModel);
    file.parameters["colorMean"] = floatList(_factors->colorMean.data(), 3);
    file.parameters["colorMatrix"] = floatList(_factors->colorMatrix.data(), 9);
    file.parameters["dynamicRangeReduction"] = std::to_string(_factors->dynamicRangeReduction);
    file.parameters["eps"] = floatText(_factors->eps);
    file.textures.push_back(uTexture());
    file.textures.push_back(sxvTexture());
    // The singular values are not needed to render; kept so that a file describes its factors.
    const int maxK = std::max({ks[0], ks[1], ks[2]});
    MaterialTexture s{"singularValues",       maxK, int(_factors->factors.size()), 1, 1,
                      MaterialTexture::Float, {}};
    s.data.assign(s.valueCount(), 0.0f);
    for (std::size_t f = 0; f < _factors->factors.size(); ++f) {
        const Eigen::VectorXf& values = _factors->factors[f].S;
        for (Eigen::Index k = 0; k < values.size() && k < maxK; ++k)
            s.data[f * std::size_t(maxK) + std::size_t(k)] = values(k);
    }
    file.textures.push_back(s);
    return file;
}

osg::ref_ptr<FmfMaterial> FmfMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<FmfMaterial> m = new FmfMaterial;
    m->readCommon(file);
    FactoredBtf factors;
    factors.source = file.source;
    factors.views = file.views;
    factors.lights = file.lights;
    factors.width = m->_width;
    factors.height = m->_height;
    const std::string& model = file.parameter("model");
    if (model != kFmfPlainModel && model != "dfmf")
        fail(file.source, "parameter 'model' must be fmf or dfmf, got " + model);
    factors.model = model == kFmfPlainModel ? FactorModel::Fmf : FactorModel::Dfmf;
    const bool fmf = factors.model == FactorModel::Fmf;
    auto numbers = [&](const std::string& key, std::size_t n) {
        std::vector<float> values;
        std::stringstream in(file.parameter(key));
        std::string item;
        while (std::getline(in, item, ',')) {
            try {
                std::size_t used = 0;
                values.push_back(std::stof(item, &used));
                if (used != item.size()) throw std::invalid_argument(item);
            } catch (const std::logic_error&) {
                values.clear();
                break;
            }
        }
        if (values.size() != n)
            fail(file.source, "parameter '" + key + "' must be " +
                                  (n == 1 ? std::string("a number")
                                          : std::to_string(n) + " comma-separated numbers") +
                                  ", got '" + file.parameter(key) + "'");
        return values;
    };
    const std::vector<float> ks = numbers("components", fmf ? 1 : 3);
    const std::vector<float> mean = numbers("colorMean", 3), matrix = numbers("colorMatrix", 9);
    const float cosine = numbers("cosine", 1)[0], colorModel = numbers("colorModel", 1)[0];
    const float drr = numbers("dynamicRangeReduction", 1)[0];
    factors.eps = numbers("eps", 1)[0];
    factors.cosine = cosine != 0.0f;
    factors.colorModel = int(colorModel);
    factors.dynamicRangeReduction = std::uint32_t(drr);
    std::copy(mean.begin(), mean.end(), factors.colorMean.begin());
    std::copy(matrix.begin(), matrix.end(), factors.colorMatrix.begin());
    for (float k : ks)
        if (!(k >= 1.0f) || k != std::floor(k) || k > float(kMaxArrayLayers * 4))
            fail(file.source, "parameter 'components' must hold positive integers, got '" +
                                  file.parameter("components") + "'");

    const MaterialTexture& u = file.texture("u");
    const MaterialTexture& sxv = file.texture("sxv");
    const std::size_t nV = file.views.size(), nL = file.lights.size();
    const std::size_t texels = std::size_t(factors.width) * std::size_t(factors.height);
    int maxGroups = 0, layers = 0;
    for (float k : ks) {
        maxGroups = std::max(maxGroups, groupsOf(int(k)));
        layers += groupsOf(int(k));
    }
    const auto check = [&](const MaterialTexture& got, int w, int h, int d) {
        if (got.width != w || got.height != h || got.depth != d || got.channels != 4 ||
            got.kind == MaterialTexture::UNorm8 || got.kind != u.kind)
            fail(file.source, "texture '" + got.name + "' must be " + std::to_string(w) + "x" +
                                  std::to_string(h) + "x" + std::to_string(d) +
                                  " RGBA half or float (as 'u') for components " +
                                  file.parameter("components"));
    };
    check(u, maxGroups, int(nL * 3), int(nV));
    check(sxv, factors.width, factors.height, layers);
    for (const MaterialTexture* t : {&u, &sxv})
        if (t->storedCount() != t->valueCount())
            fail(file.source, "texture '" + t->name + "' holds " +
                                  std::to_string(t->storedCount()) + " values, " +
                                  std::to_string(t->valueCount()) + " expected");

    factors.factors.resize(fmf ? 1 : 3);
    for (std::size_t f = 0; f < factors.factors.size(); ++f) {
        BtfFactor& factor = factors.factors[f];
        const int k = int(ks[f]);
        factor.U.resize(0, k);    // U stays in its texture
        factor.SxV.resize(0, k);  // and SxV in its
        factor.S = Eigen::VectorXf::Zero(k);
    }
    if (const MaterialTexture* s = file.findTexture("singularValues"))
        if (s->channels == 1 && s->height == int(factors.factors.size()))
            for (std::size_t f = 0; f < factors.factors.size(); ++f)
                for (Eigen::Index j = 0; j < factors.factors[f].S.size() && j < s->width; ++j)
                    factors.factors[f].S(j) = s->value(f * std::size_t(s->width) + std::size_t(j));
    if (!fmf) FactoredBtf::checkColorModel(file.source, factors.colorModel);
    // The file is this function's own: the U and SxV textures are taken, not copied, with the
    // values beyond each factor's rank set to zero as a fit writes them (the GPU multiplies the
    // two, and 0 times an infinity is not 0). A half file holds nothing beyond half's range but
    // infinity.
    MaterialTexture& ownU = file.texture("u");
    MaterialTexture& own = file.texture("sxv");
    const auto toHalves = [&](MaterialTexture& t, const char* name) {
        if (t.kind != MaterialTexture::Half || !t.halves.empty()) return;
        // A FittedMaterial made in memory, with float values.
        t.halves.resize(t.data.size());
        for (std::size_t i = 0; i < t.data.size(); ++i) {
            checkHalfRange(t.data[i], file.source, name);
            t.halves[i] = Imath::half(t.data[i]);
        }
        std::vector<float>().swap(t.data);
    };
    toHalves(ownU, "U");
    toHalves(own, "SxV");
    const std::size_t rowValues = std::size_t(maxGroups) * 4;
    for (std::size_t row = 0; row < nV * nL * 3; ++row)
        for (std::size_t j = std::size_t(ks[fmf ? 0 : row % 3]); j < rowValues; ++j) {
            if (ownU.halves.empty())
                ownU.data[row * rowValues + j] = 0.0f;
            else
                ownU.halves[row * rowValues + j] = Imath::half(0.0f);
        }
    const auto infiniteU = std::find_if(ownU.halves.begin(), ownU.halves.end(),
                                        [](Imath::half h) { return h.isInfinity(); });
    if (infiniteU != ownU.halves.end())
        fail(file.source, "fmf: U value " + floatText(float(*infiniteU)) +
                              " exceeds the half range (65504); use storage=float");
    int layer = 0;
    for (float k : ks) {
        const int padded = groupsOf(int(k)) * 4;
        layer += groupsOf(int(k));
        if (padded == int(k)) continue;
        const std::size_t lastLayer = std::size_t(layer - 1) * texels * 4;
        for (std::size_t texel = 0; texel < texels; ++texel)
            for (int j = int(k) % 4; j < 4; ++j) {
                const std::size_t at = lastLayer + texel * 4 + std::size_t(j);
                if (own.halves.empty())
                    own.data[at] = 0.0f;
                else
                    own.halves[at] = Imath::half(0.0f);
            }
    }
    const auto infinite = std::find_if(own.halves.begin(), own.halves.end(),
                                       [](Imath::half h) { return h.isInfinity(); });
    if (infinite != own.halves.end())
        fail(file.source, "fmf: SxV value " + floatText(float(*infinite)) +
                              " exceeds the half range (65504); use storage=float");
    try {
        checkLayout(factors, own.kind);
        m->adopt(std::move(factors), std::move(ownU), std::move(own));
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    return m;
}

osg::ref_ptr<osg::StateSet> FmfMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    // Arrays even with one layer (rank <= 4, one view): fmf.frag samples sampler2DArrays.
    // Uploaded straight from the shared U and SxV, which are held in the textures' layout: no
    // copy of the textures in host memory, and halves go to the driver as halves (a full-size
    // UBO2014 file's are 110 MB; converted to floats first, the upload took ~3x as long).
    addTexture(*stateSet, createStoredTextureArray(_u).get(), "fmfU", 0);
    addTexture(*stateSet, createStoredTextureArray(_sxv, filtersParameters()).get(), "fmfSxV", 1);
    _viewLookup.addToStateSet(*stateSet, "fmfViewTable", 2);
    _lightLookup.addToStateSet(*stateSet, "fmfLightTable", 3);
    const bool fmf = _factors->model == FactorModel::Fmf;
    stateSet->addUniform(new osg::Uniform("fmfShared", fmf ? 1 : 0));
    stateSet->addUniform(new osg::Uniform("fmfGroups", groups(0), groups(1), groups(2)));
    stateSet->addUniform(
        new osg::Uniform("fmfLayerOffset", layerOffset(0), layerOffset(1), layerOffset(2)));
    // Fmf decodes with exp or not at all; model 0 (none) stands for that in the colour branch.
    stateSet->addUniform(new osg::Uniform("fmfColorModel", fmf ? 0 : _factors->colorModel));
    const auto& mtx = _factors->colorMatrix;
    osg::ref_ptr<osg::Uniform> rows = new osg::Uniform(osg::Uniform::FLOAT_VEC3, "fmfColorRows", 3);
    for (unsigned i = 0; i < 3; ++i)
        rows->setElement(i, osg::Vec3(mtx[i * 3], mtx[i * 3 + 1], mtx[i * 3 + 2]));
    stateSet->addUniform(rows.get());
    const auto& mean = _factors->colorMean;
    stateSet->addUniform(new osg::Uniform("fmfColorMean", osg::Vec3(mean[0], mean[1], mean[2])));
    stateSet->addUniform(new osg::Uniform("fmfDrr", _factors->drr() ? 1 : 0));
    stateSet->addUniform(new osg::Uniform("fmfEps", _factors->eps));
    stateSet->addUniform(new osg::Uniform("fmfCosine", _factors->cosine ? 1 : 0));
    return stateSet;
}

namespace {
const bool fmfRegistered = registerMethodClass<FmfMaterial>([] {
    MethodInfo m;
    m.description =
        "full-matrix factorisation (Schwartz et al. 2013; UBO2014 FMF/DFMF files): "
        "rank-C SVD of the (view, light, colour) x texel matrix, 3x3 view/light blending of U; "
        "64 bytes per texel + U at 32 components, half";
    m.options = {OptionSpec::integer("components", 32, 1, OptionSpec::kNoLimit,
                                     "rank C: Eigen-Textures / Eigen-ABRDFs (at most the "
                                     "texels, or 3 x views x lights if fewer; the paper uses "
                                     "100)"),
                 OptionSpec::choice("storage", "half", {"half", "float"},
                                    "precision of U and SxV on the GPU and in the file")};
    // Per-texel SxV rows times per-direction U rows; the colour decoding and exp come after the
    // sums (FmfMaterial::finishLinear).
    m.filtersParameters = true;
    m.shaderCost = [](const Material& material) {
        // fmf.frag. View + light lookups 2 x 11; the 9 combinations: weight product,
        // test, row address, count (4 x 9); decode at worst (model 11): 5 model tests, exp, 3
        // adds, 2 products, YUV 8; cosine: 3 tests, divide, multiply. Shared SxV (fmf): per group
        // of 4 components 1 SxV fetch and per channel 9 x (U fetch, address add, multiply, add)
        // + dot + add; per channel (dfmf): per group the same for one channel + the layer add.
        const auto& fmf = static_cast<const FmfMaterial&>(material);
        const bool shared = fmf.factors().model == FactorModel::Fmf;
        const int g = shared ? fmf.groups(0) : fmf.groups(0) + fmf.groups(1) + fmf.groups(2);
        const DirectionLookup::Cost v = fmf.viewLookup().cost(), l = fmf.lightLookup().cost();
        const int alu = v.alu + l.alu + 36 + 19 + 5 + (shared ? 87 * g : 30 * g);
        const int tex = v.tex + l.tex + (shared ? 28 * g : 10 * g);
        const std::string lookups = "; L = " + std::to_string(v.alu + l.alu) +
                                    ", T = " + std::to_string(v.tex + l.tex) +
                                    ": view and light lookups)";
        return ShaderCost::ofEvaluate(
            alu, tex,
            shared ? "ALU 87g+60+L, TEX 28g+T (g = components / 4" + lookups
                   : "ALU 30g+60+L, TEX 10g+T (g = sum of the channels' components / 4" + lookups);
    };
    // Schwartz et al. 2013 is the latest of the papers: last in the paper order.
    // Linear in the light weights for the plain model: an environment folds into U per view once
    // per vertex (FmfEnvironment.cpp, fmf_environment.frag).
    EnvironmentHooks environment;
    environment.folds = [](const Material& material) {
        return fmfFoldable(static_cast<const FmfMaterial&>(material));
    };
    environment.fold = [](const Material& material, const std::vector<glm::vec3>& g) {
        return foldFmf(static_cast<const FmfMaterial&>(material), g);
    };
    environment.evaluateFolded = [](const Material& material, const std::vector<float>& folded,
                                    int x, int y, const glm::vec3& view) {
        return evaluateFoldedFmf(static_cast<const FmfMaterial&>(material), folded, x, y, view);
    };
    environment.foldedStride = [](const Material& material) {
        const FmfMaterial& fmf = static_cast<const FmfMaterial&>(material);
        return fmf.views().size() * std::size_t(fmf.factors().factors[0].U.cols()) * 3;
    };
    environment.addUniforms = [](const Material& material, osg::StateSet& stateSet) {
        const FmfMaterial& fmf = static_cast<const FmfMaterial&>(material);
        stateSet.addUniform(
            new osg::Uniform("fmfComponents", int(fmf.factors().factors[0].U.cols())));
    };
    m.environment = std::move(environment);
    FactorHooks factors;  // FmfMaterial::factors() are what a UBO2014 .btf file stores
    factors.description = [](const Material& material) -> const FactoredBtf& {
        return static_cast<const FmfMaterial&>(material).factors();
    };
    factors.complete = [](const Material& material) {
        return static_cast<const FmfMaterial&>(material).completeFactors();
    };
    factors.scalarBytes = [](const Material& material) {
        return static_cast<const FmfMaterial&>(material).storage() == MaterialTexture::Float ? 4
                                                                                             : 2;
    };
    factors.fromFactors = [](FactoredBtf&& stored, MaterialTexture::PixelKind storage) {
        return osg::ref_ptr<Material>(FmfMaterial::fromFactors(std::move(stored), storage));
    };
    factors.receiver = [](MaterialTexture::PixelKind storage) -> std::unique_ptr<FactorReceiver> {
        return std::make_unique<SxvReceiver>(storage);
    };
    m.factors = std::move(factors);
    m.order = 70;
    m.fitWorkingSet = 0.75;  // per-view blocks and the SVD's sketch (as pca)
    m.quickFitOptions = "components=2";
    return m;
}());
}  // namespace

// The tables every texel shares; the other textures are per texel (remapMaterial).
[[maybe_unused]] const bool fmfSharedTexturesDeclared =
    declareSharedTextures(FmfMaterial::kMethod, {"u", "singularValues"});

}  // namespace osgBTF
