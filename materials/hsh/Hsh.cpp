// Reads top to bottom: the basis, the order and the coefficients, the CPU field, the order in file
// and shader, registration (the fitter is HshFit.cpp, in libosgBTFFit). Shape checks, view
// blending, memory, file, StateSet: materials/LightBasisMaterial.h. The model: Hsh.h.
#include "materials/hsh/Hsh.h"

#include <algorithm>
#include <cmath>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "materials/MaterialMath.h"
#include "materials/MethodRegistry.h"
#include "materials/RelightFolder.h"
#include "materials/hsh/RtiFile.h"

namespace osgBTF {

// ---- the basis ---------------------------------------------------------------------------------

namespace {

/** hsh.frag's hshBasis, operation for operation, in T. The constants are the normalisations of
 *  Hsh.h (float: the literals of hsh.frag). */
template <class T>
std::array<T, HshMaterial::kMaxTerms> hshBasisIn(const glm::vec3& light) {
    const T k0 = T(0.398942280401432678), k1 = T(1.38197659788534191), k2 = T(0.690988298942670955),
            k4 = T(3.09019361618551662), k6 = T(0.892062058076385580), k9 = T(6.67558117812454546),
            k10 = T(8.17588381146625816), k11 = T(5.17088294582641097),
            k12 = T(1.05550206141118805);
    const T x = T(light.x), y = T(light.y);
    const T t = std::clamp(T(light.z), T(0), T(1));
    const T r = std::sqrt(x * x + y * y);
    const T cp = r > T(0) ? x / r : T(1);
    const T sp = r > T(0) ? y / r : T(0);
    const T t2 = t * t;
    const T w = t2 - t;  // <= 0 on [0, 1], also after rounding (t * t rounds to at most t)
    const T s = std::sqrt(-w);
    const T a = T(2) * t - T(1);
    const T c2 = cp * cp - sp * sp, s2 = T(2) * sp * cp;
    const T c3 = cp * (T(4) * cp * cp - T(3)), s3 = sp * (T(3) - T(4) * sp * sp);
    const T q = T(1) - T(5) * t + T(5) * t2;
    const T s3t = -w * s;  // s^3
    return {k0,
            k1 * cp * s,
            k2 * a,
            k1 * sp * s,
            k4 * c2 * w,
            k4 * cp * a * s,
            k6 * (T(1) - T(6) * t + T(6) * t2),
            k4 * sp * a * s,
            k4 * s2 * w,
            k9 * c3 * s3t,
            k10 * c2 * a * w,
            k11 * cp * s * q,
            k12 * (T(-1) + T(12) * t - T(30) * t2 + T(20) * t2 * t),
            k11 * sp * s * q,
            k10 * s2 * a * w,
            k9 * s3 * s3t};
}

}  // namespace

HshMaterial::Basis HshMaterial::basis(const glm::vec3& light) {
    return hshBasisIn<float>(light);
}

std::array<double, HshMaterial::kMaxTerms> HshMaterial::basisDouble(const glm::vec3& light) {
    return hshBasisIn<double>(light);
}

// ---- shape and coefficients --------------------------------------------------------------------
// (setShape, create: LightBasisMaterial's.)

void HshMaterial::checkShape(const Shape& shape) {
    if (shape.order < 2 || shape.order > 4)
        throw Error("hsh: order " + std::to_string(shape.order) + " is not 2, 3 or 4");
}

float HshMaterial::coefficient(std::size_t texel, int slot, int k, int c) const {
    return coefficients
        [((std::size_t(slot) * std::size_t(terms()) + std::size_t(k)) * texelCount() + texel) * 3 +
         std::size_t(c)];
}

void HshMaterial::setCoefficient(std::size_t texel, int slot, int k, int c, float value) {
    coefficients.set(
        ((std::size_t(slot) * std::size_t(terms()) + std::size_t(k)) * texelCount() + texel) * 3 +
            std::size_t(c),
        value);
}

// ---- CPU evaluator -----------------------------------------------------------------------------

glm::vec3 HshMaterial::field(std::size_t texel, int slot, const Basis& h) const {
    // hsh.frag's hshField, operation for operation.
    const std::size_t texels = texelCount(), n = std::size_t(terms());
    glm::vec3 sum(0.0f);
    for (std::size_t k = 0; k < n; ++k) {
        const std::size_t p = ((std::size_t(slot) * n + k) * texels + texel) * 3;
        sum += glm::vec3(coefficients[p], coefficients[p + 1], coefficients[p + 2]) * h[k];
    }
    return sum;
}

// ---- file and shader (the rest is LightBasisMaterial's) -----------------------------------------

void HshMaterial::readShape(const FittedMaterial& file, Shape& shape) {
    const std::string order = file.parameter("order");
    if (order != "2" && order != "3" && order != "4")
        fail(file.source, "parameter 'order' must be 2, 3 or 4, got '" + order + "'");
    shape.order = order[0] - '0';
}

void HshMaterial::writeShape(FittedMaterial& file) const {
    file.parameters["order"] = std::to_string(_shape.order);
}

std::vector<std::string> HshMaterial::shapeDefines() const {
    // The order is the program's, not a uniform: hsh.frag's loops run to a constant.
    return {"OSGBTF_HSH_TERMS " + std::to_string(terms())};
}

// ---- registration ------------------------------------------------------------------------------

namespace {
const bool hshRegistered = registerMethodClass<HshMaterial>([] {
    MethodInfo m;
    m.description =
        "hemispherical harmonics (Gautron et al. 2004), the RTI field's fit: per texel and "
        "channel 4, 9 or 16 coefficients of the RTI tools' basis of the light direction, fitted by "
        "one shared pseudo-inverse; on the front view or one per view, blended";
    m.options = {
        OptionSpec::integer("order", 3, 2, 4,
                            "harmonics up to this order: 2, 3 or 4 give 4, 9 or 16 coefficients "
                            "per channel (RTIBuilder's HSH orders)"),
        OptionSpec::choice("views", "front", {"front", "all"},
                           "front: one fit on the measured view nearest the normal, used for "
                           "every view (an RTI capture has one view); all: one per measured view, "
                           "blended over the 3 Delaunay-neighbour views"),
        OptionSpec::choice("storage", "half", {"half", "float"}, "precision of the coefficients")};
    // Linear in its per-texel coefficients, clamped after the blend (finishLinear).
    m.filtersParameters = true;
    m.shaderCost = [](const Material& material) {
        // hshBasis: ~45 ALU (sqrt 2, divisions 2, the 16 products and sums); hshField: per term a
        // layer address 1, a fetch and a multiply-add (2), the loop to a constant unrolled (the
        // order and the view model are compiled in: HshMaterial::shaderDefines, no test);
        // btfEvaluate: the final max 1; views=all adds the view lookup and per blended view (3)
        // loop 2, weight test 1, weighted add 2.
        const HshMaterial& m = static_cast<const HshMaterial&>(material);
        const int n = m.terms(), field = 3 * n, basisAlu = 45;
        if (!m.shape().perView)
            return ShaderCost::ofEvaluate(1 + basisAlu + field, n,
                                          "ALU " + std::to_string(1 + basisAlu + field) + ", TEX " +
                                              std::to_string(n) + " (" + std::to_string(n) +
                                              " terms, front view)");
        const DirectionLookup::Cost v = m.viewLookup().cost();
        const int alu = 1 + basisAlu + 3 * (5 + field), tex = 3 * n;
        return ShaderCost::ofEvaluate(v.alu + alu, v.tex + tex,
                                      "ALU " + std::to_string(alu) + "+L, TEX " +
                                          std::to_string(tex) + "+T (" + std::to_string(n) +
                                          " terms, views=all; L = " + std::to_string(v.alu) +
                                          ", T = " + std::to_string(v.tex) + ": the view lookup)");
    };
    m.order = 85;
    m.fitWorkingSet = 0.75;  // per-view least squares, as ptm
    ForeignFileFormat rtiFile;
    rtiFile.extension = ".rti";
    rtiFile.description = "RTI file of hemispherical harmonics (type 3): RTIBuilder's, RTIViewer's";
    rtiFile.read = [](const std::string& path) -> osg::ref_ptr<Material> {
        return readRtiFile(path);
    };
    rtiFile.write = [](const Material& material, const std::string& path) {
        const auto [error, step] = writeRtiFile(static_cast<const HshMaterial&>(material), path);
        return "8-bit terms: largest change " + floatText(float(error)) + " (largest step " +
               floatText(float(step)) + ")";
    };
    rtiFile.info = [](const std::string& path) {
        const RtiFileHeader h = parseRtiHeader(path, readWholeFile(path), false);
        std::string text = "RTI type 3 (hemispherical harmonics), " + std::to_string(h.width) +
                           "x" + std::to_string(h.height) + ", " + std::to_string(h.terms) +
                           " terms per band, basis type " + std::to_string(h.basisType) +
                           "\nterm ranges:";
        for (int k = 0; k < h.terms; ++k)
            text += " [" + floatText(h.minimum[std::size_t(k)]) + ", " +
                    floatText(h.maximum[std::size_t(k)]) + "]";
        return text;
    };
    m.foreignFiles.push_back(std::move(rtiFile));
    return m;
}());
const bool kRelightHshWriter =
    registerRelightWriter("hsh", [](const Material& material, const std::string& path) {
        return relightModelOfHsh(static_cast<const HshMaterial&>(material), path);
    });
const bool kRelightHsh = registerRelightType(
    "hsh", [](const std::string& path, const RelightPlanes& planes) -> osg::ref_ptr<Material> {
        return hshMaterialFromRelight(path, planes);
    });
}  // namespace

}  // namespace osgBTF
