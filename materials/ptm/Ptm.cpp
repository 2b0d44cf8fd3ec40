// Reads top to bottom: shape and storage, options, CPU evaluator, memory, save/load, StateSet
// builder, registration (the fitter is PtmFit.cpp, in libosgBTFFit). The model and its equation:
// Ptm.h.
#include "materials/ptm/Ptm.h"

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
#include "materials/RelightLayoutWriter.h"
#include "materials/ptm/PtmFile.h"

namespace osgBTF {

// ---- shape and storage -------------------------------------------------------------------------

float PtmMaterial::toStorage(double value, MaterialTexture::PixelKind kind) {
    return kind == MaterialTexture::Float ? float(value) : roundHalf(value);
}

void PtmMaterial::setShape(int width, int height, DirectionSet views, DirectionSet lights,
                           Shape shape, std::size_t frontView, bool allocate) {
    if (width <= 0 || height <= 0)
        throw Error("ptm: invalid size " + std::to_string(width) + "x" + std::to_string(height));
    if (lights.size() == 0) throw Error("ptm: needs at least one measured light");
    if (views.size() == 0) throw Error("ptm: needs at least one measured view");
    if (frontView >= views.size())
        throw Error("ptm: front view " + std::to_string(frontView) + " is not one of the " +
                    std::to_string(views.size()) + " measured views");
    if (shape.storage == MaterialTexture::UNorm8)
        throw Error("ptm: coefficients are stored as half or float, not 8-bit");
    _shape = shape;
    _slots = shape.perView ? int(views.size()) : 1;
    const std::size_t layers = std::size_t(_slots) * std::size_t(layersPerSlot());
    if (layers > std::size_t(kMaxArrayLayers))
        throw Error("ptm: " + std::to_string(_slots) + " views x " +
                    std::to_string(layersPerSlot()) + " coefficient layers need " +
                    std::to_string(layers) + " texture layers, more than the " +
                    std::to_string(kMaxArrayLayers) + " OpenGL guarantees");
    const std::size_t texels = std::size_t(width) * std::size_t(height);
    const std::size_t colourValues = shape.luminance ? texels * std::size_t(_slots) * 3 : 0;
    checkMemory(
        std::uint64_t(double(texels * layers * 3 + colourValues) * bytesPerValue(shape.storage)),
        "ptm model");
    _frontView = shape.perView ? 0 : frontView;
    _viewLookup = shape.perView ? DirectionLookup(views) : DirectionLookup();
    _lightVectors.clear();
    for (std::size_t l = 0; l < lights.size(); ++l) _lightVectors.push_back(lights.vector(l));
    if (allocate) {
        coefficients = StoredValues(shape.storage, texels * layers * 3);
        colour = StoredValues(shape.storage, colourValues);
    }
    setGeometry(width, height, std::move(views), std::move(lights));
}

osg::ref_ptr<PtmMaterial> PtmMaterial::create(int width, int height, DirectionSet views,
                                              DirectionSet lights, Shape shape,
                                              std::size_t frontView) {
    osg::ref_ptr<PtmMaterial> m = new PtmMaterial;
    m->setShape(width, height, std::move(views), std::move(lights), shape, frontView);
    return m;
}

std::array<double, PtmMaterial::kTerms> PtmMaterial::monomials(const glm::vec3& light) {
    const double x = light.x, y = light.y;
    return {x * x, y * y, x * y, x, y, 1.0};
}

float PtmMaterial::coefficient(std::size_t texel, int slot, int k, int c) const {
    const std::size_t texels = texelCount();
    if (_shape.luminance)
        return coefficients[((std::size_t(slot) * 2 + k / 3) * texels + texel) * 3 + k % 3];
    return coefficients[((std::size_t(slot) * kTerms + k) * texels + texel) * 3 + c];
}

void PtmMaterial::setCoefficient(std::size_t texel, int slot, int k, int c, float value) {
    const std::size_t texels = texelCount();
    if (_shape.luminance)
        coefficients.set(((std::size_t(slot) * 2 + k / 3) * texels + texel) * 3 + k % 3, value);
    else
        coefficients.set(((std::size_t(slot) * kTerms + k) * texels + texel) * 3 + c, value);
}

// ---- CPU evaluator -----------------------------------------------------------------------------

glm::vec3 PtmMaterial::field(std::size_t texel, int slot, float lx, float ly) const {
    // ptm.frag's ptmField, operation for operation.
    const float mx = lx * lx, my = ly * ly, mxy = lx * ly;
    const std::size_t texels = texelCount();
    if (_shape.luminance) {
        float a[3], b[3], rgb[3];
        coefficients.read(((std::size_t(slot) * 2) * texels + texel) * 3, 3, a);
        coefficients.read(((std::size_t(slot) * 2 + 1) * texels + texel) * 3, 3, b);
        float l = b[2];
        l += a[0] * mx;
        l += a[1] * my;
        l += a[2] * mxy;
        l += b[0] * lx;
        l += b[1] * ly;
        colour.read((std::size_t(slot) * texels + texel) * 3, 3, rgb);
        return glm::vec3(rgb[0], rgb[1], rgb[2]) * l;
    }
    const auto term = [&](int k) {
        const std::size_t p = ((std::size_t(slot) * kTerms + k) * texels + texel) * 3;
        return glm::vec3(coefficients[p], coefficients[p + 1], coefficients[p + 2]);
    };
    glm::vec3 sum = term(5);
    sum += term(0) * mx;
    sum += term(1) * my;
    sum += term(2) * mxy;
    sum += term(3) * lx;
    sum += term(4) * ly;
    return sum;
}

glm::vec3 PtmMaterial::evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const {
    return finishLinear(evaluateLinear(x, y, view, light), view, light);
}

glm::vec3 PtmMaterial::evaluateLinear(int x, int y, const glm::vec3& view,
                                      const glm::vec3& light) const {
    const std::size_t t = std::size_t(y) * std::size_t(_width) + std::size_t(x);
    if (!_shape.perView) return field(t, 0, light.x, light.y);
    const InterpolationWeights w = _viewLookup.weights(view);
    glm::vec3 sum(0.0f);
    for (int j = 0; j < 3; ++j)
        if (w.weight[j] > 0.0f) sum += w.weight[j] * field(t, w.index[j], light.x, light.y);
    return sum;
}

glm::vec3 PtmMaterial::finishLinear(const glm::vec3& linear, const glm::vec3&,
                                    const glm::vec3&) const {
    // Measured values are never negative: a polynomial's dip below 0 is clamped.
    return glm::max(linear, glm::vec3(0.0f));
}

void PtmMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    for (std::size_t v = 0; v < _views.size(); ++v) {
        const int slot = _shape.perView ? int(v) : 0;
        for (const glm::vec3& light : _lightVectors) {
            const glm::vec3 value = glm::max(field(texel, slot, light.x, light.y), glm::vec3(0.0f));
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
    }
}

// ---- memory ------------------------------------------------------------------------------------

MemoryFootprint PtmMaterial::memory() const {
    // Per-texel arrays only; the view table (views=all) is derived from the direction set, not
    // fitted data, and Boßerhoff and Nicoll 2003 Table 2 has nothing shared to count.
    const double values = double(coefficients.size() + colour.size());
    const double bytes = double(coefficients.bytes() + colour.bytes());
    return {values / double(texelCount()), bytes / double(texelCount()), std::uint64_t(bytes)};
}

// ---- save / load -------------------------------------------------------------------------------

FittedMaterial PtmMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["colour"] = _shape.luminance ? "luminance" : "rgb";
    file.parameters["views"] = _shape.perView ? "all" : "front";
    file.parameters["frontView"] = std::to_string(_frontView);
    file.textures.push_back(
        coefficients.texture("coefficients", _width, _height, _slots * layersPerSlot(), 3));
    if (_shape.luminance)
        file.textures.push_back(colour.texture("colour", _width, _height, _slots, 3));
    return file;
}

