// osgBTF method "laf": per-texel Lafortune lobes (McAllister et al. 2002; Meseth et al. 2003
// section 3.1).
//
//   BTF(x, v, l) ~ [rho_d(x) + rho_s(x) * sum_{i<k} max(Cx_i vx lx + Cy_i vy ly + Cz_i vz lz,
//   0)^n_i]
//                  * l_z                         (option cosine=1, the default; 1 with cosine=0)
//
// rho_d, rho_s RGB; the lobes (C_i, n_i) are scalar: they shape the luminance, the albedos colour
// it. v, l are the local view and light directions; the value is the BTF as measured, cosine term
// included, so the renderer multiplies by nothing afterwards. The bracket is a BRDF model
// (McAllister renders it times cos theta_l); measured values contain that cosine, so by default
// the model carries the l_z factor. Meseth et al. 2003 eq. 2 literally (cosine=0) has no l_z, and
// no lobe can produce l_z alone (a lobe in v_z l_z is also scaled by v_z): on data with Lambertian
// shading it is several times worse than a lit texture (materials/laf/README.md).
//
// The model, storage and fitter are LobeMaterial's (LobeMaterial.h, shared with SLAF): LAF is
// SLAF with the view table fixed at 1.
//
// Storage (what Meseth et al. 2003 Table 2 counts: 14 values, 22 bytes per texel at k = 2): rho_d
// and rho_s as 8-bit fixed point (2 x 3 values, 6 bytes), the lobes as half floats (4 k values, 8 k
// bytes). The fitter rounds the model to exactly these precisions, so CPU, file and GPU agree.
#pragma once

#include "materials/MethodOptions.h"
#include "materials/laf/LobeMaterial.h"

namespace osgBTF {

/** LAF stores nothing beyond LobeMaterial's data. */
struct LafData {};

class LafMaterial : public LobeMethod<LafMaterial, LafData> {
public:
    static constexpr const char* kMethod = "laf";

    LafMaterial() = default;
    LafMaterial(const LafMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : LobeMethod(other, copyop) {}
    META_Object(osgBTF, LafMaterial)

        /** Options: lobes (1..8, default 2), iterations (LM iterations per texel, 1..500, default
         *  50), cosine (0 or 1, default 1). Throws Error "laf: ..." for invalid or unknown options
         * and an empty BTF. */
        static osg::ref_ptr<LafMaterial> fit(const BtfSource& btf, const FitOptions& options);
    // create, fromFile, memory, toFittedMaterial, createStateSet: LobeMethod's.

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;

protected:
    ~LafMaterial() override = default;
};

}  // namespace osgBTF
