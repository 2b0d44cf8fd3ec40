// osgBTF (libosgBTFFit): least squares of a per-texel model that is linear in a fixed basis of
// the light direction, shared by the methods of that form (ptm: the biquadratic of Malzbender et
// al. 2001; hsh: the hemispherical harmonics of Gautron et al. 2004).
//
// For such a model the design matrix A (one row of basis values per measured light) is the same
// for every texel and view, so its pseudo-inverse is computed once and each view's coefficients
// are one product with its images. Singular values at the level of rounding are clamped to zero
// (Boßerhoff and Nicoll 2003 "clamp small eigenvalues"; Eigen's own rank threshold): fewer lights
// than terms, or lights that do not tell the terms apart, give the minimum-norm solution instead
// of amplified noise.
#pragma once

#include <cstddef>
#include <functional>
#include <string>

#include <Eigen/Core>

#include "core/BtfSource.h"

namespace osgBTF {

/** The lights' design matrix and what a fit derives from it once for all texels. */
struct LightBasisDesign {
    Eigen::MatrixXd pinvT;  ///< (A+)^T, lights x terms: coefficients of a column y are y^T (A+)^T
    Eigen::MatrixXd gram;   ///< A^T A, terms x terms
    int rank = 0;
    double condition = 0;  ///< largest / smallest kept singular value
};

/** `a`: one row of basis values per measured light. */
LightBasisDesign makeLightBasisDesign(const Eigen::MatrixXd& a);

/** The measured view nearest the normal (largest z): the "front view" of a front-only model. */
std::size_t frontViewOf(const DirectionSet& views);

/** Receives one texel's least-squares coefficients for one view slot: `c` is 3 x terms (rows R, G,
 *  B), unrounded. Called from several threads at once, for distinct (texel, slot). */
using LightBasisStore =
    std::function<void(std::size_t texel, int slot, const Eigen::Ref<const Eigen::MatrixXd>& c)>;

/** Fits every texel of one view (perView false: the view `frontView`, as slot 0) or of every
 *  view (slot = view), reading the images in blocks (in parallel) and reporting progress under
 *  `label`. */
void fitLightBasis(const BtfSource& btf, const LightBasisDesign& design, bool perView,
                   std::size_t frontView, const std::string& label, const LightBasisStore& store);

/** Bytes the fit holds besides the model: one view's images per worker. */
std::uint64_t lightBasisFitWorkingBytes(const BtfSource& btf, bool perView);

}  // namespace osgBTF