osg::ref_ptr<PtmMaterial> PtmMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<PtmMaterial> m = new PtmMaterial;
    m->readCommon(file);
    const std::string colourModel = file.parameter("colour"), views = file.parameter("views");
    if (colourModel != "rgb" && colourModel != "luminance")
        fail(file.source, "parameter 'colour' must be rgb or luminance, got '" + colourModel + "'");
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
    shape.luminance = colourModel == "luminance";
    shape.perView = views == "all";
    shape.storage = coefficients.kind;
    try {
        // No arrays: the file's are taken below (sized zeros would double the peak).
        m->setShape(m->_width, m->_height, m->_views, m->_lights, shape, frontView, false);
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    // The file is this function's own: its values are taken.
    const auto take = [&](MaterialTexture& t, int depth, StoredValues& into) {
        if (t.width != m->_width || t.height != m->_height || t.depth != depth || t.channels != 3 ||
            t.kind != shape.storage)
            fail(file.source, "texture '" + t.name + "' must be " + std::to_string(m->_width) +
                                  "x" + std::to_string(m->_height) + ", " + std::to_string(depth) +
                                  " layer(s) of RGB " + MaterialTexture::kindName(shape.storage));
        into = StoredValues::take(t, shape.storage);
        if (!into.allFinite())
            fail(file.source, "texture '" + t.name + "' holds non-finite values");
    };
    take(coefficients, m->_slots * m->layersPerSlot(), m->coefficients);
    if (shape.luminance) take(file.texture("colour"), m->_slots, m->colour);
    return m;
}

