// osgBTF method "hsh": hemispherical harmonics (Gautron, Krivanek, Pattanaik, Bouatouch 2004), the
// basis the RTI field fits its captures with (RTIBuilder, relight, RTIViewer, OpenLIME).
//
//   H(x, l) = sum_k c_k(x) h_k(l),   k < n^2,  n = option order (2, 3 or 4: 4, 9 or 16 terms)
//
// per colour channel, with h_k the hemispherical harmonics of the unit light direction l in the
// local frame, in the RTI tools' order and normalisation (orthonormal over the hemisphere; tested
// by integrating their products). With t = cos(theta_l) = l.z, (cos phi, sin phi) = (l.x, l.y) /
// |(l.x, l.y)| and s = sqrt(t - t^2):
//   h0 = 1/sqrt(2 pi)
//   h1 = sqrt(6/pi) cos(phi) s            h2 = sqrt(3/(2 pi)) (2t - 1)
//   h3 = sqrt(6/pi) sin(phi) s            h4 = sqrt(30/pi) cos(2 phi) (t^2 - t)
//   h5 = sqrt(30/pi) cos(phi) (2t - 1) s  h6 = sqrt(5/(2 pi)) (1 - 6t + 6t^2)
//   h7 = sqrt(30/pi) sin(phi) (2t - 1) s  h8 = sqrt(30/pi) sin(2 phi) (t^2 - t)
//   h9 = 2 sqrt(35/pi) cos(3 phi) s^3     h10 = sqrt(210/pi) cos(2 phi) (2t - 1)(t^2 - t)
//   h11 = 2 sqrt(21/pi) cos(phi) s (1 - 5t + 5t^2)
//   h12 = sqrt(7/(2 pi)) (-1 + 12t - 30t^2 + 20t^3)
//   h13 = 2 sqrt(21/pi) sin(phi) s (1 - 5t + 5t^2)
//   h14 = sqrt(210/pi) sin(2 phi) (2t - 1)(t^2 - t)   h15 = 2 sqrt(35/pi) sin(3 phi) s^3
// The multiple angles come from cos(phi), sin(phi) by the double- and triple-angle identities, so
// the basis needs no trigonometric function (the same float operations on CPU and GPU). A light
// below the horizon is evaluated at t = 0; at the normal (l.x = l.y = 0) phi is 0, which no term
// sees (each phi-dependent term carries a factor s = 0).
//
// Views (option views), as ptm: front (one fit on the measured view nearest the normal, used for
// every view: what RTI captures are) or all (one fit per measured view, blended over the up to 3
// Delaunay-neighbour views with the weights of materials/DirectionLookup.h). The rendered value
// is max(0, .) per channel. What is fitted: the values as measured, cosine term included.
//
// Storage (option storage): coefficients as half (default) or float, an RGB 2D array texture whose
// layer n^2 s + k holds c_k of (R, G, B) for view slot s (0 for front, the measured view for all).
#pragma once

#include <array>
#include <string>
#include <vector>

#include "materials/LightBasisMaterial.h"
#include "materials/MethodOptions.h"
#include "materials/StoredValues.h"

namespace osgBTF {

/** HshMaterial's members beyond LightBasisData's (materials/LightBasisMaterial.h). */
struct HshData : LightBasisData {
    /** The shape of a model: what the options choose. */
    struct Shape {
        int order = 3;         ///< 2, 3 or 4: order^2 terms
        bool perView = false;  ///< views=all (else front)
        MaterialTexture::PixelKind storage = MaterialTexture::Half;
    };

protected:
    Shape _shape;
};

class HshMaterial : public LightBasisMaterial<HshMaterial, HshData> {
public:
    static constexpr const char* kMethod = "hsh";
    /** fromFile takes the file's half textures as they are stored. */
    static constexpr bool kLoadsHalves = true;
    /** Terms of the largest order (4). */
    static constexpr int kMaxTerms = 16;
    using Basis = std::array<float, kMaxTerms>;

    HshMaterial() = default;
    HshMaterial(const HshMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : LightBasisMaterial(other, copyop) {}
    META_Object(osgBTF, HshMaterial)

        /** Fits the model (see the file comment). Options: order, views, storage. Throws Error for
         *  bad options, an empty BTF, or more array layers than OpenGL guarantees. Fills fitInfo:
         *  seconds, order, views, storage, front-view, rank and condition of the design matrix. */
        static osg::ref_ptr<HshMaterial> fit(const BtfSource& btf, const FitOptions& options);
    // create, fromFile, evaluate, memory, file, StateSet, shape(), slots(), frontView(),
    // viewLookup(), toStorage: LightBasisMaterial's. Shader defines: "OSGBTF_HSH_TERMS n", then
    // OSGBTF_HSH_PER_VIEW and OSGBTF_HSH_FILTERED: hsh.frag's loops run to a constant
    // (README.md, "Pass cost").

    int terms() const { return _shape.order * _shape.order; }

    /** The basis h_0 .. h_15 at a light direction, in hsh.frag's float operations (all 16; a
     *  model of order n uses the first n^2). */
    static Basis basis(const glm::vec3& light);
    /** The same in double, for the fit's design matrix. */
    static std::array<double, kMaxTerms> basisDouble(const glm::vec3& light);

    /** sum_k c_k h_k of a texel and view slot, unclamped, in the shader's float operations. */
    glm::vec3 field(std::size_t texel, int slot, const Basis& h) const;
    float coefficient(std::size_t texel, int slot, int k, int c) const;
    void setCoefficient(std::size_t texel, int slot, int k, int c, float value);

    // What LightBasisMaterial asks of the method.
    int layersPerSlot() const { return terms(); }
    static Basis lightTerms(const glm::vec3& light) { return basis(light); }
    /** Throws Error for an order other than 2, 3 or 4. */
    static void checkShape(const Shape& shape);
    static constexpr const char* kTooManyLayersHint = " (use views=front or a lower order)";
    static void readShape(const FittedMaterial& file, Shape& shape);
    void writeShape(FittedMaterial& file) const;
    std::vector<std::string> shapeDefines() const;

protected:
    ~HshMaterial() override = default;
};

}  // namespace osgBTF
