// RF's fit (libosgBTFFit): per texel and view, Levenberg-Marquardt (Ceres' TinySolver) on the
// lobes of the luminance or of each colour channel, then the colours in closed form.
#include "materials/MethodOptions.h"
#include "materials/rf/Rf.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>

#include <ceres/tiny_solver.h>
#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>
#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/Progress.h"
#include "materials/rf/RfValues.h"

namespace osgBTF {

namespace {
using rf::lobeValue;
/** What the file and the GPU hold of a value: rf's 8-bit rho_d and half rho_v and lobes. */
float toHalf(float v) {
    return StoredValues::round(MaterialTexture::Half, v);
}
float toUNorm8(float v) {
    return StoredValues::round(MaterialTexture::UNorm8, v);
}
}  // namespace

// ---- fitter ----------------------------------------------------------------------------------

namespace {

/** The lobe sum of one (texel, view) minus its target luminance, over the measured lights, with
 *  the analytic Jacobian (TinySolver's functor interface). Parameters per lobe: a, b, c and u,
 *  with n = nMin + (nMax - nMin) * sigmoid(u): the exponent stays in its valid range without
 *  bound constraints, which Levenberg-Marquardt in TinySolver does not have. */
struct LobeResidual {
    using Scalar = double;
    enum { NUM_RESIDUALS = Eigen::Dynamic, NUM_PARAMETERS = Eigen::Dynamic };

    const double* lights = nullptr;  ///< xyz per light
    const double* target = nullptr;  ///< luminance per light
    int lightCount = 0;
    int lobes = 0;
    double nMin = 0, nMax = 0;

    int NumResiduals() const { return lightCount; }
    int NumParameters() const { return 4 * lobes; }

    double exponent(double u) const { return nMin + (nMax - nMin) / (1.0 + std::exp(-u)); }
    double parameterOf(double n) const {
        // Keep starts off the saturated ends of the sigmoid, where the gradient vanishes.
        const double margin = 0.01 * (nMax - nMin);
        n = std::clamp(n, nMin + margin, nMax - margin);
        return -std::log((nMax - nMin) / (n - nMin) - 1.0);
    }

    bool operator()(const double* p, double* r, double* jacobian) const {
        for (int l = 0; l < lightCount; ++l) r[l] = -target[l];
        for (int i = 0; i < lobes; ++i) {
            const double* q = p + 4 * i;
            const double n = exponent(q[3]);
            const double dn = (n - nMin) * (nMax - n) / (nMax - nMin);
            double* J = jacobian ? jacobian + std::size_t(4 * i) * lightCount : nullptr;
            for (int l = 0; l < lightCount; ++l) {
                const double* L = lights + 3 * l;
                const double base = q[0] * L[0] + q[1] * L[1] + q[2] * L[2];
                double f = 0, logBase = 0, slope = 0;
                if (base > 1e-12) {
                    // Single precision is plenty for data known to ~1e-3 and twice as fast
                    // (exp/log are most of the fit's time).
                    logBase = std::log(float(base));
                    f = std::exp(float(n * logBase));
                    slope = n * f / base;
                }
                r[l] += f;
                if (J) {
                    J[l] = slope * L[0];
                    J[lightCount + l] = slope * L[1];
                    J[2 * lightCount + l] = slope * L[2];
                    J[3 * lightCount + l] = f * logBase * dn;
                }
            }
        }
        return true;
    }
};

using Solver = ceres::TinySolver<LobeResidual>;
using Vector = Eigen::VectorXd;

/** Fits the lobes of one texel in all measured views and then its colours. One per TBB task.
 *  A lobe group is the k lobes of one view (luminance) or of one view and colour channel (rgb):
 *  group g = view * channels + channel, the order of the lobe layers. */
class TexelFitter {
public:
    TexelFitter(const BtfSource& btf, const RfMaterial::Settings& settings)
        : _settings(settings),
          _views(btf.viewCount()),
          _lights(btf.lightCount()),
          _channels(settings.variant.rgb ? 3 : 1),
          _groups(_views * _channels),
          _lightXyz(_lights * 3),
          _luminance(_lights),
          _residual(_lights) {
        for (std::size_t l = 0; l < _lights; ++l)
            for (int a = 0; a < 3; ++a) _lightXyz[l * 3 + a] = btf.lights().vector(l)[a];
        _problem.lights = _lightXyz.data();
        _problem.target = _luminance.data();
        _problem.lightCount = int(_lights);
        _problem.lobes = settings.lobes;
        _problem.nMin = RfMaterial::kMinExponent;
        _problem.nMax = settings.maxExponent;
        _solver.options.max_num_iterations = settings.iterations + 1;  // counts the start
        _solver.options.parameter_tolerance = 1e-7;
        for (std::size_t v = 0; v < _views; ++v) {
            const glm::vec3 d = btf.views().vector(v);
            _mirror.push_back(glm::normalize(glm::dvec3(-d.x, -d.y, std::max(d.z, 0.05f))));
        }
    }

