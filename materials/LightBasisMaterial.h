// osgBTF: the render side of a light-basis method, written once: per texel and view slot, RGB
// coefficients of a fixed basis of the light direction,
//
//   f_c(x, v, l) = max(0, sum_j w_j(v) sum_k c_{k,c}(x, s_j) b_k(l))
//
// with one slot (front: fitted on one measured view and used for every view) or one slot per
// measured view (all: blended over the up to 3 Delaunay-neighbour views with the exact weights of
// materials/DirectionLookup.h). ptm (monomials of l_x, l_y) and hsh (hemispherical harmonics) are
// this model; their fits share fit/LightBasisFit.h. What the class holds for them: the shape
// checks, the arrays (coefficients; optionally a second per-slot RGB array the field multiplies,
// ptm's luminance colour), the CPU evaluation and its filtering hooks, the memory count, the file
// (parameters views, frontView and the method's own; textures coefficients and the second
// array), the StateSet (samplers <method>Coefficients on unit 0, the second array's on unit 1,
// <method>ViewTable on the next) and the shader defines OSGBTF_<METHOD>_PER_VIEW and
// OSGBTF_<METHOD>_FILTERED after the method's own.
//
// A method derives Self from LightBasisMaterial<Self, Data> (Data derives from LightBasisData
// and holds `struct Shape` with at least `perView` and `storage`, and `Shape _shape`), and gives,
// beside MethodMaterial's kMethod:
//   int layersPerSlot() const;                          coefficient layers per view slot
//   static T lightTerms(const glm::vec3& light);        what field() needs of a light (any type)
//   glm::vec3 field(std::size_t texel, int slot, const T&) const;   unclamped, the shader's floats
//   static void readShape(const FittedMaterial&, Shape&);    its own parameters (fail() if bad)
//   void writeShape(FittedMaterial&) const;
//   std::vector<std::string> shapeDefines() const;      its own defines, first
// and may shadow: checkShape(const Shape&) (throws Error), kTooManyLayersHint (appended to the
// layer-count error), and for a second array kSecondArray (its texture name, the sampler
// <method><Name>), storesSecondArray(const Shape&), secondArray() (the StoredValues member).
// relight's rbf is not one (materials/README.md, "Light-basis methods").
#pragma once

#include <cctype>
#include <string>
#include <vector>

#include <glm/common.hpp>
#include <osg/StateSet>
#include <osg/Uniform>

#include "core/Error.h"
#include "materials/DirectionLookup.h"
#include "materials/MaterialMath.h"
#include "materials/MaterialState.h"
#include "materials/MethodMaterial.h"
#include "materials/StoredValues.h"

namespace osgBTF {

/** What every light-basis material holds, beside its Data's Shape (materials/MethodMaterial.h). */
struct LightBasisData {
    /** [slot * layersPerSlot() + layer][y][x][3], rows bottom-up (the texture's layout), half or
     *  float as stored (materials/StoredValues.h). */
    StoredValues coefficients;

protected:
    int _slots = 0;
    std::size_t _frontView = 0;
    DirectionLookup _viewLookup;           ///< views=all only
    std::vector<glm::vec3> _lightVectors;  ///< measured lights, for evaluateMeasured
};

template <class Self, class Data>
class LightBasisMaterial : public MethodMaterial<Self, Data> {
public:
    using Shape = typename Data::Shape;

    /** A zero model of the given shape (tests, files of other tools); `frontView` is the measured
     *  view a front model was fitted on. Throws Error for shapes the fit refuses. */
    static osg::ref_ptr<Self> create(int width, int height, DirectionSet views, DirectionSet lights,
                                     Shape shape, std::size_t frontView = 0) {
        osg::ref_ptr<Self> m = new Self;
        m->setShape(width, height, std::move(views), std::move(lights), shape, frontView);
        return m;
    }
    static osg::ref_ptr<Self> fromFile(FittedMaterial file);

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override {
        return finishLinear(evaluateLinear(x, y, view, light), view, light);
    }
    void evaluateMeasured(std::size_t texel, float* abrdf) const override;
    MemoryFootprint memory() const override;
    FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;
    /** Self's shapeDefines(), then OSGBTF_<METHOD>_PER_VIEW and OSGBTF_<METHOD>_FILTERED (the
     *  parameters filtered: TexelFilter::Parameters) as the material has them: the method's
     *  shader holds only the variant's code. */
    std::vector<std::string> shaderDefines() const override;

