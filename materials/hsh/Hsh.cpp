// Reads top to bottom: the basis, shape and storage, CPU evaluator, memory, save/load, StateSet
// builder, registration (the fitter is HshFit.cpp, in libosgBTFFit). The model: Hsh.h.
#include "materials/hsh/Hsh.h"

#include <algorithm>
#include <cmath>

#include <glm/common.hpp>
#include <osg/Uniform>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "materials/MaterialMath.h"
#include "materials/MaterialState.h"
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

// ---- shape and storage -------------------------------------------------------------------------

float HshMaterial::toStorage(double value, MaterialTexture::PixelKind kind) {
    return kind == MaterialTexture::Float ? float(value) : roundHalf(value);
}

void HshMaterial::setShape(int width, int height, DirectionSet views, DirectionSet lights,
                           Shape shape, std::size_t frontView, bool allocate) {
    if (width <= 0 || height <= 0)
        throw Error("hsh: invalid size " + std::to_string(width) + "x" + std::to_string(height));
    if (shape.order < 2 || shape.order > 4)
        throw Error("hsh: order " + std::to_string(shape.order) + " is not 2, 3 or 4");
    if (lights.size() == 0) throw Error("hsh: needs at least one measured light");
    if (views.size() == 0) throw Error("hsh: needs at least one measured view");
    if (frontView >= views.size())
        throw Error("hsh: front view " + std::to_string(frontView) + " is not one of the " +
                    std::to_string(views.size()) + " measured views");
    if (shape.storage == MaterialTexture::UNorm8)
        throw Error("hsh: coefficients are stored as half or float, not 8-bit");
    _shape = shape;
    _slots = shape.perView ? int(views.size()) : 1;
    const std::size_t layers = std::size_t(_slots) * std::size_t(terms());
    if (layers > std::size_t(kMaxArrayLayers))
        throw Error("hsh: " + std::to_string(_slots) + " views x " + std::to_string(terms()) +
                    " coefficient layers need " + std::to_string(layers) +
                    " texture layers, more than the " + std::to_string(kMaxArrayLayers) +
                    " OpenGL guarantees (use views=front or a lower order)");
    const std::size_t texels = std::size_t(width) * std::size_t(height);
    checkMemory(std::uint64_t(double(texels * layers * 3) * bytesPerValue(shape.storage)),
                "hsh model");
    _frontView = shape.perView ? 0 : frontView;
    _viewLookup = shape.perView ? DirectionLookup(views) : DirectionLookup();
    _lightVectors.clear();
    for (std::size_t l = 0; l < lights.size(); ++l) _lightVectors.push_back(lights.vector(l));
    if (allocate) coefficients = StoredValues(shape.storage, texels * layers * 3);
    setGeometry(width, height, std::move(views), std::move(lights));
}

osg::ref_ptr<HshMaterial> HshMaterial::create(int width, int height, DirectionSet views,
                                              DirectionSet lights, Shape shape,
                                              std::size_t frontView) {
    osg::ref_ptr<HshMaterial> m = new HshMaterial;
    m->setShape(width, height, std::move(views), std::move(lights), shape, frontView);
    return m;
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

glm::vec3 HshMaterial::evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const {
    return finishLinear(evaluateLinear(x, y, view, light), view, light);
}

glm::vec3 HshMaterial::evaluateLinear(int x, int y, const glm::vec3& view,
                                      const glm::vec3& light) const {
    const std::size_t t = std::size_t(y) * std::size_t(_width) + std::size_t(x);
    const Basis h = basis(light);
    if (!_shape.perView) return field(t, 0, h);
    const InterpolationWeights w = _viewLookup.weights(view);
    glm::vec3 sum(0.0f);
    for (int j = 0; j < 3; ++j)
        if (w.weight[j] > 0.0f) sum += w.weight[j] * field(t, w.index[j], h);
    return sum;
}

glm::vec3 HshMaterial::finishLinear(const glm::vec3& linear, const glm::vec3&,
                                    const glm::vec3&) const {
    // Measured values are never negative: a dip of the harmonics below 0 is clamped.
    return glm::max(linear, glm::vec3(0.0f));
}

void HshMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    std::vector<Basis> bases;
    bases.reserve(_lightVectors.size());
    for (const glm::vec3& light : _lightVectors) bases.push_back(basis(light));
    for (std::size_t v = 0; v < _views.size(); ++v) {
        const int slot = _shape.perView ? int(v) : 0;
        for (const Basis& h : bases) {
            const glm::vec3 value = glm::max(field(texel, slot, h), glm::vec3(0.0f));
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
    }
}

// ---- memory ------------------------------------------------------------------------------------

MemoryFootprint HshMaterial::memory() const {
    // Per-texel arrays only: the view table (views=all) is derived from the direction set.
    const double values = double(coefficients.size()), bytes = double(coefficients.bytes());
    return {values / double(texelCount()), bytes / double(texelCount()), std::uint64_t(bytes)};
}

// ---- save / load -------------------------------------------------------------------------------

FittedMaterial HshMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["order"] = std::to_string(_shape.order);
    file.parameters["views"] = _shape.perView ? "all" : "front";
    file.parameters["frontView"] = std::to_string(_frontView);
    file.textures.push_back(
        coefficients.texture("coefficients", _width, _height, _slots * terms(), 3));
    return file;
}