    std::uint64_t iterations = 0;  ///< LM iterations over all solves
    std::uint64_t fallbacks = 0;   ///< (texel, lobe group) fits that kept their initialisation

    /** abrdf: the texel's [view][light][rgb] values; previous: the left neighbour's lobe
     *  parameters per lobe group (a warm start) or empty. Writes the texel's final, rounded model
     *  into m. */
    void fitTexel(const float* abrdf, std::vector<Vector>& previous, RfMaterial& m,
                  std::size_t texel) {
        // Pass 1: rho_d = 0, the lobes see the data as measured and the closed form finds any
        // light-independent floor. (Starting at the texel's minimum instead leaves the lobes
        // to fit l_z - min(l_z), which no lobe without an offset can: nearly Lambertian texels
        // came out worse than the Lambert baseline.) Pass 2, where the texel's lowest value is
        // at least 0.01: the lobes fitted to the data minus that minimum (what recovers a model
        // with a real floor), pass 1 as a second start; the better pass (total squared error of
        // the stored model) is kept. Without the diffuse term there is no floor to fit above.
        const double zero[3] = {0, 0, 0};
        std::vector<Vector> first(_groups);
        std::vector<float> fitted = fitLobes(abrdf, zero, previous, first);
        if (!previous.empty()) previous = first;
        std::vector<float> kept = fitted;  // storeTexel rescales its input in place
        const double error1 = storeTexel(abrdf, fitted, m, texel);
        if (!_settings.variant.diffuse) return;
        double floor[3] = {std::numeric_limits<double>::max(), std::numeric_limits<double>::max(),
                           std::numeric_limits<double>::max()};
        for (std::size_t i = 0; i < _views * _lights; ++i)
            for (int c = 0; c < 3; ++c) floor[c] = std::min(floor[c], double(abrdf[i * 3 + c]));
        if (std::max({floor[0], floor[1], floor[2]}) >= 0.01) {
            std::vector<Vector> second(_groups);
            std::vector<float> refitted = fitLobes(abrdf, floor, first, second);
            if (storeTexel(abrdf, refitted, m, texel) > error1) {
                storeTexel(abrdf, kept, m, texel);
            } else if (!previous.empty()) {
                previous = second;
            }
        }
    }

private:
    /** The lobes of every lobe group of one texel for its data minus `floor`; `starts` holds a
     *  start per group (or empty vectors), `results` receives the LM parameters. Returns
     *  (a, b, c, n) per group and lobe. */
    std::vector<float> fitLobes(const float* abrdf, const double floor[3],
                                const std::vector<Vector>& starts, std::vector<Vector>& results) {
        const int k = _settings.lobes;
        std::vector<float> fitted(_groups * std::size_t(k) * 4);
        for (std::size_t g = 0; g < _groups; ++g) {
            const std::size_t v = g / _channels;
            const float* y = abrdf + v * _lights * 3;
            // Luminance lobes fit the mean of the channels (rho_v supplies the colour); rgb
            // lobes fit their own channel.
            if (_channels == 1) {
                for (std::size_t l = 0; l < _lights; ++l)
                    _luminance[l] = ((y[l * 3] - floor[0]) + (y[l * 3 + 1] - floor[1]) +
                                     (y[l * 3 + 2] - floor[2])) /
                                    3.0;
            } else {
                const std::size_t c = g % _channels;
                for (std::size_t l = 0; l < _lights; ++l) _luminance[l] = y[l * 3 + c] - floor[c];
            }
            const Vector* start = g < starts.size() && starts[g].size() ? &starts[g] : nullptr;
            const Vector best = fitView(v, start);
            results[g] = best;
            for (int i = 0; i < k; ++i) {
                float* out = &fitted[(g * k + i) * 4];
                for (int a = 0; a < 3; ++a) out[a] = float(best[4 * i + a]);
                out[3] = float(_problem.exponent(best[4 * i + 3]));
            }
        }
        return fitted;
    }

