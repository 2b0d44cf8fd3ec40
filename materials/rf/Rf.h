// osgBTF method "rf": reflectance fields (Meseth, Müller, Klein 2003; Meseth et al. 2003
// section 3.3).
//
// For every measured view v the texel's reflectance field (fixed view, varying light) is a
// diffuse term plus an RGB albedo times k Lafortune-like lobes in the light direction only:
//
//   RF_v(x, l) = rho_d(x) + rho_v(x, v) * sum_i max(0, a_vi(x) l_x + b_vi(x) l_y + c_vi(x)
//   l_z)^n_vi(x)
//
// and a view that was not measured blends the three nearest measured views with the Delaunay
// interpolation weights of materials/DirectionLookup.h (exact, the same on CPU and GPU):
//
//   BTF(x, v, l) ~ sum_j w_j(v) RF_{v_j}(x, l)
//
// rho_d, rho_v RGB; the lobes are scalar (luminance), so colour varies only through rho_v.
//
// Boßerhoff and Nicoll 2003's per-view Lafortune BTF (section 3.2) is this model with two options
// (README.md): diffuse=0 drops rho_d (its lobes have no diffuse term), and colour=rgb gives every
// colour channel its own k lobes (its RGB model, 2 lobes per channel), rho_v then a per-channel
// scale:
//
//   RF_v(x, l)_c = [rho_d(x)_c +] rho_v(x, v)_c * sum_i max(0, (a, b, c)_vci(x) . l)^n_vci(x)
//
// With the view fixed, the Lafortune lobe of Boßerhoff and Nicoll 2003 [C_x u_x v_x + C_y u_y v_y +
// C_z u_z v_z]^n is
// ((C_x v_x, C_y v_y, C_z v_z) . u)^n: exactly this lobe in the light direction.
// Meseth et al. 2003's equation (5) writes the lobe as a dot product without the exponent in the
// garbled text extraction; the exponent n is Meseth's definition ("similar to the Lafortune lobes")
// and the value count of Table 2 (4 values per lobe) confirms it. max(0, .) keeps a lobe's base
// non-negative so any real exponent is defined (the shader does the same).
//
// Storage (values / bytes per texel with V views and k lobes; Table 2 with V = 81, k = 2):
//   rho_d   RGB, 8-bit fixed point (UNorm8)           3 values,          3 bytes
//   rho_v   RGB per view, half                        3 V values,        6 V bytes
//   lobes   (a, b, c, n) per view and lobe, half      4 k V values,      8 k V bytes
//   total   3 + V (3 + 4k) = 894 values, 3 + 2 V (3 + 4k) = 1785 bytes for V = 81, k = 2.
// diffuse=0 stores no rho_d; colour=rgb stores 3 k lobes per view (12 k V values).
//
// Fit (fit()): per texel and measured view, Levenberg-Marquardt (Ceres' TinySolver, analytic
// Jacobian) of the lobes to the view's luminance over the measured lights, several starts,
// then the colour terms in closed form (variable projection): rho_d jointly over all views,
// rho_v per view, both computed with the lobes already rounded to their storage precision, so
// CPU, file and GPU evaluate exactly the same model; texels whose data have a floor get a second
// pass fitted above it (README.md). Parallel over texel blocks with TBB.
#pragma once

#include <vector>

#include "materials/DirectionLookup.h"
#include "materials/MethodMaterial.h"
#include "materials/MethodOptions.h"
#include "materials/StoredValues.h"

namespace osgBTF {

/** RfMaterial's members (materials/MethodMaterial.h). */
struct RfData {
    /** The model's terms beyond the lobe count (options "diffuse" and "colour"). */
    struct Variant {
        bool diffuse = true;  ///< has rho_d (Meseth et al. 2003); false: lobes only (Boßerhoff and
                              ///< Nicoll 2003)
        bool rgb = false;     ///< k lobes per colour channel instead of k luminance lobes
    };

