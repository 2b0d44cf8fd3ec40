#include "materials/pca/Pca.h"
#include "materials/CoordinateMapRendering.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include <Imath/half.h>
#include <tbb/parallel_for.h>
#include <osg/Uniform>

#include "core/Error.h"
#include "core/LowRank.h"
#include "core/Progress.h"
#include "materials/MaterialState.h"

namespace osgBTF {

namespace {

// GL limits every OpenGL 4 implementation offers (and llvmpipe): texture size and array layers.
constexpr int kMaxTextureSize = 16384;
constexpr int kMaxArrayLayers = 2048;

const char* storageName(MaterialTexture::PixelKind kind) {
    switch (kind) {
        case MaterialTexture::UNorm8:
            return "unorm8";
        case MaterialTexture::Half:
            return "half";
        case MaterialTexture::Float:
            break;
    }
    return "float";
}

double bytesPerValue(MaterialTexture::PixelKind kind) {
    switch (kind) {
        case MaterialTexture::UNorm8:
            return 1;
        case MaterialTexture::Half:
            return 2;
        case MaterialTexture::Float:
            break;
    }
    return 4;
}

/** The storage option's value (validated: one of the option table's choices). */
MaterialTexture::PixelKind storageKind(const std::string& text) {
    if (text == "unorm8") return MaterialTexture::UNorm8;
    return text == "half" ? MaterialTexture::Half : MaterialTexture::Float;
}

/** Stores one Eigen-Texture column (3 * texels values, max |value| = 1) at the storage's precision.
 *  `stored` receives what the file and the GPU hold, `basis` what that means (E = offset + range
 *  * stored per channel), `offset`/`range` the per-channel mapping (0/1 unless unorm8). */
void quantise(const float* e, std::size_t rows, MaterialTexture::PixelKind kind, float* stored,
              float* basis, float offset[3], float range[3]) {
    for (int ch = 0; ch < 3; ++ch) offset[ch] = 0.0f, range[ch] = 1.0f;
    if (kind == MaterialTexture::Float) {
        std::copy(e, e + rows, stored);
        std::copy(e, e + rows, basis);
        return;
    }
    if (kind == MaterialTexture::Half) {
        for (std::size_t i = 0; i < rows; ++i) basis[i] = stored[i] = float(Imath::half(e[i]));
        return;
    }
    for (int ch = 0; ch < 3; ++ch) {
        float lo = 0.0f, hi = 0.0f;
        if (rows >= 3) lo = hi = e[ch];
        for (std::size_t i = std::size_t(ch); i < rows; i += 3) {
            lo = std::min(lo, e[i]);
            hi = std::max(hi, e[i]);
        }
        offset[ch] = lo;
        range[ch] = hi - lo;
    }
    for (std::size_t i = 0; i < rows; ++i) {
        const int ch = int(i % 3);
        // n / 255.0f is exactly what the file loader produces, so save/load stays bit-exact.
        const float n =
            range[ch] > 0.0f
                ? std::clamp(std::round((e[i] - offset[ch]) / range[ch] * 255.0f), 0.0f, 255.0f)
                : 0.0f;
        stored[i] = n / 255.0f;
        basis[i] = offset[ch] + range[ch] * stored[i];
    }
}

}  // namespace

PcaMaterial::PcaMaterial(const PcaMaterial& other, const osg::CopyOp& copyop)
    : Material(other, copyop),
      eigenTextures(other.eigenTextures),
      weights(other.weights),
      _components(other._components),
      _tileColumns(other._tileColumns),
      _viewLookup(other._viewLookup),
      _lightLookup(other._lightLookup) {}

void PcaMaterial::assignFrom(const Material& other) {
    const PcaMaterial& o = assignCommon<PcaMaterial>(other);
    eigenTextures = o.eigenTextures;
    weights = o.weights;
    _components = o._components;
    _tileColumns = o._tileColumns;
    _viewLookup = o._viewLookup;
    _lightLookup = o._lightLookup;
}

void PcaMaterial::setShape(int width, int height, const DirectionSet& views,
                           const DirectionSet& lights, int components,
                           MaterialTexture::PixelKind storage) {
    if (width <= 0 || height <= 0) throw Error("pca: invalid texel size");
    if (components < 1) throw Error("pca: components must be at least 1");
    if (views.size() > std::size_t(kMaxArrayLayers) || lights.size() > kMaxTextureSize)
        throw Error("pca: " + std::to_string(views.size()) + " views x " +
                    std::to_string(lights.size()) + " lights exceed the GPU's texture limits (" +
                    std::to_string(kMaxArrayLayers) + " array layers)");
    const int columns = std::max(1, std::min(components, kMaxTextureSize / width));
    const int rows = (components + columns - 1) / columns;
    if (width > kMaxTextureSize || std::int64_t(rows) * height > kMaxTextureSize)
        throw Error("pca: " + std::to_string(width) + "x" + std::to_string(height) +
                    " texels with " + std::to_string(components) +
                    " components do not fit a texture of " + std::to_string(kMaxTextureSize) + "x" +
                    std::to_string(kMaxTextureSize));
    setGeometry(width, height, views, lights);
    _components = components;
    _tileColumns = columns;
    eigenTextures = {
        "eigenTextures", columns * width, rows * height, int(views.size()), 3, storage, {}};
    weights = {
        "weights", components + 1, int(lights.size()), int(views.size()), 3, MaterialTexture::Float,
        {}};
}

void PcaMaterial::prepareLookups() {
    _viewLookup = DirectionLookup(_views);
    _lightLookup = _lights == _views ? _viewLookup : DirectionLookup(_lights);
}

osg::ref_ptr<PcaMaterial> PcaMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const OptionValues o = validateOptions("pca", options);
    if (btf.empty()) throw Error("pca: the BTF is empty");
    const int components = o.integer("components");
    const MaterialTexture::PixelKind storage = storageKind(o.choice("storage"));
    const std::size_t texels = btf.texelCount(), rows = texels * 3, lights = btf.lightCount();
    const std::size_t maxComponents = std::min(lights, rows);
    // The rank of a view's matrix bounds it; that depends on the data, not on the table.
    if (std::size_t(components) > maxComponents)
        throw Error("pca: option components must be at most " + std::to_string(maxComponents) +
                    " for this BTF (its lights, or 3 x texels if fewer), got " +
                    std::to_string(components));