osg::ref_ptr<HshMaterial> HshMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<HshMaterial> m = new HshMaterial;
    m->readCommon(file);
    const std::string order = file.parameter("order"), views = file.parameter("views");
    if (order != "2" && order != "3" && order != "4")
        fail(file.source, "parameter 'order' must be 2, 3 or 4, got '" + order + "'");
    if (views != "front" && views != "all")
        fail(file.source, "parameter 'views' must be front or all, got '" + views + "'");
    std::size_t frontView = 0;
    try {
        frontView = std::size_t(std::stoul(file.parameter("frontView")));
    } catch (const std::logic_error&) {
        fail(file.source, "parameter 'frontView' is not an integer");
    }
    MaterialTexture& coefficients = file.texture("coefficients");
    Shape shape;
    shape.order = order[0] - '0';
    shape.perView = views == "all";
    shape.storage = coefficients.kind;
    try {
        // No arrays: the file's are taken below (sized zeros would double the peak).
        m->setShape(m->_width, m->_height, m->_views, m->_lights, shape, frontView, false);
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    const int layers = m->_slots * m->terms();
    if (coefficients.width != m->_width || coefficients.height != m->_height ||
        coefficients.depth != layers || coefficients.channels != 3)
        fail(file.source, "texture 'coefficients' must be " + std::to_string(m->_width) + "x" +
                              std::to_string(m->_height) + ", " + std::to_string(layers) +
                              " layer(s) of RGB");
    // The file is this function's own: its values are taken.
    m->coefficients = StoredValues::take(coefficients, shape.storage);
    if (!m->coefficients.allFinite())
        fail(file.source, "texture 'coefficients' holds non-finite values");
    return m;
}

// ---- StateSet ----------------------------------------------------------------------------------

osg::ref_ptr<osg::StateSet> HshMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addTexture(*stateSet,
               createFloatTextureArray(
                   coefficients.texture("coefficients", _width, _height, _slots * terms(), 3),
                   filtersParameters())
                   .get(),
               "hshCoefficients", 0);
    // The view table's sampler gets a unit of its own even when unread (GL refuses samplers of
    // different types on one unit, and an unset sampler is unit 0).
    if (_shape.perView)
        _viewLookup.addToStateSet(*stateSet, "hshViewTable", 1);
    else
        stateSet->addUniform(new osg::Uniform("hshViewTable", 1));
    // The order and the view model are the program's (shaderDefines), not uniforms.
    return stateSet;
}

std::vector<std::string> HshMaterial::shaderDefines() const {
    std::vector<std::string> defines = {"OSGBTF_HSH_TERMS " + std::to_string(terms())};
    if (_shape.perView) defines.push_back("OSGBTF_HSH_PER_VIEW");
    if (filtersParameters()) defines.push_back("OSGBTF_HSH_FILTERED");
    return defines;
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
