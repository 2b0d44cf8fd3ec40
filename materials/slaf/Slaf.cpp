#include "materials/slaf/Slaf.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include <tbb/parallel_for.h>

#include "core/Error.h"
#include "core/Progress.h"
#include "materials/MaterialState.h"
#include "materials/laf/Lobes.h"

namespace osgBTF {

// ---- model -----------------------------------------------------------------------------------

SlafMaterial::SlafMaterial(const SlafMaterial& other, const osg::CopyOp& copyop)
    : Material(other, copyop),
      rhoD(other.rhoD),
      rhoS(other.rhoS),
      lobes(other.lobes),
      scale(other.scale),
      _lobes(other._lobes),
      _cosine(other._cosine),
      _viewTable(other._viewTable) {}

void SlafMaterial::assignFrom(const Material& other) {
    const SlafMaterial& o = assignCommon<SlafMaterial>(other);
    rhoD = o.rhoD;
    rhoS = o.rhoS;
    lobes = o.lobes;
    scale = o.scale;
    _lobes = o._lobes;
    _cosine = o._cosine;
    _viewTable = o._viewTable;
}

osg::ref_ptr<SlafMaterial> SlafMaterial::create(int width, int height, int lobeCount,
                                                const DirectionSet& views,
                                                const DirectionSet& lights) {
    osg::ref_ptr<SlafMaterial> m = new SlafMaterial;
    m->setGeometry(width, height, views, lights);
    m->_lobes = lobeCount;
    m->_cosine = true;
    m->rhoD.assign(m->texelCount() * 3, 0.0f);
    m->rhoS.assign(m->texelCount() * 3, 0.0f);
    m->lobes.assign(m->texelCount() * lobeCount * lobes::kValuesPerLobe, 0.0f);
    for (std::size_t i = 3; i < m->lobes.size(); i += lobes::kValuesPerLobe) m->lobes[i] = 1.0f;
    m->scale.assign(m->texelCount() * views.size() * 3, 1.0f);
    m->prepare();
    return m;
}

void SlafMaterial::prepare() {
    _viewTable = DirectionInterpolator(_views).bake(kDirectionTableResolution);
}

// ---- fitter ----------------------------------------------------------------------------------
//
// Per texel: a LAF fit (Lobes.h), then `rounds` alternations of
//   colours | lobes, T  (linear, closed form per channel)  and  lobes | T  (LM on the luminance,
//   each pair scaled by the view's mean T),
// then the storage rounding: lobes rescaled so max(rho_s) = 1 and rounded to half, colours
// normalised per channel so max(rho_d, rho_s) = 1 (T carries the scale; the product is unchanged)
// and quantised to 8 bits, and finally T solved in closed form against the stored values and
// rounded to half, so the last step is optimal for exactly what the file and the GPU hold.

osg::ref_ptr<SlafMaterial> SlafMaterial::fit(const MeasuredBtf& btf, const FitOptions& options) {
    const OptionValues o = validateOptions("slaf", options);
    const int k = o.integer("lobes"), iterations = o.integer("iterations"),
              rounds = o.integer("rounds");
    const bool cosine = o.flag("cosine");
    if (btf.empty() || btf.viewCount() == 0 || btf.lightCount() == 0)
        throw Error("slaf: cannot fit an empty BTF");
    if (btf.viewCount() < 3) throw Error("slaf: needs at least 3 view directions to interpolate T");

    const auto start = std::chrono::steady_clock::now();
    osg::ref_ptr<SlafMaterial> m = create(btf.width(), btf.height(), k, btf.views(), btf.lights());
    m->_cosine = cosine;
    std::vector<glm::vec3> views, lights;
    for (std::size_t v = 0; v < btf.viewCount(); ++v) views.push_back(btf.views().vector(v));
    for (std::size_t l = 0; l < btf.lightCount(); ++l) lights.push_back(btf.lights().vector(l));
    const lobes::PairTable pairs = lobes::makePairTable(views, lights);
    const std::size_t pairCount = pairs.products.size(), viewCount = views.size(),
                      lightCount = lights.size(), texels = btf.texelCount();
    // The model's l_z factor (LafMaterial's option cosine), as evaluate() forms it, or 1.
    std::vector<double> outside(pairCount);
    for (std::size_t j = 0; j < pairCount; ++j)
        outside[j] = cosine ? double(lights[j % lightCount].z) : 1.0;

    Progress progress("fitting slaf", texels);
    std::atomic<long long> totalIterations{0};
    std::atomic<int> fallbacks{0};
    tbb::parallel_for(0, btf.height(), [&](int y) {
        std::vector<float> abrdf(pairCount * 3), model(pairCount * 3);
        std::vector<double> rgb(pairCount * 3), luminance(pairCount), sum(pairCount),
            pairScale(pairCount), pairTarget(pairCount), f(pairCount), g(pairCount);
        std::vector<double> T(viewCount * 3);
        std::vector<double> neighbour;
        double rd[3], rs[3];

        // Colours given lobe sums and T (NNLS per channel).
        auto solveColours = [&] {
            for (int c = 0; c < 3; ++c) {
                for (std::size_t j = 0; j < pairCount; ++j) {
                    f[j] = T[pairs.pairView[j] * 3 + c] * outside[j];
                    g[j] = f[j] * sum[j];
                }
                lobes::nonNegativeLeastSquares2(f.data(), g.data(), rgb.data() + c, pairCount, 3,
                                                rd[c], rs[c]);
            }
        };
        // T per view and channel given colours and lobe sums: sum y M / sum M^2, M >= 0.
        auto solveScale = [&](bool roundToHalf) {
            for (std::size_t v = 0; v < viewCount; ++v)
                for (int c = 0; c < 3; ++c) {
                    double ym = 0, mm = 0;
                    for (std::size_t l = 0; l < lightCount; ++l) {
                        const std::size_t j = v * lightCount + l;
                        const double mj =
                            roundToHalf ? double((float(rd[c]) + float(rs[c]) * float(sum[j])) *
                                                 float(outside[j]))
                                        : (rd[c] + rs[c] * sum[j]) * outside[j];
                        ym += rgb[j * 3 + c] * mj;
                        mm += mj * mj;
                    }
                    double value = mm > 0 ? std::max(ym / mm, 0.0) : 0.0;
                    T[v * 3 + c] = roundToHalf ? double(lobes::roundHalf(value)) : value;
                }
        };
        auto lobeSums = [&](const std::vector<double>& params) {
            std::vector<double> lobesOnly = params;
            lobesOnly[0] = 0.0;
            for (std::size_t j = 0; j < pairCount; ++j)
                sum[j] = lobes::luminanceModel(lobesOnly.data(), k, pairs.products[j]);
        };

        for (int x = 0; x < btf.width(); ++x) {
            const std::size_t t = std::size_t(y) * btf.width() + x;
            btf.abrdf(t, abrdf.data());
            for (std::size_t j = 0; j < pairCount; ++j) {
                for (int c = 0; c < 3; ++c) rgb[j * 3 + c] = abrdf[j * 3 + c];
                luminance[j] = (rgb[j * 3] + rgb[j * 3 + 1] + rgb[j * 3 + 2]) / 3.0;
            }
            lobes::LuminanceFit fit =
                lobes::fitLuminance(pairs, luminance.data(), outside.data(), k, iterations,
                                    neighbour.empty() ? nullptr : &neighbour);
            neighbour = fit.params;
            long long spent = fit.iterations;

            std::fill(T.begin(), T.end(), 1.0);
            lobeSums(fit.params);
            solveColours();
            for (int r = 0; r < rounds; ++r) {
                solveScale(false);
                solveColours();
                // Given colours and T the luminance is exactly A_j + B_j * S_j (A, B the channel
                // means of T out (rho_d, rho_s)): LM on the lobes with target Y - A and scale B.
                // The free ambient `a` starts at 0 and is dropped (rho_d re-solved next absorbs
                // it).
                for (std::size_t j = 0; j < pairCount; ++j) {
                    double A = 0, B = 0;
                    for (int c = 0; c < 3; ++c) {
                        const double tj = T[pairs.pairView[j] * 3 + c] * outside[j];
                        A += tj * rd[c] / 3.0;
                        B += tj * rs[c] / 3.0;
                    }
                    pairTarget[j] = luminance[j] - A;
                    pairScale[j] = B;
                }
                if (std::max({rs[0], rs[1], rs[2]}) > 1e-6) {
                    fit.params[0] = 0.0;
                    spent += lobes::refineLuminance(pairs, pairTarget.data(), pairScale.data(), k,
                                                    iterations, fit.params);
                }
                lobeSums(fit.params);
                solveColours();
            }
            solveScale(false);
            solveColours();

            // Storage rounding (see above).
            std::vector<double> lobeParams(fit.params.begin() + 1, fit.params.end());
            const double rsMax = std::max({rs[0], rs[1], rs[2]});
            float stored[lobes::kMaxLobes * lobes::kValuesPerLobe];
            if (rsMax > 1e-6 && std::isfinite(rsMax)) {
                lobes::scaleLobes(lobeParams.data(), k, rsMax);
                for (int c = 0; c < 3; ++c) rs[c] /= rsMax;
                for (int i = 0; i < k * lobes::kValuesPerLobe; ++i)
                    stored[i] = lobes::roundHalf(lobeParams[i]);
            } else {
                for (int c = 0; c < 3; ++c) rs[c] = 0.0;
                for (int i = 0; i < k * lobes::kValuesPerLobe; ++i)
                    stored[i] = i % lobes::kValuesPerLobe == 3 ? 1.0f : 0.0f;
            }
            for (std::size_t j = 0; j < pairCount; ++j)
                sum[j] =
                    lobes::lobeSum(stored, k, views[pairs.pairView[j]], lights[j % lightCount]);
            solveColours();
            for (int c = 0; c < 3; ++c) {
                const double norm = std::max(rd[c], rs[c]);
                if (norm > 1e-9) {
                    rd[c] /= norm;
                    rs[c] /= norm;
                    for (std::size_t v = 0; v < viewCount; ++v) T[v * 3 + c] *= norm;
                }
                rs[c] = lobes::quantizeUNorm8(rs[c]);
                // rho_d again given the quantised rho_s and T: y - T rs S ~ rd T.
                double num = 0, den = 0;
                for (std::size_t j = 0; j < pairCount; ++j) {
                    const double tj = T[pairs.pairView[j] * 3 + c] * outside[j];
                    num += tj * (rgb[j * 3 + c] - tj * rs[c] * sum[j]);
                    den += tj * tj;
                }
                rd[c] = lobes::quantizeUNorm8(den > 0 ? num / den : 0.0);
            }
            solveScale(true);
            for (std::size_t j = 0; j < pairCount; ++j)
                for (int c = 0; c < 3; ++c)
                    model[j * 3 + c] =
                        float(T[pairs.pairView[j] * 3 + c]) *
                        ((float(rd[c]) + float(rs[c]) * float(sum[j])) * float(outside[j]));
            const double error = lobes::texelError(rgb, model);

            // Divergence guard: never worse than rho_d = 1, rho_s = 0, T = the best colour per
            // view (a lit texture per view with cosine=1, the view's mean colour with cosine=0).
            std::vector<double> fallbackT(viewCount * 3);
            for (std::size_t v = 0; v < viewCount; ++v)
                for (int c = 0; c < 3; ++c) {
                    double num = 0, den = 0;
                    for (std::size_t l = 0; l < lightCount; ++l) {
                        const std::size_t j = v * lightCount + l;
                        num += rgb[j * 3 + c] * outside[j];
                        den += outside[j] * outside[j];
                    }
                    fallbackT[v * 3 + c] = lobes::roundHalf(num / den);
                }
            for (std::size_t j = 0; j < pairCount; ++j)
                for (int c = 0; c < 3; ++c)
                    model[j * 3 + c] =
                        float(fallbackT[pairs.pairView[j] * 3 + c]) * float(outside[j]);
            if (!(error <= lobes::texelError(rgb, model))) {
                ++fallbacks;
                T = fallbackT;
                for (int c = 0; c < 3; ++c) {
                    rd[c] = 1.0;
                    rs[c] = 0.0;
                }
                for (int i = 0; i < k * lobes::kValuesPerLobe; ++i)
                    stored[i] = i % lobes::kValuesPerLobe == 3 ? 1.0f : 0.0f;
            }

            for (int c = 0; c < 3; ++c) {
                m->rhoD[t * 3 + c] = float(rd[c]);
                m->rhoS[t * 3 + c] = float(rs[c]);
            }
            for (int i = 0; i < k; ++i)
                std::copy(stored + i * lobes::kValuesPerLobe,
                          stored + (i + 1) * lobes::kValuesPerLobe,
                          m->lobes.begin() + (i * texels + t) * lobes::kValuesPerLobe);
            for (std::size_t v = 0; v < viewCount; ++v)
                for (int c = 0; c < 3; ++c)
                    m->scale[(v * texels + t) * 3 + c] = float(T[v * 3 + c]);
            totalIterations += spent;
            progress.advance();
        }
    });
    progress.finish();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    m->fitInfo["seconds"] = std::to_string(seconds);
    m->fitInfo["iterations"] = std::to_string(totalIterations.load());
    m->fitInfo["fallbacks"] = std::to_string(fallbacks.load());
    m->fitInfo["lobes"] = std::to_string(k);
    m->fitInfo["rounds"] = std::to_string(rounds);
    return m;
}

// ---- CPU evaluator ---------------------------------------------------------------------------

glm::vec3 SlafMaterial::evaluate(int x, int y, const glm::vec3& view,
                                 const glm::vec3& light) const {
    const std::size_t t = std::size_t(y) * _width + x, texels = texelCount();
    // The same baked lookup and blend order as shaders/slaf.frag.
    const InterpolationWeights w = DirectionInterpolator::lookupBaked(_viewTable, view);
    glm::vec3 T(0.0f);
    for (int i = 0; i < 3; ++i) {
        const float* s = &scale[(std::size_t(w.index[i]) * texels + t) * 3];
        T += w.weight[i] * glm::vec3(s[0], s[1], s[2]);
    }
    float sum = 0.0f;
    for (int i = 0; i < _lobes; ++i)
        sum += lobes::lobeValue(&lobes[(i * texels + t) * lobes::kValuesPerLobe], view, light);
    return T * ((glm::vec3(rhoD[t * 3], rhoD[t * 3 + 1], rhoD[t * 3 + 2]) +
                 glm::vec3(rhoS[t * 3], rhoS[t * 3 + 1], rhoS[t * 3 + 2]) * sum) *
                (_cosine ? light.z : 1.0f));
}

void SlafMaterial::evaluateMeasured(std::size_t t, float* abrdf) const {
    const std::size_t texels = texelCount();
    const glm::vec3 rd(rhoD[t * 3], rhoD[t * 3 + 1], rhoD[t * 3 + 2]),
        rs(rhoS[t * 3], rhoS[t * 3 + 1], rhoS[t * 3 + 2]);
    for (std::size_t v = 0; v < _views.size(); ++v) {
        const glm::vec3 view = _views.vector(v);
        const float* s = &scale[(v * texels + t) * 3];
        const glm::vec3 T(s[0], s[1], s[2]);
        for (std::size_t l = 0; l < _lights.size(); ++l) {
            const glm::vec3 light = _lights.vector(l);
            float sum = 0.0f;
            for (int i = 0; i < _lobes; ++i)
                sum +=
                    lobes::lobeValue(&lobes[(i * texels + t) * lobes::kValuesPerLobe], view, light);
            const glm::vec3 value = T * ((rd + rs * sum) * (_cosine ? light.z : 1.0f));
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
    }
}

// ---- memory, save / load ---------------------------------------------------------------------

MemoryFootprint SlafMaterial::memory() const {
    // Counted from the textures as stored (the view table is shared and not counted, as in
    // seed 001: it is 65 x 65 x 6 floats for any material size).
    return lobes::footprintOf(toFittedMaterial(), texelCount());
}

FittedMaterial SlafMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["lobes"] = std::to_string(_lobes);
    file.parameters["cosine"] = _cosine ? "1" : "0";
    file.textures.push_back({"rhoD", _width, _height, 1, 3, MaterialTexture::UNorm8, rhoD});
    file.textures.push_back({"rhoS", _width, _height, 1, 3, MaterialTexture::UNorm8, rhoS});
    file.textures.push_back({"lobes", _width, _height, _lobes, 4, MaterialTexture::Half, lobes});
    file.textures.push_back(
        {"scale", _width, _height, int(_views.size()), 3, MaterialTexture::Half, scale});
    return file;
}

osg::ref_ptr<SlafMaterial> SlafMaterial::fromFile(const FittedMaterial& file) {
    osg::ref_ptr<SlafMaterial> m = new SlafMaterial;
    m->readCommon(file);
    try {
        m->_lobes = std::stoi(file.parameter("lobes"));
    } catch (const std::invalid_argument&) {
        fail(file.source, "parameter 'lobes' is not an integer");
    }
    if (m->_lobes < 1 || m->_lobes > lobes::kMaxLobes)
        fail(file.source, "parameter 'lobes' must be between 1 and 8");
    const std::string& cosine = file.parameter("cosine");
    if (cosine != "0" && cosine != "1") fail(file.source, "parameter 'cosine' must be 0 or 1");
    m->_cosine = cosine == "1";
    if (m->_views.size() < 3) fail(file.source, "slaf needs at least 3 view directions");
    auto read = [&](const std::string& name, int depth, int channels) {
        const MaterialTexture& t = file.texture(name);
        if (t.width != m->_width || t.height != m->_height || t.depth != depth ||
            t.channels != channels)
            fail(file.source, "texture '" + name + "' must be " + std::to_string(m->_width) + "x" +
                                  std::to_string(m->_height) + "x" + std::to_string(depth) +
                                  " with " + std::to_string(channels) + " channels");
        return t.data;
    };
    m->rhoD = read("rhoD", 1, 3);
    m->rhoS = read("rhoS", 1, 3);
    m->lobes = read("lobes", m->_lobes, 4);
    m->scale = read("scale", int(m->_views.size()), 3);
    m->prepare();
    return m;
}

// ---- StateSet --------------------------------------------------------------------------------

osg::ref_ptr<osg::StateSet> SlafMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, methodName(), _width, _height);
    addTexture(
        *stateSet,
        createFloatTexture({"rhoD", _width, _height, 1, 3, MaterialTexture::UNorm8, rhoD}).get(),
        "slafRhoD", 0);
    addTexture(
        *stateSet,
        createFloatTexture({"rhoS", _width, _height, 1, 3, MaterialTexture::UNorm8, rhoS}).get(),
        "slafRhoS", 1);
    // Lobe slices as an atlas (see LafMaterial::createStateSet); T as a 2D array, one layer per
    // measured view (81 or 151 layers, well below GL's 2048).
    addTexture(
        *stateSet,
        createFloatTexture({"lobes", _width, _height * _lobes, 1, 4, MaterialTexture::Half, lobes})
            .get(),
        "slafLobes", 2);
    addTexture(*stateSet,
               createFloatTexture(
                   {"scale", _width, _height, int(_views.size()), 3, MaterialTexture::Half, scale})
                   .get(),
               "slafScale", 3);
    addDirectionTable(*stateSet, _viewTable, "slafView", 4, 5);
    stateSet->addUniform(new osg::Uniform("slafLobeCount", _lobes));
    stateSet->addUniform(new osg::Uniform("slafCosine", _cosine ? 1 : 0));
    return stateSet;
}