// ---- StateSet ----------------------------------------------------------------------------------

osg::ref_ptr<osg::StateSet> PtmMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addTexture(*stateSet,
               createFloatTextureArray(coefficients.texture("coefficients", _width, _height,
                                                            _slots * layersPerSlot(), 3),
                                       filtersParameters())
                   .get(),
               "ptmCoefficients", 0);
    // Samplers the variant never reads still get units of their own: GL refuses to draw when
    // samplers of different types share a unit, and an unset sampler is unit 0.
    if (_shape.luminance)
        addTexture(
            *stateSet,
            createFloatTextureArray(colour.texture("colour", _width, _height, _slots, 3)).get(),
            "ptmColour", 1);
    else
        stateSet->addUniform(new osg::Uniform("ptmColour", 1));
    if (_shape.perView)
        _viewLookup.addToStateSet(*stateSet, "ptmViewTable", 2);
    else
        stateSet->addUniform(new osg::Uniform("ptmViewTable", 2));
    // The colour and view models are the program's (shaderDefines), not uniforms.
    return stateSet;
}

std::vector<std::string> PtmMaterial::shaderDefines() const {
    std::vector<std::string> defines;
    if (_shape.luminance) defines.push_back("OSGBTF_PTM_LUMINANCE");
    if (_shape.perView) defines.push_back("OSGBTF_PTM_PER_VIEW");
    if (filtersParameters()) defines.push_back("OSGBTF_PTM_FILTERED");
    return defines;
}

// ---- registration ------------------------------------------------------------------------------