    // Held as the file stores them (materials/StoredValues.h): a loaded material takes its
    // file's size in memory, and every value set is rounded as the file and the GPU hold it.
    /** rho_d: [y][x][rgb], rows bottom-up; 8-bit. Empty without the diffuse term. */
    StoredValues rhoD;
    /** rho_v: [view][y][x][rgb], half. */
    StoredValues rhoV;
    /** Lobes: [(view * lobeChannels() + channel) * lobeCount() + lobe][y][x][a, b, c, n], half. */
    StoredValues lobes;

protected:
    int _lobes = 0;
    Variant _variant;
    DirectionLookup _viewLookup;
    std::vector<glm::vec3> _lightVectors;  ///< measured lights, for evaluateMeasured
};

class RfMaterial : public MethodMaterial<RfMaterial, RfData> {
public:
    static constexpr const char* kMethod = "rf";
    /** fromFile takes the file's 8-bit and half textures as they are stored. */
    static constexpr bool kLoadsBytes = true;
    static constexpr bool kLoadsHalves = true;

    /** Fit settings; see settingsFrom() for the option names. */
    struct Settings {
        int lobes = 2;            ///< lobes per view (and channel with rgb), 1..8
        int iterations = 20;      ///< Levenberg-Marquardt iterations per start
        int starts = 2;           ///< initialisations tried per (texel, view), 1..3
        double maxExponent = 64;  ///< upper bound of n (the Bonn lights are 15 degrees apart)
        Variant variant;
    };
    /** Smallest exponent a lobe may have (n > 0 keeps the lobe a lobe). */
    static constexpr double kMinExponent = 0.25;
    /** Most lobes per view: 8 x 151 UBO2014 views stay within GL's 2048 array layers. */
    static constexpr int kMaxLobes = 8;

    RfMaterial() = default;
    RfMaterial(const RfMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop) {}
    META_Object(osgBTF, RfMaterial)

        /** Reads and validates "lobes", "iterations", "starts", "max-exponent", "diffuse",
         *  "colour"; throws Error for an unknown option or a value out of range. */
        static Settings settingsFrom(const FitOptions& options);
    /** Fits the model to a measured BTF (see the file comment). Throws Error for bad options or
     *  data the model cannot hold. Fills fitInfo: seconds, lobes, iterations (mean LM iterations
     *  per texel and view, and channel with rgb), fallbacks (fits that kept their
     *  initialisation), max-exponent, diffuse, colour. */
    static osg::ref_ptr<RfMaterial> fit(const BtfSource& btf, const FitOptions& options);
    static osg::ref_ptr<RfMaterial> fromFile(FittedMaterial file);
    /** A zero model of the given shape: memory accounting, tests and synthetic data. Throws Error
     *  if the shape is invalid (fewer than 3 views, lobes out of range, too many layers). */
    static osg::ref_ptr<RfMaterial> create(int width, int height, DirectionSet views,
                                           DirectionSet lights, int lobes, Variant variant);
    /** The default variant (rho_d, luminance lobes). */
    static osg::ref_ptr<RfMaterial> create(int width, int height, DirectionSet views,
                                           DirectionSet lights, int lobes);

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    void evaluateMeasured(std::size_t texel, float* abrdf) const override;
    MemoryFootprint memory() const override;
    FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

    /** Lobes per view (luminance) or per view and colour channel (rgb). */
    int lobeCount() const { return _lobes; }
    bool hasDiffuse() const { return _variant.diffuse; }
    /** 1 (luminance lobes) or 3 (lobes per colour channel). */
    int lobeChannels() const { return _variant.rgb ? 3 : 1; }
    Variant variant() const { return _variant; }
    const DirectionLookup& viewLookup() const { return _viewLookup; }
    /** The reflectance field of measured view `view` without rho_d: rho_v * lobe sum(s). */
    glm::vec3 reflectanceField(std::size_t texel, std::size_t view, const glm::vec3& light) const;
    /** rho_d of one texel, or 0 without the diffuse term. */
    glm::vec3 diffuse(std::size_t texel) const;
    /** sum_i max(0, (a, b, c)_i . light)^n_i of one texel, measured view and lobe channel (0 for
     *  luminance lobes, 0..2 for rgb). */
    float lobeSum(std::size_t texel, std::size_t view, const glm::vec3& light,
                  int channel = 0) const;

protected:
    ~RfMaterial() override = default;

private:
    /** Checks the shape, builds the view interpolation and, unless `allocate` is false (a file
     *  brings the arrays), sizes the arrays. */
    void setShape(int width, int height, DirectionSet views, DirectionSet lights, int lobes,
                  Variant variant, bool allocate = true);
};

}  // namespace osgBTF