namespace {
const bool registered = registerMethod([] {
    MethodInfo m;
    m.name = "slaf";
    m.description =
        "scaled Lafortune lobes (Daubert): T(v) * (rho_d + rho_s * sum_k (C . v*l)^n), T an RGB "
        "table over the measured views; 257 values / 508 bytes per texel at 81 views, 2 lobes";
    m.options = {
        OptionSpec::integer("lobes", 2, 1, lobes::kMaxLobes, "number of Lafortune lobes"),
        OptionSpec::integer("iterations", 50, 1, 500,
                            "Levenberg-Marquardt iterations per texel and round"),
        OptionSpec::integer("rounds", 2, 0, 10,
                            "alternations between the view table T and the lobes"),
        OptionSpec::flag("cosine", true,
                         "1: the bracket times l_z; 0: seed 001 eq. 4 literally (see laf)")};
    m.fit = [](const MeasuredBtf& btf, const FitOptions& o) -> osg::ref_ptr<Material> {
        return SlafMaterial::fit(btf, o);
    };
    m.load = [](const FittedMaterial& f) -> osg::ref_ptr<Material> {
        return SlafMaterial::fromFile(f);
    };
    m.createInstance = []() -> osg::Object* { return new SlafMaterial; };
    m.shaderCost = [](const Material& material) {
        // View lookup; T: 3 multiply-adds and 3 fetches; v*l 1; lobes as LAF; bracket 5; T* 1.
        const int k = static_cast<const SlafMaterial&>(material).lobeCount();
        return ShaderCost::ofEvaluate(ShaderCost::kLookupAlu + 6 + 1 + 6 * k + 5 + 1,
                                      ShaderCost::kLookupTex + 3 + k + 2,
                                      "ALU 6k+34, TEX k+7 (k lobes)");
    };
    m.order = 20;
    return m;
}());
}  // namespace

}  // namespace osgBTF