    /** The lobes of one view for the target in _luminance (luminance or one channel): up to
     *  `starts` initialisations, each refined by LM; the best valid result (finite, peak
     *  bounded) wins. */
    Vector fitView(std::size_t v, const Vector* neighbour) {
        double maxY = 0, energy = 0;
        for (double y : _luminance) {
            maxY = std::max(maxY, y);
            energy += y * y;
        }
        // Divergent fits (Meseth et al. 2003 4.4) show up as lobes whose peak, between the measured
        // lights, is far above anything measured: refuse those.
        const double peakBound = 2.0 * maxY + 1e-3;
        _solver.options.function_tolerance = 1e-7 * energy + 1e-30;
        _solver.options.gradient_tolerance = 1e-12 * (maxY + 1e-6);

        Vector best = greedyStart(maxY, nullptr);
        if (maxY <= 1e-6) return best;  // black in this view: the start is as good as any
        double bestCost = cost(best);
        const double good = 1e-4 * energy;  // relative rms residual 1 %: no need for more starts
        bool improved = false, mirrorTried = false;
        for (int s = 0; s < _settings.starts; ++s) {
            Vector x;
            if (s == 0) {
                x = best;
            } else if (s == 1 && neighbour && neighbour->size() == best.size()) {
                x = *neighbour;
            } else if (_settings.lobes > 1 && !mirrorTried) {
                x = greedyStart(maxY, &_mirror[v]);
                mirrorTried = true;
            } else {
                continue;
            }
            const auto& summary = _solver.Solve(_problem, &x);
            iterations += std::uint64_t(std::max(summary.iterations, 0));
            const double c = valid(x, peakBound) ? cost(x) : std::numeric_limits<double>::max();
            if (c < bestCost) {
                best = x;
                bestCost = c;
                improved = true;
            }
            if (bestCost <= good) break;
        }
        if (!improved) ++fallbacks;
        return best;
    }

    double cost(const Vector& x) {
        _problem(x.data(), _residual.data(), nullptr);
        double sum = 0;
        for (double r : _residual) sum += r * r;
        return std::isfinite(sum) ? sum : std::numeric_limits<double>::max();
    }

    bool valid(const Vector& x, double peakBound) const {
        double peak = 0;
        for (int i = 0; i < _settings.lobes; ++i) {
            const double a = x[4 * i], b = x[4 * i + 1], c = x[4 * i + 2], u = x[4 * i + 3];
            if (!std::isfinite(a) || !std::isfinite(b) || !std::isfinite(c) || !std::isfinite(u))
                return false;
            const double length = std::sqrt(a * a + b * b + c * c);
            if (length == 0) continue;
            // Highest base over the upper hemisphere: the lobe axis, or the horizon below it.
            const double z = c / length;
            const double reach = z >= 0 ? length : length * std::sqrt(std::max(0.0, 1 - z * z));
            peak += std::pow(reach, _problem.exponent(u));
        }
        return std::isfinite(peak) && peak <= peakBound;
    }

    /** Lobes placed one after the other on what the previous ones leave unexplained: a broad
     *  lobe (n = 1) along the luminance-weighted mean light, then narrower ones (n = 8, 16, ...)
     *  at the brightest remaining light, or the first of them along `second` (the mirror
     *  direction of the view, where a specular peak sits). Magnitudes in closed form. */
    Vector greedyStart(double maxY, const glm::dvec3* second) {
        const int k = _settings.lobes;
        Vector x(4 * k);
        for (std::size_t l = 0; l < _lights; ++l) _residual[l] = _luminance[l];
        const double smallest = 1e-3 * maxY + 1e-9, largest = std::max(maxY, smallest);
        for (int i = 0; i < k; ++i) {
            glm::dvec3 d(0, 0, 1);
            double n = 1.0;
            if (i == 0) {
                glm::dvec3 sum(0);
                for (std::size_t l = 0; l < _lights; ++l)
                    sum += std::max(_residual[l], 0.0) * light(l);
                if (glm::length(sum) > 1e-12) d = glm::normalize(sum);
            } else {
                n = std::min(8.0 * double(1 << std::min(i - 1, 10)), 0.5 * _problem.nMax);
                if (i == 1 && second) {
                    d = *second;
                } else {
                    std::size_t peak = 0;
                    for (std::size_t l = 1; l < _lights; ++l)
                        if (_residual[l] > _residual[peak]) peak = l;
                    d = light(peak);
                }
            }
            n = _problem.exponent(_problem.parameterOf(n));
            double sumRf = 0, sumFf = 0;
            std::vector<double>& f = _lobe;
            f.resize(_lights);
            for (std::size_t l = 0; l < _lights; ++l) {
                f[l] = std::pow(std::max(0.0, glm::dot(d, light(l))), n);
                sumRf += _residual[l] * f[l];
                sumFf += f[l] * f[l];
            }
            const double magnitude =
                std::clamp(sumFf > 0 ? sumRf / sumFf : smallest, smallest, largest);
            for (std::size_t l = 0; l < _lights; ++l) _residual[l] -= magnitude * f[l];
            const glm::dvec3 abc = std::pow(magnitude, 1.0 / n) * d;
            x[4 * i] = abc.x;
            x[4 * i + 1] = abc.y;
            x[4 * i + 2] = abc.z;
            x[4 * i + 3] = _problem.parameterOf(n);
        }
        return x;
    }

