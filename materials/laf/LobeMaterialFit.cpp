// LobeMaterial's fitter (libosgBTFFit), shared by LAF and SLAF.
#include "materials/laf/LobeMaterial.h"

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>

#include <tbb/parallel_for.h>

#include "core/Error.h"
#include "core/Progress.h"
#include "materials/MaterialMath.h"
#include "materials/laf/Lobes.h"

namespace osgBTF {

// ---- fitter ----------------------------------------------------------------------------------
//
// Per texel: the luminance fit (Lobes.h), then (SLAF only) `rounds` alternations of
//   colours | lobes, T  (linear, closed form per channel)  and  lobes | T  (LM on the luminance,
//   each pair scaled by the view's mean T),
// then the storage rounding: lobes rescaled so max(rho_s) = 1 and rounded to half, colours
// solved again against the lobes as stored; with a table, colours normalised per channel so
// max(rho_d, rho_s) = 1 (T carries the scale; the product is unchanged); colours quantised to 8
// bits and rho_d re-solved given the quantised rho_s; with a table, finally T solved in closed
// form against the stored values and rounded to half. So the last step is optimal for exactly
// what the file and the GPU hold. With T fixed at 1 every product with T is exact, which makes
// the LAF path the SLAF computation without the T steps.

void LobeMaterial::fitLobes(const BtfSource& btf, int iterations, int rounds,
                            StoredValues* scaleOut) {
    const bool viewTable = scaleOut != nullptr;
    const int k = _lobes;
    const auto start = std::chrono::steady_clock::now();
    std::vector<glm::vec3> views, lights;
    for (std::size_t v = 0; v < btf.viewCount(); ++v) views.push_back(btf.views().vector(v));
    for (std::size_t l = 0; l < btf.lightCount(); ++l) lights.push_back(btf.lights().vector(l));
    const lobes::PairTable pairs = lobes::makePairTable(views, lights);
    const std::size_t pairCount = pairs.products.size(), viewCount = views.size(),
                      lightCount = lights.size(), texels = btf.texelCount();
    // The model's l_z factor (option cosine), as the evaluators form it (in float), or 1.
    std::vector<double> outside(pairCount);
    for (std::size_t j = 0; j < pairCount; ++j)
        outside[j] = _cosine ? double(lights[j % lightCount].z) : 1.0;

    Progress progress("fitting " + methodName(), texels);
    std::atomic<long long> totalIterations{0};
    std::atomic<int> fallbacks{0};
    // Rows in parallel, texels of a row in order: each texel starts (among others) from its left
    // neighbour's fit, so results do not depend on the thread schedule.
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
                nonNegativeLeastSquares2(f.data(), g.data(), rgb.data() + c, pairCount, 3, rd[c],
                                         rs[c]);
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
                    T[v * 3 + c] = roundToHalf ? double(roundHalf(value)) : value;
                }
        };
        auto lobeSums = [&](const std::vector<double>& params) {
            std::vector<double> lobesOnly = params;
            lobesOnly[0] = 0.0;
            for (std::size_t j = 0; j < pairCount; ++j)
                sum[j] = lobes::luminanceModel(lobesOnly.data(), k, pairs.products[j]);
        };

        // The whole row in one read: for factored input that is one decoding GEMM per row.
        std::vector<float> row(std::size_t(btf.width()) * pairCount * 3);
        btf.readAbrdfRange(std::size_t(y) * btf.width(), std::size_t(btf.width()), row.data());
        for (int x = 0; x < btf.width(); ++x) {
            const std::size_t t = std::size_t(y) * btf.width() + x;
            std::copy_n(row.data() + std::size_t(x) * pairCount * 3, pairCount * 3, abrdf.data());
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
            if (viewTable) {
                for (int r = 0; r < rounds; ++r) {
                    solveScale(false);
                    solveColours();
                    // Given colours and T the luminance is exactly A_j + B_j * S_j (A, B the
                    // channel means of T out (rho_d, rho_s)): LM on the lobes with target Y - A
                    // and scale B. The free ambient `a` starts at 0 and is dropped (rho_d
                    // re-solved next absorbs it).
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
                        spent += lobes::refineLuminance(pairs, pairTarget.data(), pairScale.data(),
                                                        k, iterations, fit.params);
                    }
                    lobeSums(fit.params);
                    solveColours();
                }
                solveScale(false);
                solveColours();
            }

            // Storage rounding (see above). solveColours overwrites rd and rs right after.
            std::vector<double> lobeParams(fit.params.begin() + 1, fit.params.end());
            const double rsMax = std::max({rs[0], rs[1], rs[2]});
            float stored[lobes::kMaxLobes * lobes::kValuesPerLobe];
            if (rsMax > 1e-6 && std::isfinite(rsMax)) {
                lobes::scaleLobes(lobeParams.data(), k, rsMax);
                for (int i = 0; i < k * lobes::kValuesPerLobe; ++i)
                    stored[i] = roundHalf(lobeParams[i]);
            } else {
                for (int i = 0; i < k * lobes::kValuesPerLobe; ++i)
                    stored[i] = i % lobes::kValuesPerLobe == 3 ? 1.0f : 0.0f;
            }
            for (std::size_t j = 0; j < pairCount; ++j)
                sum[j] =
                    lobes::lobeSum(stored, k, views[pairs.pairView[j]], lights[j % lightCount]);
            solveColours();
            for (int c = 0; c < 3; ++c) {
                const double norm = std::max(rd[c], rs[c]);
                if (viewTable && norm > 1e-9) {
                    rd[c] /= norm;
                    rs[c] /= norm;
                    for (std::size_t v = 0; v < viewCount; ++v) T[v * 3 + c] *= norm;
                }
                rs[c] = quantizeUNorm8(rs[c]);
                // rho_d again given the quantised rho_s and T: y - T rs S ~ rd T. The two
                // association orders of T rs S are the ones LAF and SLAF had as separate
                // fitters; kept so their files stay bit-identical.
                double num = 0, den = 0;
                for (std::size_t j = 0; j < pairCount; ++j) {
                    const double tj = T[pairs.pairView[j] * 3 + c] * outside[j];
                    const double fitted = viewTable ? tj * rs[c] * sum[j] : rs[c] * (tj * sum[j]);
                    num += tj * (rgb[j * 3 + c] - fitted);
                    den += tj * tj;
                }
                rd[c] = quantizeUNorm8(den > 0 ? num / den : 0.0);
            }
            if (viewTable) solveScale(true);
            for (std::size_t j = 0; j < pairCount; ++j)
                for (int c = 0; c < 3; ++c)
                    model[j * 3 + c] =
                        float(T[pairs.pairView[j] * 3 + c]) *
                        ((float(rd[c]) + float(rs[c]) * float(sum[j])) * float(outside[j]));
            const double error = texelError(rgb, model);

            // Divergence guard (Meseth et al. 2003 4.4): never worse than the best lit texture the
            // model holds: rho_s = 0 and, with a table, rho_d = 1 and T the best colour per view,
            // without one, rho_d the best colour (with cosine=0: mean colours instead).
            std::vector<double> fallbackT;
            float mean[3] = {1.0f, 1.0f, 1.0f};
            if (viewTable) {
                fallbackT.resize(viewCount * 3);
                for (std::size_t v = 0; v < viewCount; ++v)
                    for (int c = 0; c < 3; ++c) {
                        double num = 0, den = 0;
                        for (std::size_t l = 0; l < lightCount; ++l) {
                            const std::size_t j = v * lightCount + l;
                            num += rgb[j * 3 + c] * outside[j];
                            den += outside[j] * outside[j];
                        }
                        fallbackT[v * 3 + c] = roundHalf(num / den);
                    }
                for (std::size_t j = 0; j < pairCount; ++j)
                    for (int c = 0; c < 3; ++c)
                        model[j * 3 + c] =
                            float(fallbackT[pairs.pairView[j] * 3 + c]) * float(outside[j]);
            } else {
                for (int c = 0; c < 3; ++c) {
                    double num = 0, den = 0;
                    for (std::size_t j = 0; j < pairCount; ++j) {
                        num += outside[j] * rgb[j * 3 + c];
                        den += outside[j] * outside[j];
                    }
                    mean[c] = quantizeUNorm8(num / den);
                }
                for (std::size_t j = 0; j < pairCount; ++j)
                    for (int c = 0; c < 3; ++c) model[j * 3 + c] = mean[c] * float(outside[j]);
            }
            if (!(error <= texelError(rgb, model))) {
                ++fallbacks;
                if (viewTable) T = fallbackT;
                for (int c = 0; c < 3; ++c) {
                    rd[c] = mean[c];
                    rs[c] = 0.0;
                }
                for (int i = 0; i < k * lobes::kValuesPerLobe; ++i)
                    stored[i] = i % lobes::kValuesPerLobe == 3 ? 1.0f : 0.0f;
            }

            for (int c = 0; c < 3; ++c) {
                rhoD.set(t * 3 + c, float(rd[c]));
                rhoS.set(t * 3 + c, float(rs[c]));
            }
            for (int i = 0; i < k; ++i)
                lobes.write((i * texels + t) * lobes::kValuesPerLobe,
                            stored + i * lobes::kValuesPerLobe, lobes::kValuesPerLobe);
            if (viewTable)
                for (std::size_t v = 0; v < viewCount; ++v)
                    for (int c = 0; c < 3; ++c)
                        scaleOut->set((v * texels + t) * 3 + c, float(T[v * 3 + c]));
            totalIterations += spent;
            progress.advance();
        }
    });
    progress.finish();
    const double seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    fitInfo["seconds"] = std::to_string(seconds);
    fitInfo["iterations"] = std::to_string(totalIterations.load());
    fitInfo["fallbacks"] = std::to_string(fallbacks.load());
    fitInfo["lobes"] = std::to_string(k);
}

}  // namespace osgBTF