    const Shape& shape() const { return this->_shape; }
    /** View slots stored: 1 (front) or the measured views (all). */
    int slots() const { return this->_slots; }
    /** The measured view a front model was fitted on (0 when perView). */
    std::size_t frontView() const { return this->_frontView; }
    const DirectionLookup& viewLookup() const { return this->_viewLookup; }
    /** A value at the storage precision (half or float), as the fitter stores it. */
    static float toStorage(double value, MaterialTexture::PixelKind kind) {
        return kind == MaterialTexture::Float ? float(value) : roundHalf(value);
    }

    // Defaults Self may shadow (see the file comment).
    static void checkShape(const Shape&) {}
    static constexpr const char* kTooManyLayersHint = "";
    static constexpr const char* kSecondArray = nullptr;
    static bool storesSecondArray(const Shape&) { return false; }

protected:
    LightBasisMaterial() = default;
    LightBasisMaterial(const LightBasisMaterial& other, const osg::CopyOp& copyop)
        : MethodMaterial<Self, Data>(other, copyop) {}
    ~LightBasisMaterial() override = default;

    /** The view-blended field before the clamp at 0. */
    glm::vec3 evaluateLinear(int x, int y, const glm::vec3& view,
                             const glm::vec3& light) const override;
    /** Measured values are never negative: a dip of the basis below 0 is clamped. */
    glm::vec3 finishLinear(const glm::vec3& linear, const glm::vec3&,
                           const glm::vec3&) const override {
        return glm::max(linear, glm::vec3(0.0f));
    }