namespace {
const bool ptmRegistered = registerMethodClass<PtmMaterial>([] {
    MethodInfo m;
    m.description =
        "polynomial texture maps (Malzbender 2001, as Boßerhoff and Nicoll 2003 use them): per "
        "texel a biquadratic in the "
        "light's (l_x, l_y), per channel or on the luminance times a base colour, fitted by one "
        "shared pseudo-inverse; on the front view or one per view, blended";
    m.options = {
        OptionSpec::choice("colour", "rgb", {"rgb", "luminance"},
                           "rgb: a polynomial per channel (18 coefficients per texel); luminance: "
                           "one on the Rec. 709 luminance times an RGB base colour of unit "
                           "luminance (6 + 3)"),
        OptionSpec::choice("views", "front", {"front", "all"},
                           "front: one PTM fitted on the measured view nearest the normal, used "
                           "for every view (the paper's); all: one PTM per measured view, blended "
                           "over the 3 Delaunay-neighbour views"),
        OptionSpec::choice("storage", "half", {"half", "float"},
                           "precision of the coefficients and the colour")};
    // A polynomial in the light whose coefficients are per texel (luminance materials excepted:
    // PtmMaterial::linearInParameters).
    m.filtersParameters = true;
    m.shaderCost = [](const Material& material) {
        // ptmField: monomials 3; rgb: layer base 1, 5 layer offsets, 6 fetches, 5 multiply-adds
        // (10) = 19 ALU, 6 TEX; luminance: layer addresses 3, 5 multiply-adds (10), colour
        // multiply 1 = 17 ALU, 3 TEX (the colour model and the view model are compiled in:
        // PtmMaterial::shaderDefines, no test). btfEvaluate: the final max 1; views=all adds the
        // view lookup and per blended view (3) loop 2, weight test 1, weighted add 2.
        const PtmMaterial& m = static_cast<const PtmMaterial&>(material);
        const bool luminance = m.shape().luminance;
        const int fieldAlu = luminance ? 17 : 19, fieldTex = luminance ? 3 : 6;
        const std::string variant = luminance ? "luminance" : "rgb";
        if (!m.shape().perView)
            return ShaderCost::ofEvaluate(1 + fieldAlu, fieldTex,
                                          "ALU " + std::to_string(1 + fieldAlu) + ", TEX " +
                                              std::to_string(fieldTex) + " (" + variant +
                                              ", front view)");
        const DirectionLookup::Cost v = m.viewLookup().cost();
        const int alu = 1 + 3 * (5 + fieldAlu), tex = 3 * fieldTex;
        return ShaderCost::ofEvaluate(v.alu + alu, v.tex + tex,
                                      "ALU " + std::to_string(alu) + "+L, TEX " +
                                          std::to_string(tex) + "+T (" + variant +
                                          ", views=all; L = " + std::to_string(v.alu) +
                                          ", T = " + std::to_string(v.tex) + ": the view lookup)");
    };
    m.order = 80;
    m.fitWorkingSet = 0.75;  // per-view least squares
    ForeignFileFormat ptmFile;
    ptmFile.extension = ".ptm";
    ptmFile.description =
        "Polynomial Texture Map file (PTM_1.2; PTM_FORMAT_RGB, _LRGB, _JPEG_RGB, _JPEG_LRGB): "
        "RTIBuilder's, "
        "RTIViewer's";
    ptmFile.read = [](const std::string& path) -> osg::ref_ptr<Material> {
        return readPtmFile(path);
    };
    ptmFile.write = [](const Material& material, const std::string& path) {
        const PtmQuantisation q = writePtmFile(static_cast<const PtmMaterial&>(material), path);
        return "8-bit coefficients: largest change " + floatText(float(q.largestCoefficientError)) +
               " (largest step " + floatText(float(q.largestStep)) + ")";
    };
    ptmFile.info = [](const std::string& path) {
        const PtmFileHeader h = parsePtmHeader(path, readWholeFile(path), false);
        std::string text = "PTM_1.2 " + h.format + ", " + std::to_string(h.width) + "x" +
                           std::to_string(h.height) + "\nscales:";
        for (const float s : h.scale) text += " " + floatText(s);
        text += "\nbiases:";
        for (const int b : h.bias) text += " " + std::to_string(b);
        return text;
    };
    m.foreignFiles.push_back(std::move(ptmFile));
    // relight's web layout, whatever its type (materials/RelightFolder.h): the folder's info.json.
    // Registered here, the RTI field's first basis; each type's method reads its own.
    ForeignFileFormat relightFolder;
    relightFolder.extension = "info.json";
    relightFolder.description =
        "relight's web layout as OpenLIME loads it (info.json + plane_N.jpg or deep-zoom "
        "pyramids; types ptm, hsh (colorspaces rgb, lrgb), rbf and bilinear (mrgb, mycc))";
    relightFolder.read = [](const std::string& path) { return readRelightMaterial(path); };
    relightFolder.info = [](const std::string& path) { return relightInfo(path); };
    // Written for every method that registered a relight writer (RelightLayoutWriter.h).
    relightFolder.methods = [] { return relightWriterMethods(); };
    relightFolder.write = [](const Material& material, const std::string& path) {
        return writeRelightLayout(material, path);
    };
    m.foreignFiles.push_back(std::move(relightFolder));
    return m;
}());
const bool kRelightPtmWriter =
    registerRelightWriter("ptm", [](const Material& material, const std::string& path) {
        return relightModelOfPtm(static_cast<const PtmMaterial&>(material), path);
    });
const bool kRelightPtm = registerRelightType(
    "ptm", [](const std::string& path, const RelightPlanes& planes) -> osg::ref_ptr<Material> {
        return ptmMaterialFromRelight(path, planes);
    });
}  // namespace

}  // namespace osgBTF