    glm::dvec3 light(std::size_t l) const {
        return {_lightXyz[l * 3], _lightXyz[l * 3 + 1], _lightXyz[l * 3 + 2]};
    }

    /** Rounds the lobes to half, then solves the colour terms in closed form with exactly those
     *  lobes: per channel, rho_d over all views jointly with rho_v per view (rho_v eliminated:
     *  rho_v = A_v - rho_d B_v, leaving a 1-D least-squares problem in rho_d), rho_d rounded to
     *  8 bits, then rho_v with the rounded rho_d, rounded to half (rho_d = 0 without the diffuse
     *  term). Channel c uses the lobe sum of its own group with rgb lobes. Returns the texel's
     *  total squared error of the stored model. */
    double storeTexel(const float* abrdf, std::vector<float>& fitted, RfMaterial& m,
                      std::size_t texel) {
        const int k = _settings.lobes;
        const std::size_t texels = m.texelCount();
        const float nLow = toHalf(float(RfMaterial::kMinExponent));
        const float nHigh = toHalf(float(_settings.maxExponent));
        std::vector<float> S(_groups * _lights);
        std::vector<glm::vec3> L(_lights);
        for (std::size_t l = 0; l < _lights; ++l) L[l] = glm::vec3(light(l));
        for (std::size_t g = 0; g < _groups; ++g) {
            float* p = &fitted[g * k * 4];
            // Scale the lobes so that their sum peaks at 1 over the measured lights: rho_v then
            // carries the magnitude and the lobe bases stay near 1, where half is most precise.
            float peak = 0;
            for (std::size_t l = 0; l < _lights; ++l) {
                float s = 0;
                for (int i = 0; i < k; ++i) s += lobeValue(p + 4 * i, L[l]);
                peak = std::max(peak, s);
            }
            if (peak > 0 && std::isfinite(peak))
                for (int i = 0; i < k; ++i)
                    for (int a = 0; a < 3; ++a)
                        p[4 * i + a] *= std::pow(peak, -1.0f / p[4 * i + 3]);
            for (int i = 0; i < k; ++i) {
                for (int a = 0; a < 3; ++a) p[4 * i + a] = toHalf(p[4 * i + a]);
                p[4 * i + 3] = std::clamp(toHalf(p[4 * i + 3]), nLow, nHigh);
                m.lobes.write(((g * k + i) * texels + texel) * 4, p + 4 * i, 4);
            }
            for (std::size_t l = 0; l < _lights; ++l) {
                float s = 0;
                for (int i = 0; i < k; ++i) s += lobeValue(p + 4 * i, L[l]);
                S[g * _lights + l] = s;
            }
        }
        double squaredError = 0;
        for (int c = 0; c < 3; ++c) {
            // Lobe sum of view v for this channel: S[(v * _channels + own) * _lights + l].
            const std::size_t own = _channels == 1 ? 0 : std::size_t(c);
            const float* Sc = &S[own * _lights];
            const std::size_t stride = _channels * _lights;
            std::vector<double> A(_views, 0.0), B(_views, 0.0), SS(_views, 0.0);
            for (std::size_t v = 0; v < _views; ++v) {
                double sy = 0, s1 = 0, ss = 0;
                for (std::size_t l = 0; l < _lights; ++l) {
                    const double s = Sc[v * stride + l];
                    sy += s * abrdf[(v * _lights + l) * 3 + c];
                    s1 += s;
                    ss += s * s;
                }
                SS[v] = ss;
                if (ss > 1e-20) {
                    A[v] = sy / ss;
                    B[v] = s1 / ss;
                }
            }
            float d = 0;
            if (_settings.variant.diffuse) {
                double eg = 0, gg = 0;
                for (std::size_t v = 0; v < _views; ++v)
                    for (std::size_t l = 0; l < _lights; ++l) {
                        const double s = Sc[v * stride + l];
                        const double g = 1.0 - B[v] * s;
                        eg += (abrdf[(v * _lights + l) * 3 + c] - A[v] * s) * g;
                        gg += g * g;
                    }
                d = toUNorm8(gg > 1e-12 ? float(eg / gg) : 0.0f);
                m.rhoD.set(texel * 3 + c, d);
            }
            for (std::size_t v = 0; v < _views; ++v) {
                double sy = 0;
                for (std::size_t l = 0; l < _lights; ++l)
                    sy += Sc[v * stride + l] * (abrdf[(v * _lights + l) * 3 + c] - d);
                const float rho = SS[v] > 1e-20 ? toHalf(float(std::max(0.0, sy / SS[v]))) : 0.0f;
                m.rhoV.set((v * texels + texel) * 3 + c, rho);
                for (std::size_t l = 0; l < _lights; ++l) {
                    const double r =
                        abrdf[(v * _lights + l) * 3 + c] - d - rho * Sc[v * stride + l];
                    squaredError += r * r;
                }
            }
        }
        return squaredError;
    }