    osg::ref_ptr<PcaMaterial> m = new PcaMaterial;
    m->setShape(btf.width(), btf.height(), btf.views(), btf.lights(), components, storage);
    m->prepareLookups();
    // The model itself can be gigabytes (151 views x 16 components x 160000 texels x RGB for a
    // full-size UBO2014 file): refused before allocating when it cannot fit.
    // 8-bit Eigen-Textures are held as bytes: a quarter of the memory of floats (1.2 GB instead
    // of 4.6 for a full-size UBO2014 file at 16 components).
    const bool bytes = storage == MaterialTexture::UNorm8;
    checkMemory(std::uint64_t(m->eigenTextures.valueCount()) * (bytes ? 1 : sizeof(float)) +
                    std::uint64_t(m->weights.valueCount()) * sizeof(float),
                "pca: " + std::to_string(components) + " Eigen-Textures for each of " +
                    std::to_string(btf.viewCount()) + " views");
    if (bytes)
        m->eigenTextures.bytes.assign(m->eigenTextures.valueCount(), 0);
    else
        m->eigenTextures.data.assign(m->eigenTextures.valueCount(), 0.0f);
    m->weights.data.assign(m->weights.valueCount(), 0.0f);

    std::vector<double> totalSquares(btf.viewCount(), 0.0), residualSquares(btf.viewCount(), 0.0);
    Progress progress("pca: fitting " + std::to_string(btf.viewCount()) + " views",
                      btf.viewCount());
    // One view per task: each is an independent (3 * texels) x lights problem, and Eigen's
    // single-threaded kernels inside keep both cores busy without oversubscription.
    tbb::parallel_for(std::size_t(0), btf.viewCount(), [&](std::size_t v) {
        std::vector<float> images(rows * lights);  // column l = image (v, l), texel-major RGB
        btf.readImages(v * lights, lights, images.data());
        const TruncatedSvd svd = truncatedSvd(images.data(), rows, lights, components);
        double sumSquares = 0;
        for (double s : svd.singularValues) sumSquares += s * s;
        totalSquares[v] = sumSquares;
        residualSquares[v] = svd.residualSquared();

        std::vector<float> e(rows), stored(rows), basis(rows * std::size_t(components));
        std::vector<float> offsets(std::size_t(components) * 3), ranges(offsets.size());
        for (int k = 0; k < components; ++k) {
            const float* u = svd.u.data() + std::size_t(k) * rows;
            float maxAbs = 0.0f;
            for (std::size_t i = 0; i < rows; ++i) maxAbs = std::max(maxAbs, std::abs(u[i]));
            // Any scale works (the weights absorb it); max |E| = 1 puts half's and unorm8's
            // precision where the values are.
            const float scale = maxAbs > 0.0f ? 1.0f / maxAbs : 0.0f;
            for (std::size_t i = 0; i < rows; ++i) e[i] = u[i] * scale;
            quantise(e.data(), rows, storage, stored.data(), basis.data() + std::size_t(k) * rows,
                     offsets.data() + k * 3, ranges.data() + k * 3);
            for (std::size_t t = 0; t < texels; ++t) {
                const std::size_t at =
                    m->eigenIndex(v, k, int(t % btf.width()), int(t / btf.width()));
                for (std::size_t ch = 0; ch < 3; ++ch) {
                    const float q = stored[t * 3 + ch];
                    if (bytes)
                        m->eigenTextures.bytes[at + ch] = std::uint8_t(std::lround(q * 255.0f));
                    else
                        m->eigenTextures.data[at + ch] = q;
                }
            }
        }
        // Weights refitted against the basis as stored: for float storage this is the projection
        // onto the top singular vectors (the Eckart-Young optimum); for half and unorm8 it is the
        // best the quantised basis can do.
        const std::vector<float> alpha =
            leastSquares(basis.data(), rows, components, images.data(), int(lights));
        for (std::size_t l = 0; l < lights; ++l) {
            float* out = m->weights.data.data() + m->weightIndex(v, l, 0);
            float* bias = m->weights.data.data() + m->weightIndex(v, l, components);
            for (int k = 0; k < components; ++k) {
                const float a = alpha[l * std::size_t(components) + k];
                for (int ch = 0; ch < 3; ++ch) {
                    out[k * 3 + ch] = a * ranges[k * 3 + ch];
                    bias[ch] += a * offsets[k * 3 + ch];
                }
            }
        }
        progress.advance();
    });
    progress.finish();

