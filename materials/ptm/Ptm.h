// osgBTF method "ptm": Polynomial Texture Maps (Malzbender, Gelb, Wolters 2001) as Boßerhoff and
// Nicoll 2003 section 3.1 uses them for BTFs (Boßerhoff, Nicoll).
//
//   P(x, l) = a0(x) lx^2 + a1(x) ly^2 + a2(x) lx ly + a3(x) lx + a4(x) ly + a5(x)
//
// (lx, ly) = the x and y components of the unit light direction in the local frame. Two colour
// models (option colour):
//   rgb        one polynomial per channel: 18 coefficients per texel;
//   luminance  one polynomial on the Rec. 709 luminance Y = 0.2126 R + 0.7152 G + 0.0722 B times a
//              per-texel RGB base colour: value = colour(x) * P(x, l), 6 + 3 values per texel.
// and two view models (option views):
//   front      one PTM fitted on the measured view nearest the normal and used for every view
//              (the paper's setting: "a fixed front-view");
//   all        one PTM per measured view, blended over the (up to) 3 Delaunay-neighbour views with
//              the exact weights of materials/DirectionLookup.h, as rf and pca blend.
// The rendered value is max(0, sum_j w_j P_{v_j}(x, l)) per channel: measured values are never
// negative, so the clamp can only lower the error where a polynomial dips below 0 (grazing
// lights beyond the measured ones).
//
// What is fitted: the values as measured, cosine term included (the PTM was defined on photographs,
// which carry the foreshortening too); nothing multiplies by n.l again.
//
// Fit: the lights' design matrix A (rows (lx^2, ly^2, lx ly, lx, ly, 1)) is the same for every
// texel and view, so its pseudo-inverse A+ (Eigen JacobiSVD, singular values below the rank
// threshold clamped to zero, as the paper clamps "small eigenvalues") is computed once; each view's
// coefficients are one product A+ Y with Y the view's images (one column per texel and channel).
// Luminance: the least-squares fit is linear in the data, so the luminance PTM is the same
// combination of the three channel PTMs; after rounding it to storage, the base colour is the
// least-squares colour for that stored polynomial, colour_c = <y_c, P> / <P, P>, computed from the
// channel fits through A^T A (A^T y_c = A^T A A+ y_c). Summed with the Rec. 709 weights this
// colour has luminance <Y, P> / <P, P> = 1 (P is Y's projection onto the polynomials): the
// polynomial is the luminance and the colour a chromaticity of unit luminance.
//
// Storage (option storage): coefficients and colour as half (default) or float.
//   coefficients  RGB 2D array texture; rgb: layer 6 s + k holds a_k of (R, G, B) for view slot s;
//                 luminance: layer 2 s = (a0, a1, a2), layer 2 s + 1 = (a3, a4, a5)
//   colour        luminance only: RGB 2D array texture, layer s
// with s = 0 (front) or s = the measured view (all).
#pragma once

#include <array>
#include <string>
#include <vector>

#include <glm/vec2.hpp>

#include "materials/LightBasisMaterial.h"
#include "materials/MethodOptions.h"
#include "materials/StoredValues.h"

namespace osgBTF {

/** PtmMaterial's members beyond LightBasisData's (materials/LightBasisMaterial.h). */
struct PtmData : LightBasisData {
    /** The shape of a model: what the options choose. */
    struct Shape {
        bool luminance = false;  ///< colour=luminance (else rgb)
        bool perView = false;    ///< views=all (else front)
        MaterialTexture::PixelKind storage = MaterialTexture::Half;
    };

    // coefficients (LightBasisData): rgb: layer 6 s + k holds a_k of (R, G, B) for view slot s;
    // luminance: layer 2 s = (a0, a1, a2), layer 2 s + 1 = (a3, a4, a5).
    /** Luminance only: [slot][y][x][rgb], half or float as stored; empty for rgb. */
    StoredValues colour;

protected:
    Shape _shape;
};

class PtmMaterial : public LightBasisMaterial<PtmMaterial, PtmData> {
public:
    static constexpr const char* kMethod = "ptm";
    /** fromFile takes the file's half textures as they are stored. */
    static constexpr bool kLoadsHalves = true;

    /** Terms of the biquadratic. */
    static constexpr int kTerms = 6;
    /** Rec. 709 luminance weights of R, G, B (they sum to 1). */
    static constexpr std::array<double, 3> kLuminance{0.2126, 0.7152, 0.0722};

    PtmMaterial() = default;
    PtmMaterial(const PtmMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : LightBasisMaterial(other, copyop) {}
    META_Object(osgBTF, PtmMaterial)

        /** Fits the model (see the file comment). Options: colour, views, storage. Throws Error
         *  for bad options, an empty BTF, no lights, views=all with fewer than 3 views, or more
         *  array layers than OpenGL guarantees. Fills fitInfo: seconds, colour, views, storage,
         *  front-view, rank and condition of the design matrix. */
        static osg::ref_ptr<PtmMaterial> fit(const BtfSource& btf, const FitOptions& options);
    // create, fromFile, evaluate, memory, file, StateSet, shape(), slots(), frontView(),
    // viewLookup(), toStorage: LightBasisMaterial's. Shader defines: OSGBTF_PTM_LUMINANCE, then
    // OSGBTF_PTM_PER_VIEW and OSGBTF_PTM_FILTERED (README.md, "Pass cost").

    /** Coefficient layers per slot: 6 (rgb) or 2 (luminance). */
    int layersPerSlot() const { return _shape.luminance ? 2 : kTerms; }

    /** The polynomial(s) of view slot `slot` at a texel, unclamped, in the shader's float
     *  operations: (P_R, P_G, P_B) for rgb, colour * P_Y for luminance. */
    glm::vec3 field(std::size_t texel, int slot, float lx, float ly) const;
    /** Coefficient a_k (k in 0..5) of channel c (rgb) or of the luminance (c ignored) of a texel
     *  and slot, as stored. */
    float coefficient(std::size_t texel, int slot, int k, int c) const;
    void setCoefficient(std::size_t texel, int slot, int k, int c, float value);
    /** The monomials (lx^2, ly^2, lx ly, lx, ly, 1) of a light direction: a design matrix row. */
    static std::array<double, kTerms> monomials(const glm::vec3& light);

    // What LightBasisMaterial asks of the method.
    static glm::vec2 lightTerms(const glm::vec3& light) { return {light.x, light.y}; }
    glm::vec3 field(std::size_t texel, int slot, const glm::vec2& l) const {
        return field(texel, slot, l.x, l.y);
    }
    static constexpr const char* kSecondArray = "colour";
    static bool storesSecondArray(const Shape& shape) { return shape.luminance; }
    StoredValues& secondArray() { return colour; }
    const StoredValues& secondArray() const { return colour; }
    static void readShape(const FittedMaterial& file, Shape& shape);
    void writeShape(FittedMaterial& file) const;
    std::vector<std::string> shapeDefines() const;

protected:
    ~PtmMaterial() override = default;
    /** Luminance materials multiply two per-texel parameters (colour and luminance). */
    bool linearInParameters() const override { return !_shape.luminance; }
};

}  // namespace osgBTF