    /** Checks the shape, builds the view interpolation and, unless `allocate` is false (a file
     *  brings the arrays), sizes the arrays. */
    void setShape(int width, int height, DirectionSet views, DirectionSet lights, Shape shape,
                  std::size_t frontView, bool allocate = true);

private:
    const Self& self() const { return static_cast<const Self&>(*this); }
    Self& self() { return static_cast<Self&>(*this); }
    static constexpr bool hasSecondArray() { return Self::kSecondArray != nullptr; }
    /** The method's name in upper case, for the defines. */
    static std::string upperMethod() {
        std::string name = Self::kMethod;
        for (char& c : name) c = char(std::toupper(static_cast<unsigned char>(c)));
        return name;
    }
    /** "<method><Name>": the sampler of a texture named `name`. */
    static std::string sampler(const std::string& name) {
        return Self::kMethod +
               std::string(1, char(std::toupper(static_cast<unsigned char>(name[0])))) +
               name.substr(1);
    }
};

// ---- shape -------------------------------------------------------------------------------------

template <class Self, class Data>
void LightBasisMaterial<Self, Data>::setShape(int width, int height, DirectionSet views,
                                              DirectionSet lights, Shape shape,
                                              std::size_t frontView, bool allocate) {
    const std::string method = Self::kMethod;
    if (width <= 0 || height <= 0)
        throw Error(method + ": invalid size " + std::to_string(width) + "x" +
                    std::to_string(height));
    Self::checkShape(shape);
    if (lights.size() == 0) throw Error(method + ": needs at least one measured light");
    if (views.size() == 0) throw Error(method + ": needs at least one measured view");
    if (frontView >= views.size())
        throw Error(method + ": front view " + std::to_string(frontView) + " is not one of the " +
                    std::to_string(views.size()) + " measured views");
    if (shape.storage == MaterialTexture::UNorm8)
        throw Error(method + ": coefficients are stored as half or float, not 8-bit");
    this->_shape = shape;
    this->_slots = shape.perView ? int(views.size()) : 1;
    const int perSlot = self().layersPerSlot();
    const std::size_t layers = std::size_t(this->_slots) * std::size_t(perSlot);
    if (layers > std::size_t(kMaxArrayLayers))
        throw Error(method + ": " + std::to_string(this->_slots) + " views x " +
                    std::to_string(perSlot) + " coefficient layers need " + std::to_string(layers) +
                    " texture layers, more than the " + std::to_string(kMaxArrayLayers) +
                    " OpenGL guarantees" + Self::kTooManyLayersHint);
    const std::size_t texels = std::size_t(width) * std::size_t(height);
    const std::size_t secondValues =
        Self::storesSecondArray(shape) ? texels * std::size_t(this->_slots) * 3 : 0;
    checkMemory(
        std::uint64_t(double(texels * layers * 3 + secondValues) * bytesPerValue(shape.storage)),
        method + " model");
    this->_frontView = shape.perView ? 0 : frontView;
    this->_viewLookup = shape.perView ? DirectionLookup(views) : DirectionLookup();
    this->_lightVectors.clear();
    for (std::size_t l = 0; l < lights.size(); ++l) this->_lightVectors.push_back(lights.vector(l));
    if (allocate) {
        this->coefficients = StoredValues(shape.storage, texels * layers * 3);
        if constexpr (hasSecondArray())
            self().secondArray() = StoredValues(shape.storage, secondValues);
    }
    this->setGeometry(width, height, std::move(views), std::move(lights));
}

// ---- CPU evaluator -----------------------------------------------------------------------------

template <class Self, class Data>
glm::vec3 LightBasisMaterial<Self, Data>::evaluateLinear(int x, int y, const glm::vec3& view,
                                                         const glm::vec3& light) const {
    const std::size_t t = std::size_t(y) * std::size_t(this->_width) + std::size_t(x);
    const auto terms = Self::lightTerms(light);
    if (!this->_shape.perView) return self().field(t, 0, terms);
    const InterpolationWeights w = this->_viewLookup.weights(view);
    glm::vec3 sum(0.0f);
    for (int j = 0; j < 3; ++j)
        if (w.weight[j] > 0.0f) sum += w.weight[j] * self().field(t, w.index[j], terms);
    return sum;
}

template <class Self, class Data>
void LightBasisMaterial<Self, Data>::evaluateMeasured(std::size_t texel, float* abrdf) const {
    std::vector<decltype(Self::lightTerms(glm::vec3()))> lights;
    lights.reserve(this->_lightVectors.size());
    for (const glm::vec3& light : this->_lightVectors) lights.push_back(Self::lightTerms(light));
    for (std::size_t v = 0; v < this->_views.size(); ++v) {
        const int slot = this->_shape.perView ? int(v) : 0;
        for (const auto& terms : lights) {
            const glm::vec3 value = glm::max(self().field(texel, slot, terms), glm::vec3(0.0f));
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
    }
}

// ---- memory ------------------------------------------------------------------------------------

template <class Self, class Data>
MemoryFootprint LightBasisMaterial<Self, Data>::memory() const {
    // Per-texel arrays only: the view table (views=all) is derived from the direction set, not
    // fitted data.
    std::size_t values = this->coefficients.size(), bytes = this->coefficients.bytes();
    if constexpr (hasSecondArray()) {
        values += self().secondArray().size();
        bytes += self().secondArray().bytes();
    }
    const double texels = double(this->texelCount());
    return {double(values) / texels, double(bytes) / texels, std::uint64_t(bytes)};
}

// ---- save / load -------------------------------------------------------------------------------

template <class Self, class Data>
FittedMaterial LightBasisMaterial<Self, Data>::toFittedMaterial() const {
    FittedMaterial file = this->writeCommon();
    self().writeShape(file);
    file.parameters["views"] = this->_shape.perView ? "all" : "front";
    file.parameters["frontView"] = std::to_string(this->_frontView);
    const int w = this->_width, h = this->_height;
    file.textures.push_back(
        this->coefficients.texture("coefficients", w, h, this->_slots * self().layersPerSlot(), 3));
    if constexpr (hasSecondArray())
        if (Self::storesSecondArray(this->_shape))
            file.textures.push_back(
                self().secondArray().texture(Self::kSecondArray, w, h, this->_slots, 3));
    return file;
}

template <class Self, class Data>
osg::ref_ptr<Self> LightBasisMaterial<Self, Data>::fromFile(FittedMaterial file) {
    osg::ref_ptr<Self> m = new Self;
    m->readCommon(file);
    Shape shape;
    Self::readShape(file, shape);
    const std::string views = file.parameter("views");
    if (views != "front" && views != "all")
        fail(file.source, "parameter 'views' must be front or all, got '" + views + "'");
    std::size_t frontView = 0;
    try {
        frontView = std::size_t(std::stoul(file.parameter("frontView")));
    } catch (const std::logic_error&) {
        fail(file.source, "parameter 'frontView' is not an integer");
    }
    MaterialTexture& coefficients = file.texture("coefficients");
    shape.perView = views == "all";
    shape.storage = coefficients.kind;
    const int width = m->_width, height = m->_height;
    try {
        // No arrays: the file's are taken below (sized zeros would double the peak).
        m->setShape(width, height, m->_views, m->_lights, shape, frontView, false);
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    // The file is this function's own: its values are taken.
    const auto take = [&](MaterialTexture& t, int depth, StoredValues& into) {
        if (t.width != width || t.height != height || t.depth != depth || t.channels != 3 ||
            t.kind != shape.storage)
            fail(file.source, "texture '" + t.name + "' must be " + std::to_string(width) + "x" +
                                  std::to_string(height) + ", " + std::to_string(depth) +
                                  " layer(s) of RGB " + MaterialTexture::kindName(shape.storage));
        into = StoredValues::take(t, shape.storage);
        if (!into.allFinite())
            fail(file.source, "texture '" + t.name + "' holds non-finite values");
    };
    take(coefficients, m->_slots * m->layersPerSlot(), m->coefficients);
    if constexpr (hasSecondArray())
        if (Self::storesSecondArray(shape))
            take(file.texture(Self::kSecondArray), m->_slots, m->secondArray());
    return m;
}

// ---- StateSet ----------------------------------------------------------------------------------

template <class Self, class Data>
osg::ref_ptr<osg::StateSet> LightBasisMaterial<Self, Data>::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    const int w = this->_width, h = this->_height;
    addTexture(
        *stateSet,
        createFloatTextureArray(this->coefficients.texture(
                                    "coefficients", w, h, this->_slots * self().layersPerSlot(), 3),
                                this->filtersParameters())
            .get(),
        sampler("coefficients"), 0);
    // Samplers the variant never reads still get units of their own: GL refuses to draw when
    // samplers of different types share a unit, and an unset sampler is unit 0.
    int unit = 1;
    if constexpr (hasSecondArray()) {
        if (Self::storesSecondArray(this->_shape))
            addTexture(*stateSet,
                       createFloatTextureArray(
                           self().secondArray().texture(Self::kSecondArray, w, h, this->_slots, 3))
                           .get(),
                       sampler(Self::kSecondArray), unit);
        else
            stateSet->addUniform(new osg::Uniform(sampler(Self::kSecondArray).c_str(), unit));
        ++unit;
    }
    if (this->_shape.perView)
        this->_viewLookup.addToStateSet(*stateSet, sampler("viewTable"), unit);
    else
        stateSet->addUniform(new osg::Uniform(sampler("viewTable").c_str(), unit));
    // The method's shape and the view model are the program's (shaderDefines), not uniforms.
    return stateSet;
}

template <class Self, class Data>
std::vector<std::string> LightBasisMaterial<Self, Data>::shaderDefines() const {
    std::vector<std::string> defines = self().shapeDefines();
    const std::string prefix = "OSGBTF_" + upperMethod();
    if (this->_shape.perView) defines.push_back(prefix + "_PER_VIEW");
    if (this->filtersParameters()) defines.push_back(prefix + "_FILTERED");
    return defines;
}

}  // namespace osgBTF
