#include "materials/laf/Lobes.h"

#include <algorithm>
#include <limits>
#include <memory>
#include <numeric>

#include <ceres/ceres.h>

#include "core/Error.h"

namespace osgBTF::lobes {

namespace {

/** Every `stride`-th pair, about `target` of them; the stride is made coprime with the light count
 *  so the subset walks through all lights over the views instead of repeating a few. */
std::vector<int> strideSubset(std::size_t pairCount, std::size_t lightCount, std::size_t target) {
    std::size_t stride = std::max<std::size_t>(1, pairCount / target);
    while (stride > 1 && std::gcd(stride, lightCount) != 1) --stride;
    std::vector<int> subset;
    for (std::size_t j = 0; j < pairCount; j += stride) subset.push_back(int(j));
    return subset;
}

}  // namespace

PairTable makePairTable(const std::vector<glm::vec3>& views, const std::vector<glm::vec3>& lights) {
    PairTable table;
    for (std::size_t v = 0; v < views.size(); ++v)
        for (std::size_t l = 0; l < lights.size(); ++l) {
            // Products in float first, as the shader forms them, then widened.
            table.products.emplace_back(views[v].x * lights[l].x, views[v].y * lights[l].y,
                                        views[v].z * lights[l].z);
            table.pairView.push_back(int(v));
        }
    // 13 nonlinear parameters do not need 6561 residuals: on the built-in sample (24x24, Bonn
    // 81x81) comparing starts on ~500 pairs and refining on ~1300 changed the error avg from
    // 0.0699 to 0.0701 and cut the CPU time 3.5x (16.1 s -> 4.6 s); the colours are still solved
    // on all pairs afterwards.
    table.subsample = strideSubset(table.products.size(), lights.size(), 500);
    table.refineSubset = strideSubset(table.products.size(), lights.size(), 1300);
    return table;
}

namespace {

/** r_j = scale_j * model(w_j) - y_j over a list of pairs, with its analytic Jacobian: about 4x
 *  faster than autodiff Jets here, which decides whether 256x256 texels fit in minutes. */
class LuminanceCost : public ceres::CostFunction {
public:
    LuminanceCost(const PairTable& pairs, const std::vector<int>* subset, const double* target,
                  const double* scale, int lobes)
        : _pairs(pairs), _subset(subset), _target(target), _scale(scale), _lobes(lobes) {
        set_num_residuals(int(subset ? subset->size() : pairs.products.size()));
        mutable_parameter_block_sizes()->push_back(1 + kValuesPerLobe * lobes);
    }

