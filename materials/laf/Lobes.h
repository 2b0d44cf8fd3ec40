// osgBTF: Lafortune lobes and their per-texel fit, shared by the LAF and SLAF methods.
//
// A lobe is s(v, l) = max(Cx vx lx + Cy vy ly + Cz vz lz, 0)^n (Meseth et al. 2003 eq. 3; the text
// extraction garbles the exponent's placement, we follow Lafortune et al. 1997 where n applies to
// the whole dot product). The clamp at 0 keeps the power defined for every direction pair (a
// negative base has no real power), on the CPU and in the shader alike.
//
// Fitting (the part Meseth et al. 2003 calls slow and fragile, section 4.4): per texel, the
// luminance
//   Y(v, l) ~ t(v) * (a + sum_i s_i(v, l))           (t = 1 for LAF, SLAF's view scale otherwise)
// is fitted with Ceres' Levenberg-Marquardt over a + 4 k lobe parameters, bounded so every lobe
// stays valid (n in [kMinExponent, kMaxExponent], |C| <= kMaxCoefficient, a >= 0). The specular
// albedo's luminance is folded into the lobes (rho_s * s_i(C) = s_i(C * rho_s^(1/n))), which
// removes the scale ambiguity between rho_s and C that would leave LM's normal equations singular.
// The RGB colours are then linear given the lobes and are solved in closed form per channel
// (variable projection): the nonlinear solver never sees them. Several starts (a diffuse-like
// lobe plus mirror / retro-reflective lobes, and the already fitted left neighbour) are tried on a
// subsample of the pairs; the best is refined on a larger subsample (PairTable).
// The material around this fit (colours, storage rounding, SLAF's view table) is LobeMaterial.h;
// helpers that are not about lobes are in materials/MaterialMath.h.
#pragma once

#include <array>
#include <cmath>
#include <vector>

#include <glm/vec3.hpp>

namespace osgBTF::lobes {

constexpr double kMinExponent = 0.5;
constexpr double kMaxExponent = 256.0;
constexpr double kMaxCoefficient = 64.0;
/** Bases at or below this count as 0: keeps d/dC = n b^(n-1) finite for n < 1. */
constexpr double kMinBase = 1e-8;
constexpr int kMaxLobes = 8;
constexpr int kValuesPerLobe = 4;  ///< Cx, Cy, Cz, n

/** One lobe's value, in float, with the exact operations the shaders use
 *  (dot(C.xyz, v * l), then pow), so the CPU reference equals the GPU. */
inline float lobeValue(const float* lobe, const glm::vec3& v, const glm::vec3& l) {
    const float base = lobe[0] * (v.x * l.x) + lobe[1] * (v.y * l.y) + lobe[2] * (v.z * l.z);
    return base > 0.0f ? std::pow(base, lobe[3]) : 0.0f;
}

/** Sum of `count` lobes stored as consecutive (Cx, Cy, Cz, n). */
inline float lobeSum(const float* lobes, int count, const glm::vec3& v, const glm::vec3& l) {
    float sum = 0.0f;
    for (int i = 0; i < count; ++i) sum += lobeValue(lobes + i * kValuesPerLobe, v, l);
    return sum;
}

/** The luminance model's residuals as a template (Ceres autodiff in the tests checks the
 *  analytic Jacobian the fitter uses against it). params = [a, (Cx, Cy, Cz, n) x lobes]. */
template <typename T>
T luminanceModel(const T* params, int lobes, const glm::dvec3& w) {
    using std::pow;
    T sum = params[0];
    for (int i = 0; i < lobes; ++i) {
        const T* p = params + 1 + i * kValuesPerLobe;
        const T base = p[0] * w.x + p[1] * w.y + p[2] * w.z;
        if (base > T(kMinBase)) sum += pow(base, p[3]);
    }
    return sum;
}

/** What the fitter needs to know about the direction pairs, shared by all texels. */
struct PairTable {
    std::vector<glm::dvec3> products;  ///< v * l (componentwise) per pair, [view][light]
    std::vector<int> pairView;         ///< view index of each pair
    std::vector<int> subsample;        ///< pairs used to compare starting points (~500)
    std::vector<int> refineSubset;     ///< pairs the best start is refined on (~1300)
};
PairTable makePairTable(const std::vector<glm::vec3>& views, const std::vector<glm::vec3>& lights);

struct LuminanceFit {
    std::vector<double> params;  ///< [a, (Cx, Cy, Cz, n) x lobes]
    double cost = 0;             ///< 0.5 * sum of squared residuals over all pairs
    int iterations = 0;          ///< LM iterations spent on this texel, all starts
};

/** Fits Y_j ~ scale_j * luminanceModel(params, w_j) for one texel. `scale` may be null (1).
 *  `neighbour`, if not null, is a previous texel's params used as one more start. Never returns
 *  non-finite params: a start that fails keeps its (finite) starting point. */
LuminanceFit fitLuminance(const PairTable& pairs, const double* target, const double* scale,
                          int lobes, int maxIterations, const std::vector<double>* neighbour);

/** Continues LM from `params` on the refine subset (SLAF's alternation); returns the iterations
 *  spent. */
int refineLuminance(const PairTable& pairs, const double* target, const double* scale, int lobes,
                    int maxIterations, std::vector<double>& params);

/** Scales the lobe sum by `factor` > 0 (C_i *= factor^(1/n_i)), so a colour can be divided by it.
 */
void scaleLobes(double* lobeParams, int lobes, double factor);

}  // namespace osgBTF::lobes