    const double total = std::accumulate(totalSquares.begin(), totalSquares.end(), 0.0);
    const double residual = std::accumulate(residualSquares.begin(), residualSquares.end(), 0.0);
    m->fitInfo["seconds"] = std::to_string(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    m->fitInfo["components"] = std::to_string(components);
    m->fitInfo["storage"] = storageName(storage);
    // Share of the data's squared norm the rank-c subspaces capture (before quantisation).
    m->fitInfo["energy"] = std::to_string(total > 0 ? 1.0 - residual / total : 1.0);
    return m;
}

glm::vec3 PcaMaterial::combination(int x, int y, std::size_t view, std::size_t light) const {
    const float* w = weights.data.data() + weightIndex(view, light, 0);
    const float* bias = w + std::size_t(_components) * 3;
    glm::vec3 sum(bias[0], bias[1], bias[2]);
    for (int k = 0; k < _components; ++k)
        sum += glm::vec3(w[k * 3], w[k * 3 + 1], w[k * 3 + 2]) * eigenTexel(view, k, x, y);
    return sum;
}

glm::vec3 PcaMaterial::evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const {
    // The shader's loop: 3 view x 3 light neighbours of the exact interpolation.
    const InterpolationWeights wv = _viewLookup.weights(view);
    const InterpolationWeights wl = _lightLookup.weights(light);
    glm::vec3 sum(0.0f);
    for (int i = 0; i < 3; ++i) {
        if (!(wv.weight[i] > 0.0f)) continue;
        for (int j = 0; j < 3; ++j) {
            const float w = wv.weight[i] * wl.weight[j];
            if (!(w > 0.0f)) continue;
            sum += w * combination(x, y, std::size_t(wv.index[i]), std::size_t(wl.index[j]));
        }
    }
    return sum;
}

void PcaMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    const int x = int(texel % std::size_t(_width)), y = int(texel / std::size_t(_width));
    for (std::size_t v = 0; v < _views.size(); ++v)
        for (std::size_t l = 0; l < _lights.size(); ++l) {
            const glm::vec3 value = combination(x, y, v, l);
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
}

PcaMaterial::MemoryBreakdown PcaMaterial::memoryBreakdown() const {
    const double texels = double(texelCount());
    MemoryBreakdown m;
    m.perTexelValues = double(eigenTextures.valueCount()) / texels;
    m.perTexelBytes = m.perTexelValues * bytesPerValue(eigenTextures.kind);
    m.sharedValues = double(weights.valueCount()) / texels;
    m.sharedBytes = m.sharedValues * bytesPerValue(weights.kind);
    return m;
}

MemoryFootprint PcaMaterial::memory() const {
    const MemoryBreakdown m = memoryBreakdown();
    const double bytes = double(eigenTextures.valueCount()) * bytesPerValue(eigenTextures.kind) +
                         double(weights.valueCount()) * bytesPerValue(weights.kind);
    return {m.perTexelValues + m.sharedValues, m.perTexelBytes + m.sharedBytes,
            std::uint64_t(bytes)};
}

FittedMaterial PcaMaterial::toFittedMaterial() const {
    return osg::ref_ptr<PcaMaterial>(new PcaMaterial(*this))->releaseFittedMaterial();
}

FittedMaterial PcaMaterial::releaseFittedMaterial() {
    FittedMaterial file = writeCommon();
    file.parameters["components"] = std::to_string(_components);
    file.parameters["tileColumns"] = std::to_string(_tileColumns);
    file.textures.push_back(std::move(eigenTextures));
    file.textures.push_back(std::move(weights));
    eigenTextures = {};
    weights = {};
    return file;
}

osg::ref_ptr<PcaMaterial> PcaMaterial::fromFile(const FittedMaterial& file) {
    osg::ref_ptr<PcaMaterial> m = new PcaMaterial;
    m->readCommon(file);
    int components = 0;
    try {
        components = std::stoi(file.parameter("components"));
    } catch (const std::logic_error&) {
        fail(file.source, "parameter 'components' is not an integer");
    }
    const MaterialTexture& eigen = file.texture("eigenTextures");
    const MaterialTexture& w = file.texture("weights");
    try {
        m->setShape(m->_width, m->_height, file.views, file.lights, components, eigen.kind);
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    const auto check = [&](const MaterialTexture& expected, const MaterialTexture& got) {
        if (got.width != expected.width || got.height != expected.height ||
            got.depth != expected.depth || got.channels != expected.channels ||
            got.kind != expected.kind)
            fail(file.source,
                 "texture '" + expected.name + "' must be " + std::to_string(expected.width) + "x" +
                     std::to_string(expected.height) + "x" + std::to_string(expected.depth) +
                     " RGB " + storageName(expected.kind) + " for " + std::to_string(components) +
                     " components");
    };
    check(m->eigenTextures, eigen);
    check(m->weights, w);
    for (const MaterialTexture* t : {&eigen, &w})
        if (t->storedCount() != t->valueCount())
            fail(file.source, "texture '" + t->name + "' holds " +
                                  std::to_string(t->storedCount()) + " values, " +
                                  std::to_string(t->valueCount()) + " expected");
    if (eigen.kind == MaterialTexture::UNorm8) {
        // Held as bytes like a fit's (the loader gives k / 255.0f: exact).
        m->eigenTextures.bytes.resize(eigen.valueCount());
        for (std::size_t i = 0; i < eigen.valueCount(); ++i)
            m->eigenTextures.bytes[i] = std::uint8_t(std::lround(eigen.value(i) * 255.0f));
    } else {
        m->eigenTextures.data = eigen.data;
    }
    m->weights.data = w.data;
    m->prepareLookups();
    return m;
}

osg::ref_ptr<osg::StateSet> PcaMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addTexture(*stateSet, createFloatTexture(eigenTextures).get(), "pcaEigenTextures", 0);
    addTexture(*stateSet, createFloatTexture(weights).get(), "pcaWeights", 1);
    _viewLookup.addToStateSet(*stateSet, "pcaViewTable", 2);
    _lightLookup.addToStateSet(*stateSet, "pcaLightTable", 3);
    stateSet->addUniform(new osg::Uniform("pcaComponents", _components));
    stateSet->addUniform(new osg::Uniform("pcaTileColumns", _tileColumns));
    return stateSet;
}

namespace {
const bool registered = registerMethod([] {
    MethodInfo m;
    m.name = kPcaMethodName;
    m.description =
        "per-view Eigen-Textures (Sattler 2003): rank-c PCA of each view's light images, "
        "3x3 view/light interpolation; 3888 values / 3888 bytes per texel at 81 views, 16 "
        "components, unorm8";
    m.options = {
        OptionSpec::integer("components", 16, 1, OptionSpec::kNoLimit,
                            "Eigen-Textures per view (at most the lights, or 3 x texels if fewer)"),
        OptionSpec::choice("storage", "unorm8", {"unorm8", "half", "float"},
                           "Eigen-Texture precision: unorm8 is 1 byte per value, as seed 001 "
                           "Table 2 counts")};
    m.fit = [](const BtfSource& btf, const FitOptions& o) -> osg::ref_ptr<Material> {
        return PcaMaterial::fit(btf, o);
    };
    m.load = [](const FittedMaterial& f) -> osg::ref_ptr<Material> {
        return PcaMaterial::fromFile(f);
    };
    m.createInstance = []() -> osg::Object* { return new PcaMaterial; };
    // Per-texel Eigen-Texture values times per-direction weights; pca.frag blends the four
    // texels itself (tiled components).
    m.filtersLinearly = true;
    m.shaderCost = [](const Material& material) {
        // View + light lookups; 3 view-weight tests; per (view, light) pair (9): weight product
        // and test, bias fetch, per component: tile address 4, multiply-add 2 and 2 fetches;
        // weighted add 2.
        const PcaMaterial& m = static_cast<const PcaMaterial&>(material);
        const int c = m.components();
        const DirectionLookup::Cost v = m.viewLookup().cost(), l = m.lightLookup().cost();
        return ShaderCost::ofEvaluate(
            v.alu + l.alu + 3 + 9 * (4 + 6 * c), v.tex + l.tex + 9 * (1 + 2 * c),
            "ALU 54c+49+L, TEX 18c+9+T (c components; L = " + std::to_string(v.alu + l.alu) +
                ", T = " + std::to_string(v.tex + l.tex) + ": view and light lookups)");
    };
    // Linear in the light weights: an environment folds into each view's weights once per vertex
    // (PcaEnvironment.cpp, pca_environment.frag).
    EnvironmentHooks environment;
    environment.fold = [](const Material& material, const std::vector<glm::vec3>& g) {
        return foldPca(static_cast<const PcaMaterial&>(material), g);
    };
    environment.evaluateFolded = [](const Material& material, const std::vector<float>& folded,
                                    int x, int y, const glm::vec3& view) {
        return evaluateFoldedPca(static_cast<const PcaMaterial&>(material), folded, x, y, view);
    };
    environment.foldedStride = [](const Material& material) {
        const PcaMaterial& pca = static_cast<const PcaMaterial&>(material);
        return pca.views().size() * std::size_t(pca.components() + 1) * 3;
    };
    m.environment = std::move(environment);
    m.order = 40;
    m.quickFitOptions = "components=2";
    return m;
}());
}  // namespace

// The tables every texel shares; the other textures are per texel (remapMaterial).
[[maybe_unused]] const bool sharedTexturesDeclared = declareSharedTextures("pca", {"weights"});

}  // namespace osgBTF
