#include "materials/laf/Laf.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include <Imath/half.h>
#include <tbb/parallel_for.h>
#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/Progress.h"
#include "materials/MaterialState.h"
#include "materials/laf/Lobes.h"

namespace osgBTF {

// ---- model -----------------------------------------------------------------------------------

LafMaterial::LafMaterial(const LafMaterial& other, const osg::CopyOp& copyop)
    : Material(other, copyop),
      rhoD(other.rhoD),
      rhoS(other.rhoS),
      lobes(other.lobes),
      _lobes(other._lobes),
      _cosine(other._cosine) {}

void LafMaterial::assignFrom(const Material& other) {
    const LafMaterial& o = assignCommon<LafMaterial>(other);
    rhoD = o.rhoD;
    rhoS = o.rhoS;
    lobes = o.lobes;
    _lobes = o._lobes;
    _cosine = o._cosine;
}

osg::ref_ptr<LafMaterial> LafMaterial::create(int width, int height, int lobeCount,
                                              const DirectionSet& views,
                                              const DirectionSet& lights) {
    osg::ref_ptr<LafMaterial> m = new LafMaterial;
    m->setGeometry(width, height, views, lights);
    m->_lobes = lobeCount;
    m->_cosine = true;
    m->rhoD.assign(m->texelCount() * 3, 0.0f);
    m->rhoS.assign(m->texelCount() * 3, 0.0f);
    m->lobes.assign(m->texelCount() * lobeCount * lobes::kValuesPerLobe, 0.0f);
    for (std::size_t i = 3; i < m->lobes.size(); i += lobes::kValuesPerLobe) m->lobes[i] = 1.0f;
    return m;
}

// ---- fitter ----------------------------------------------------------------------------------

osg::ref_ptr<LafMaterial> LafMaterial::fit(const MeasuredBtf& btf, const FitOptions& options) {
    const OptionValues o = validateOptions("laf", options);
    const int k = o.integer("lobes"), iterations = o.integer("iterations");
    const bool cosine = o.flag("cosine");
    if (btf.empty() || btf.viewCount() == 0 || btf.lightCount() == 0)
        throw Error("laf: cannot fit an empty BTF");

    const auto start = std::chrono::steady_clock::now();
    osg::ref_ptr<LafMaterial> m = create(btf.width(), btf.height(), k, btf.views(), btf.lights());
    m->_cosine = cosine;
    std::vector<glm::vec3> views, lights;
    for (std::size_t v = 0; v < btf.viewCount(); ++v) views.push_back(btf.views().vector(v));
    for (std::size_t l = 0; l < btf.lightCount(); ++l) lights.push_back(btf.lights().vector(l));
    const lobes::PairTable pairs = lobes::makePairTable(views, lights);
    const std::size_t pairCount = pairs.products.size();
    const std::size_t texels = btf.texelCount();
    // The factor outside the bracket: l_z (as evaluate() forms it, in float) or 1.
    std::vector<double> outside(pairCount);
    for (std::size_t j = 0; j < pairCount; ++j)
        outside[j] = cosine ? double(lights[j % lights.size()].z) : 1.0;

    Progress progress("fitting laf", texels);
    std::atomic<long long> totalIterations{0};
    std::atomic<int> fallbacks{0};
    // Rows in parallel, texels of a row in order: each texel starts (among others) from its left
    // neighbour's fit, so results do not depend on the thread schedule.
    tbb::parallel_for(0, btf.height(), [&](int y) {
        std::vector<float> abrdf(pairCount * 3), model(pairCount * 3);
        std::vector<double> rgb(pairCount * 3), luminance(pairCount), sum(pairCount),
            scaledSum(pairCount);
        std::vector<double> neighbour;
        for (int x = 0; x < btf.width(); ++x) {
            const std::size_t t = std::size_t(y) * btf.width() + x;
            btf.abrdf(t, abrdf.data());
            for (std::size_t j = 0; j < pairCount; ++j) {
                for (int c = 0; c < 3; ++c) rgb[j * 3 + c] = abrdf[j * 3 + c];
                luminance[j] = (rgb[j * 3] + rgb[j * 3 + 1] + rgb[j * 3 + 2]) / 3.0;
            }
            const lobes::LuminanceFit fit =
                lobes::fitLuminance(pairs, luminance.data(), outside.data(), k, iterations,
                                    neighbour.empty() ? nullptr : &neighbour);
            neighbour = fit.params;
            totalIterations += fit.iterations;

            // Colours given the (unrounded) lobes, then the lobes rescaled so max(rho_s) = 1 uses
            // the 8-bit range fully, then everything rounded to its storage precision, and the
            // colours solved again against the lobes as stored.
            std::vector<double> lobeParams(fit.params.begin() + 1, fit.params.end());
            std::vector<double> lobesOnly = fit.params;
            lobesOnly[0] = 0.0;
            for (std::size_t j = 0; j < pairCount; ++j)
                scaledSum[j] =
                    outside[j] * lobes::luminanceModel(lobesOnly.data(), k, pairs.products[j]);
            double rhoSMax = 0;
            for (int c = 0; c < 3; ++c) {
                double a, b;
                lobes::nonNegativeLeastSquares2(outside.data(), scaledSum.data(), rgb.data() + c,
                                                pairCount, 3, a, b);
                rhoSMax = std::max(rhoSMax, b);
            }
            float stored[lobes::kMaxLobes * lobes::kValuesPerLobe];
            if (rhoSMax > 1e-6 && std::isfinite(rhoSMax)) {
                lobes::scaleLobes(lobeParams.data(), k, rhoSMax);
                for (int i = 0; i < k * lobes::kValuesPerLobe; ++i)
                    stored[i] = lobes::roundHalf(lobeParams[i]);
            } else {
                for (int i = 0; i < k * lobes::kValuesPerLobe; ++i)
                    stored[i] = i % lobes::kValuesPerLobe == 3 ? 1.0f : 0.0f;
            }
            for (std::size_t j = 0; j < pairCount; ++j) {
                sum[j] =
                    lobes::lobeSum(stored, k, views[pairs.pairView[j]], lights[j % lights.size()]);
                scaledSum[j] = outside[j] * sum[j];
            }
            float rd[3], rs[3];
            for (int c = 0; c < 3; ++c) {
                double a, b;
                lobes::nonNegativeLeastSquares2(outside.data(), scaledSum.data(), rgb.data() + c,
                                                pairCount, 3, a, b);
                rs[c] = lobes::quantizeUNorm8(b);
                double num = 0, den = 0;
                for (std::size_t j = 0; j < pairCount; ++j) {
                    num += outside[j] * (rgb[j * 3 + c] - double(rs[c]) * scaledSum[j]);
                    den += outside[j] * outside[j];
                }
                rd[c] = lobes::quantizeUNorm8(num / den);
            }
            for (std::size_t j = 0; j < pairCount; ++j)
                for (int c = 0; c < 3; ++c)
                    model[j * 3 + c] = (rd[c] + rs[c] * float(sum[j])) * float(outside[j]);
            const double error = lobes::texelError(rgb, model);

            // Guard against divergent fits (seed 001 4.4): never worse than the texel's best
            // rho_d alone (a lit texture with cosine=1, the mean colour with cosine=0).
            float mean[3];
            for (int c = 0; c < 3; ++c) {
                double num = 0, den = 0;
                for (std::size_t j = 0; j < pairCount; ++j) {
                    num += outside[j] * rgb[j * 3 + c];
                    den += outside[j] * outside[j];
                }
                mean[c] = lobes::quantizeUNorm8(num / den);
            }
            for (std::size_t j = 0; j < pairCount; ++j)
                for (int c = 0; c < 3; ++c) model[j * 3 + c] = mean[c] * float(outside[j]);
            if (!(error <= lobes::texelError(rgb, model))) {
                ++fallbacks;
                for (int c = 0; c < 3; ++c) {
                    rd[c] = mean[c];
                    rs[c] = 0.0f;
                }
                for (int i = 0; i < k * lobes::kValuesPerLobe; ++i)
                    stored[i] = i % lobes::kValuesPerLobe == 3 ? 1.0f : 0.0f;
            }
            for (int c = 0; c < 3; ++c) {
                m->rhoD[t * 3 + c] = rd[c];
                m->rhoS[t * 3 + c] = rs[c];
            }
            for (int i = 0; i < k; ++i)
                std::copy(stored + i * lobes::kValuesPerLobe,
                          stored + (i + 1) * lobes::kValuesPerLobe,
                          m->lobes.begin() + (i * texels + t) * lobes::kValuesPerLobe);
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
    return m;
}

// ---- CPU evaluator ---------------------------------------------------------------------------

glm::vec3 LafMaterial::evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const {
    const std::size_t t = std::size_t(y) * _width + x;
    float sum = 0.0f;
    for (int i = 0; i < _lobes; ++i)
        sum +=
            lobes::lobeValue(&lobes[(i * texelCount() + t) * lobes::kValuesPerLobe], view, light);
    return (glm::vec3(rhoD[t * 3], rhoD[t * 3 + 1], rhoD[t * 3 + 2]) +
            glm::vec3(rhoS[t * 3], rhoS[t * 3 + 1], rhoS[t * 3 + 2]) * sum) *
           (_cosine ? light.z : 1.0f);
}

// ---- memory, save / load ---------------------------------------------------------------------

MemoryFootprint LafMaterial::memory() const {
    // Counted from the textures as stored, so the numbers follow their declared storage kinds.
    return lobes::footprintOf(toFittedMaterial(), texelCount());
}

FittedMaterial LafMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["lobes"] = std::to_string(_lobes);
    file.parameters["cosine"] = _cosine ? "1" : "0";
    file.textures.push_back({"rhoD", _width, _height, 1, 3, MaterialTexture::UNorm8, rhoD});
    file.textures.push_back({"rhoS", _width, _height, 1, 3, MaterialTexture::UNorm8, rhoS});
    file.textures.push_back({"lobes", _width, _height, _lobes, 4, MaterialTexture::Half, lobes});
    return file;
}

osg::ref_ptr<LafMaterial> LafMaterial::fromFile(const FittedMaterial& file) {
    osg::ref_ptr<LafMaterial> m = new LafMaterial;
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
    return m;
}

// ---- StateSet --------------------------------------------------------------------------------

osg::ref_ptr<osg::StateSet> LafMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, methodName(), _width, _height);
    addTexture(
        *stateSet,
        createFloatTexture({"rhoD", _width, _height, 1, 3, MaterialTexture::UNorm8, rhoD}).get(),
        "lafRhoD", 0);
    addTexture(
        *stateSet,
        createFloatTexture({"rhoS", _width, _height, 1, 3, MaterialTexture::UNorm8, rhoS}).get(),
        "lafRhoS", 1);
    // The lobe slices stacked as one atlas (lobe i in rows [i h, (i + 1) h)): the same memory
    // layout as the [lobe][y][x] array, and a plain sampler2D for any lobe count, 1 included.
    addTexture(
        *stateSet,
        createFloatTexture({"lobes", _width, _height * _lobes, 1, 4, MaterialTexture::Half, lobes})
            .get(),
        "lafLobes", 2);
    stateSet->addUniform(new osg::Uniform("lafLobeCount", _lobes));
    stateSet->addUniform(new osg::Uniform("lafCosine", _cosine ? 1 : 0));
    return stateSet;
}

namespace {
const bool registered = registerMethod([] {
    MethodInfo m;
    m.name = "laf";
    m.description =
        "Lafortune lobes per texel (McAllister): rho_d + rho_s * sum_k (C . v*l)^n; RGB albedos, "
        "luminance lobes; 14 values / 22 bytes per texel at 2 lobes";
    m.options = {
        OptionSpec::integer("lobes", 2, 1, lobes::kMaxLobes, "number of Lafortune lobes"),
        OptionSpec::integer("iterations", 50, 1, 500, "Levenberg-Marquardt iterations per texel"),
        OptionSpec::flag("cosine", true,
                         "1: the bracket times l_z, the BRDF model times the foreshortening the "
                         "data contain; 0: seed 001 eq. 2 literally, no l_z")};
    m.fit = [](const MeasuredBtf& btf, const FitOptions& o) -> osg::ref_ptr<Material> {
        return LafMaterial::fit(btf, o);
    };
    m.load = [](const FittedMaterial& f) -> osg::ref_ptr<Material> {
        return LafMaterial::fromFile(f);
    };
    m.createInstance = []() -> osg::Object* { return new LafMaterial; };
    m.shaderCost = [](const Material& material) {
        // v*l 1; per lobe: row index 2, dot, test, pow, add; bracket 5. Fetches: lobes + rhoD,
        // rhoS.
        const int k = static_cast<const LafMaterial&>(material).lobeCount();
        return ShaderCost::ofEvaluate(6 + 6 * k, k + 2, "ALU 6k+16, TEX k+2 (k lobes)");
    };
    m.order = 10;
    return m;
}());
}  // namespace

}  // namespace osgBTF
