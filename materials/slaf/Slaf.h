// osgBTF method "slaf": scaled Lafortune lobes (Daubert et al. 2001; Meseth et al. 2003
// section 3.2).
//
//   BTF(x, v, l) ~ T(x, v) * (rho_d(x) + rho_s(x) * sum_{i<k} max(C_i . (v * l), 0)^n_i) * l_z
//
// (l_z with option cosine=1, the default, as for LAF: materials/laf/Laf.h explains why.)
// The LAF term (materials/laf/Laf.h: RGB albedos, scalar luminance lobes, as Meseth et al. 2003
// limits SLAF to luminance lobes with a specular albedo) scaled per texel by an RGB table T over
// the measured view directions, which captures view-dependent masking and parallax that lobes
// cannot. Between measured views T is blended with the direction interpolation of
// core/DirectionInterpolation.h (exact Delaunay weights, materials/DirectionLookup.h, the same on
// CPU and GPU). Values include the cosine term.
//
// The bracket, its storage and the fitter are LobeMaterial's (materials/laf/LobeMaterial.h),
// shared with LAF, which is this model with T fixed at 1.
//
// Storage (Meseth et al. 2003 Table 2: 257 values, 508 bytes per texel at 81 views, k = 2): rho_d,
// rho_s 8-bit (6 values, 6 bytes), lobes half (8 values, 16 bytes), T half (81 x 3 values, 486
// bytes).
#pragma once

#include <vector>

#include "materials/DirectionLookup.h"
#include "materials/MethodOptions.h"
#include "materials/laf/LobeMaterial.h"

namespace osgBTF {

/** SlafMaterial's members beyond LobeMaterial's (materials/MethodMaterial.h). */
struct SlafData {
    /** T: [view][y][x][rgb], half, >= 0. */
    StoredValues scale;

protected:
    DirectionLookup _viewLookup;
};

class SlafMaterial : public LobeMethod<SlafMaterial, SlafData> {
public:
    static constexpr const char* kMethod = "slaf";

    SlafMaterial() = default;
    SlafMaterial(const SlafMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : LobeMethod(other, copyop) {}
    META_Object(osgBTF, SlafMaterial)

        /** Options: lobes (1..8, default 2), iterations (LM iterations per texel and round, 1..500,
         *  default 50), rounds (alternations between T and the lobes, 0..10, default 2), cosine (0
         * or 1, default 1). Throws Error "slaf: ..." for invalid or unknown options and an empty
         * BTF. */
        static osg::ref_ptr<SlafMaterial> fit(const BtfSource& btf, const FitOptions& options);
    // create (T = 1), fromFile, memory (the view table is shared and not counted, as in Meseth
    // et al. 2003: it is 65 x 65 x 6 floats for any material size), toFittedMaterial,
    // createStateSet: LobeMethod's, with T through the hooks below.

    const DirectionLookup& viewLookup() const { return _viewLookup; }
    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    void evaluateMeasured(std::size_t texel, float* abrdf) const override;

    // LobeMethod's hooks: T, its file texture "scale" and its units 3 (T) and 4 (view table).
    void initExtra();
    void checkFile(const FittedMaterial& file) const;
    void readExtra(FittedMaterial& file);
    void writeExtra(FittedMaterial& file) const;
    void addExtraState(osg::StateSet& stateSet) const;

protected:
    ~SlafMaterial() override = default;
};

}  // namespace osgBTF