    bool Evaluate(double const* const* parameters, double* residuals,
                  double** jacobians) const override {
        const double* p = parameters[0];
        const int n = num_residuals(), cols = 1 + kValuesPerLobe * _lobes;
        double* jac = jacobians ? jacobians[0] : nullptr;
        for (int r = 0; r < n; ++r) {
            const int j = _subset ? (*_subset)[r] : r;
            const glm::dvec3& w = _pairs.products[j];
            const double s = _scale ? _scale[j] : 1.0;
            double sum = p[0];
            double* row = jac ? jac + std::size_t(r) * cols : nullptr;
            if (row) row[0] = s;
            for (int i = 0; i < _lobes; ++i) {
                const double* c = p + 1 + i * kValuesPerLobe;
                const double base = c[0] * w.x + c[1] * w.y + c[2] * w.z;
                double* d = row ? row + 1 + i * kValuesPerLobe : nullptr;
                if (base > kMinBase) {
                    const double logBase = std::log(base);
                    const double value = std::exp(c[3] * logBase);
                    sum += value;
                    if (d) {
                        const double dBase = s * c[3] * value / base;
                        d[0] = dBase * w.x;
                        d[1] = dBase * w.y;
                        d[2] = dBase * w.z;
                        d[3] = s * value * logBase;
                    }
                } else if (d) {
                    d[0] = d[1] = d[2] = d[3] = 0.0;
                }
            }
            residuals[r] = s * sum - _target[j];
            // Overflowing or absurd values (C^n explodes for large n): LM rejects the step.
            if (!(std::abs(residuals[r]) < 1e6)) return false;
        }
        return true;
    }

private:
    const PairTable& _pairs;
    const std::vector<int>* _subset;
    const double* _target;
    const double* _scale;
    int _lobes;
};

struct SolveResult {
    double cost;
    int iterations;
};

SolveResult solve(const PairTable& pairs, const std::vector<int>* subset, const double* target,
                  const double* scale, int lobes, int maxIterations, std::vector<double>& params,
                  double maxTarget) {
    ceres::Problem::Options problemOptions;
    problemOptions.enable_fast_removal = false;
    ceres::Problem problem(problemOptions);
    double* x = params.data();
    // Ceres refuses starts outside the bounds (a neighbour's `a` may exceed this texel's bound).
    x[0] = std::clamp(x[0], 0.0, std::max(1.0, 2.0 * maxTarget));
    for (int i = 0; i < lobes; ++i) {
        double* c = x + 1 + i * kValuesPerLobe;
        for (int k = 0; k < 3; ++k) c[k] = std::clamp(c[k], -kMaxCoefficient, kMaxCoefficient);
        c[3] = std::clamp(c[3], kMinExponent, kMaxExponent);
    }
    auto* cost = new LuminanceCost(pairs, subset, target, scale, lobes);
    problem.AddResidualBlock(cost, nullptr, x);
    {
        // A start that cannot be evaluated (a neighbour's sharp lobe overflowing here) is skipped
        // quietly instead of letting Ceres log an error for it.
        std::vector<double> probe(cost->num_residuals());
        const double* blocks[] = {x};
        if (!cost->Evaluate(blocks, probe.data(), nullptr))
            return {std::numeric_limits<double>::infinity(), 0};
    }
    // Bounds keep every lobe valid (n > 0) and every evaluation finite.
    problem.SetParameterLowerBound(x, 0, 0.0);
    problem.SetParameterUpperBound(x, 0, std::max(1.0, 2.0 * maxTarget));
    for (int i = 0; i < lobes; ++i) {
        const int o = 1 + i * kValuesPerLobe;
        for (int k = 0; k < 3; ++k) {
            problem.SetParameterLowerBound(x, o + k, -kMaxCoefficient);
            problem.SetParameterUpperBound(x, o + k, kMaxCoefficient);
        }
        problem.SetParameterLowerBound(x, o + 3, kMinExponent);
        problem.SetParameterUpperBound(x, o + 3, kMaxExponent);
    }
    ceres::Solver::Options options;
    options.minimizer_type = ceres::TRUST_REGION;
    options.trust_region_strategy_type = ceres::LEVENBERG_MARQUARDT;
    options.linear_solver_type = ceres::DENSE_NORMAL_CHOLESKY;
    options.max_num_iterations = maxIterations;
    options.num_threads = 1;  // parallelism is over texels
    options.logging_type = ceres::SILENT;
    options.minimizer_progress_to_stdout = false;
    options.function_tolerance = 1e-6;
    options.parameter_tolerance = 1e-9;
    const std::vector<double> start = params;
    ceres::Solver::Summary summary;
    ceres::Solve(options, &problem, &summary);
    bool finite = std::isfinite(summary.final_cost);
    for (double v : params) finite = finite && std::isfinite(v);
    if (!finite) {
        params = start;
        return {std::numeric_limits<double>::infinity(), int(summary.iterations.size())};
    }
    return {summary.final_cost, int(summary.iterations.size())};
}

}  // namespace

void scaleLobes(double* lobeParams, int lobes, double factor) {
    for (int i = 0; i < lobes; ++i) {
        double* c = lobeParams + i * kValuesPerLobe;
        const double k = std::pow(factor, 1.0 / c[3]);
        c[0] *= k;
        c[1] *= k;
        c[2] *= k;
    }
}

LuminanceFit fitLuminance(const PairTable& pairs, const double* target, const double* scale,
                          int lobes, int maxIterations, const std::vector<double>* neighbour) {
    const std::size_t count = pairs.products.size();
    double mean = 0, minimum = std::numeric_limits<double>::infinity(), maximum = 0, meanZ = 0;
    for (std::size_t j = 0; j < count; ++j) {
        const double s = scale ? std::max(scale[j], 1e-6) : 1.0;
        mean += target[j] / s;
        minimum = std::min(minimum, target[j] / s);
        maximum = std::max(maximum, target[j] / s);
        meanZ += pairs.products[j].z;
    }
    mean /= double(count);
    meanZ /= double(count);
    minimum = std::max(minimum, 0.0);

    // Starts: an ambient term at the minimum, a diffuse-like lobe (n = 1 along the normal) for most
    // of the mean, then specular (mirror: C = (-1, -1, 1)) and retro-reflective (C = (1, 1, 1))
    // lobes with small weight; the second start swaps their sharpness.
    auto makeStart = [&](double nSpecular, double nRetro, double diffuseShare) {
        std::vector<double> p(1 + kValuesPerLobe * lobes, 0.0);
        p[0] = 0.5 * minimum;
        const double rest = std::max(mean - p[0], 1e-3);
        for (int i = 0; i < lobes; ++i) {
            double* c = p.data() + 1 + i * kValuesPerLobe;
            if (i == 0) {
                c[0] = c[1] = 0.0;
                c[2] = std::max(diffuseShare * rest / std::max(meanZ, 1e-3), 1e-3);
                c[3] = 1.0;
            } else {
                const bool mirror = i % 2 == 1;
                const double n = mirror ? nSpecular : nRetro;
                const double k = std::pow(std::max(0.2 * rest, 1e-3), 1.0 / n);
                c[0] = c[1] = mirror ? -k : k;
                c[2] = k;
                c[3] = n;
            }
        }
        return p;
    };
    std::vector<std::vector<double>> starts = {makeStart(8.0, 2.0, 0.8), makeStart(2.0, 8.0, 0.5)};
    if (neighbour && neighbour->size() == starts[0].size()) starts.push_back(*neighbour);

    LuminanceFit fit;
    double best = std::numeric_limits<double>::infinity();
    // A start's basin shows within a few iterations; the winner gets the full budget below.
    const int shortIterations = std::min(maxIterations, 6);
    for (auto& start : starts) {
        const SolveResult r =
            solve(pairs, &pairs.subsample, target, scale, lobes, shortIterations, start, maximum);
        fit.iterations += r.iterations;
        if (r.cost < best || fit.params.empty()) {
            best = r.cost;
            fit.params = start;
        }
    }
    const SolveResult r =
        solve(pairs, &pairs.refineSubset, target, scale, lobes, maxIterations, fit.params, maximum);
    fit.iterations += r.iterations;
    fit.cost = r.cost;
    return fit;
}

int refineLuminance(const PairTable& pairs, const double* target, const double* scale, int lobes,
                    int maxIterations, std::vector<double>& params) {
    double maximum = 0;
    for (std::size_t j = 0; j < pairs.products.size(); ++j)
        maximum = std::max(maximum, target[j] / (scale ? std::max(scale[j], 1e-6) : 1.0));
    return solve(pairs, &pairs.refineSubset, target, scale, lobes, maxIterations, params, maximum)
        .iterations;
}

}  // namespace osgBTF::lobes