    RfMaterial::Settings _settings;
    std::size_t _views, _lights;
    std::size_t _channels;  ///< lobe channels: 1 (luminance) or 3 (rgb)
    std::size_t _groups;    ///< lobe groups per texel: views x channels
    std::vector<double> _lightXyz, _luminance, _residual, _lobe;
    std::vector<glm::dvec3> _mirror;
    LobeResidual _problem;
    Solver _solver;
};

}  // namespace

osg::ref_ptr<RfMaterial> RfMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const Settings settings = settingsFrom(options);
    if (btf.empty()) throw Error("rf: the measured BTF is empty");
    osg::ref_ptr<RfMaterial> m = create(btf.width(), btf.height(), btf.views(), btf.lights(),
                                        settings.lobes, settings.variant);

    // Blocks of consecutive texels (along rows): gathering their ABRDFs reads each measured
    // image in contiguous runs, and each texel can start from its left neighbour's lobes.
    const std::size_t blockSize = 32, texels = btf.texelCount();
    const std::size_t views = btf.viewCount(), lights = btf.lightCount();
    const std::size_t groups = views * std::size_t(m->lobeChannels());
    const std::size_t blocks = (texels + blockSize - 1) / blockSize;
    std::atomic<std::uint64_t> iterations{0}, fallbacks{0};
    Progress progress("rf fit", texels);
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, blocks, 1), [&](const auto& range) {
        TexelFitter fitter(btf, settings);
        std::vector<float> abrdfs(blockSize * views * lights * 3);
        for (std::size_t b = range.begin(); b != range.end(); ++b) {
            const std::size_t first = b * blockSize, count = std::min(blockSize, texels - first);
            btf.readAbrdfRange(first, count, abrdfs.data());
            std::vector<Vector> previous(groups);
            for (std::size_t t = 0; t < count; ++t) {
                // A new row has no left neighbour in this block.
                if ((first + t) % std::size_t(btf.width()) == 0) previous.assign(groups, Vector());
                fitter.fitTexel(&abrdfs[t * views * lights * 3], previous, *m, first + t);
            }
            progress.advance(count);
        }
        iterations += fitter.iterations;
        fallbacks += fitter.fallbacks;
    });
    progress.finish();

    std::ostringstream seconds, meanIterations;
    seconds << progress.elapsedSeconds();
    meanIterations << double(iterations) / double(texels * groups);
    m->fitInfo["seconds"] = seconds.str();
    m->fitInfo["iterations"] = meanIterations.str();
    m->fitInfo["fallbacks"] = std::to_string(fallbacks.load());
    m->fitInfo["lobes"] = std::to_string(settings.lobes);
    std::ostringstream maxExponent;
    maxExponent << settings.maxExponent;
    m->fitInfo["max-exponent"] = maxExponent.str();
    m->fitInfo["diffuse"] = settings.variant.diffuse ? "1" : "0";
    m->fitInfo["colour"] = settings.variant.rgb ? "rgb" : "luminance";
    return m;
}

namespace {
// The fit hook of the method registered in Rf.cpp (libosgBTF).
const bool rfFitterRegistered = registerFitterClass<RfMaterial>();
}  // namespace

}  // namespace osgBTF
