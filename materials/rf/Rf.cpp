// Reads top to bottom: storage layout, options, CPU evaluator, memory, save/load, StateSet
// builder, registration (the fitter is RfFit.cpp, in libosgBTFFit). The model and its equation:
// Rf.h.
#include "materials/rf/Rf.h"

#include <algorithm>
#include <cmath>
#include <limits>
#include <sstream>

#include <glm/geometric.hpp>
#include <osg/Uniform>

#include "core/Error.h"
#include "materials/MaterialMath.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"
#include "materials/rf/RfValues.h"

namespace osgBTF {

// ---- storage layout --------------------------------------------------------------------------

namespace {

/** One array of the model as it is stored (file part, GPU texture): the single description that
 *  save, load, memory accounting and the StateSet builder all read, so they cannot disagree. */
struct StoredArray {
    const char* name;     ///< texture name in the file
    const char* sampler;  ///< GLSL sampler in rf.frag
    int depth;            ///< layers (a Texture2DArray on the GPU when > 1)
    int channels;
    MaterialTexture::PixelKind kind;
    StoredValues RfMaterial::*member;
};

/** Without the diffuse term there is no rhoD array (nothing stored, nothing counted). */
std::vector<StoredArray> storedArrays(std::size_t views, int lobes, RfMaterial::Variant variant) {
    std::vector<StoredArray> arrays;
    if (variant.diffuse)
        arrays.push_back({"rhoD", "rfRhoD", 1, 3, MaterialTexture::UNorm8, &RfMaterial::rhoD});
    arrays.push_back({"rhoV", "rfRhoV", int(views), 3, MaterialTexture::Half, &RfMaterial::rhoV});
    arrays.push_back({"lobes", "rfLobes", int(views) * lobes * (variant.rgb ? 3 : 1), 4,
                      MaterialTexture::Half, &RfMaterial::lobes});
    return arrays;
}

using rf::lobeValue;

}  // namespace

void RfMaterial::setShape(int width, int height, DirectionSet views, DirectionSet lights,
                          int lobeCount, Variant variant, bool allocate) {
    if (width <= 0 || height <= 0)
        throw Error("rf: invalid size " + std::to_string(width) + "x" + std::to_string(height));
    if (lobeCount < 1 || lobeCount > kMaxLobes)
        throw Error("rf: lobes must be between 1 and " + std::to_string(kMaxLobes) + ", got " +
                    std::to_string(lobeCount));
    if (views.size() == 0) throw Error("rf: needs at least one measured view");
    if (lights.size() == 0) throw Error("rf: needs at least one measured light");
    const std::size_t channels = variant.rgb ? 3 : 1;
    const std::size_t layers = views.size() * channels * std::size_t(lobeCount);
    if (layers > std::size_t(kMaxArrayLayers))
        throw Error("rf: " + std::to_string(views.size()) + " views x " +
                    (variant.rgb ? "3 colour channels (colour=rgb) x " : "") +
                    std::to_string(lobeCount) + " lobes need " + std::to_string(layers) +
                    " texture layers, more than the " + std::to_string(kMaxArrayLayers) +
                    " OpenGL guarantees");
    const std::size_t texels = std::size_t(width) * std::size_t(height);
    // 8-bit rho_d, half rho_v and lobes.
    checkMemory(std::uint64_t(texels) *
                    ((variant.diffuse ? 3 : 0) + views.size() * (3 + 4 * channels * lobeCount) * 2),
                "rf model");
    _viewLookup = DirectionLookup(views);
    _lightVectors.clear();
    for (std::size_t l = 0; l < lights.size(); ++l) _lightVectors.push_back(lights.vector(l));
    _lobes = lobeCount;
    _variant = variant;
    if (allocate)
        for (const StoredArray& a : storedArrays(views.size(), lobeCount, variant))
            this->*a.member = StoredValues(a.kind, texels * std::size_t(a.depth * a.channels));
    setGeometry(width, height, std::move(views), std::move(lights));
}

osg::ref_ptr<RfMaterial> RfMaterial::create(int width, int height, DirectionSet views,
                                            DirectionSet lights, int lobeCount, Variant variant) {
    osg::ref_ptr<RfMaterial> m = new RfMaterial;
    m->setShape(width, height, std::move(views), std::move(lights), lobeCount, variant);
    return m;
}

osg::ref_ptr<RfMaterial> RfMaterial::create(int width, int height, DirectionSet views,
                                            DirectionSet lights, int lobeCount) {
    return create(width, height, std::move(views), std::move(lights), lobeCount, Variant());
}

// ---- options ---------------------------------------------------------------------------------

RfMaterial::Settings RfMaterial::settingsFrom(const FitOptions& options) {
    const OptionValues o = validateOptions(kMethod, options);
    Settings s;
    s.lobes = o.integer("lobes");
    s.iterations = o.integer("iterations");
    s.starts = o.integer("starts");
    s.maxExponent = o.number("max-exponent");
    s.variant.diffuse = o.flag("diffuse");
    s.variant.rgb = o.choice("colour") == "rgb";
    return s;
}

// ---- CPU evaluator ---------------------------------------------------------------------------

float RfMaterial::lobeSum(std::size_t texel, std::size_t view, const glm::vec3& light,
                          int channel) const {
    const std::size_t first = (view * std::size_t(lobeChannels()) + channel) * _lobes;
    float sum = 0, lobe[4];
    for (int i = 0; i < _lobes; ++i) {
        lobes.read(((first + i) * texelCount() + texel) * 4, 4, lobe);
        sum += lobeValue(lobe, light);
    }
    return sum;
}

glm::vec3 RfMaterial::reflectanceField(std::size_t texel, std::size_t view,
                                       const glm::vec3& light) const {
    const std::size_t rho = (view * texelCount() + texel) * 3;
    // rho_c times the lobe sum of channel c, in the shader's order (rf.frag).
    const glm::vec3 sum =
        _variant.rgb ? glm::vec3(lobeSum(texel, view, light, 0), lobeSum(texel, view, light, 1),
                                 lobeSum(texel, view, light, 2))
                     : glm::vec3(lobeSum(texel, view, light));
    return glm::vec3(rhoV[rho], rhoV[rho + 1], rhoV[rho + 2]) * sum;
}

glm::vec3 RfMaterial::diffuse(std::size_t texel) const {
    return _variant.diffuse ? glm::vec3(rhoD[texel * 3], rhoD[texel * 3 + 1], rhoD[texel * 3 + 2])
                            : glm::vec3(0.0f);
}

glm::vec3 RfMaterial::evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const {
    const std::size_t t = std::size_t(y) * _width + x;
    const InterpolationWeights w = _viewLookup.weights(view);
    glm::vec3 color = diffuse(t);
    for (int j = 0; j < 3; ++j)
        if (w.weight[j] > 0.0f) color += w.weight[j] * reflectanceField(t, w.index[j], light);
    return color;
}

void RfMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    const glm::vec3 d = diffuse(texel);
    for (std::size_t v = 0; v < _views.size(); ++v)
        for (const glm::vec3& light : _lightVectors) {
            const glm::vec3 value = d + reflectanceField(texel, v, light);
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
}

// ---- memory ----------------------------------------------------------------------------------

MemoryFootprint RfMaterial::memory() const {
    // Per-texel arrays only: the baked view table is derived from the direction set, not fitted
    // data (Meseth et al. 2003 Table 2 does not count it either).
    MemoryFootprint footprint;
    for (const StoredArray& a : storedArrays(_views.size(), _lobes, _variant)) {
        const StoredValues& values = this->*a.member;
        const double perTexel = double(values.size()) / double(texelCount());
        footprint.valuesPerTexel += perTexel;
        footprint.bytesPerTexel += perTexel * bytesPerValue(a.kind);
        footprint.totalBytes += values.bytes();
    }
    return footprint;
}

// ---- save / load -----------------------------------------------------------------------------

FittedMaterial RfMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["lobes"] = std::to_string(_lobes);
    file.parameters["diffuse"] = _variant.diffuse ? "1" : "0";
    file.parameters["colour"] = _variant.rgb ? "rgb" : "luminance";
    for (const StoredArray& a : storedArrays(_views.size(), _lobes, _variant))
        file.textures.push_back(
            (this->*a.member).texture(a.name, _width, _height, a.depth, a.channels));
    return file;
}

osg::ref_ptr<RfMaterial> RfMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<RfMaterial> m = new RfMaterial;
    m->readCommon(file);
    int lobeCount = 0;
    try {
        lobeCount = std::stoi(file.parameter("lobes"));
    } catch (const std::logic_error&) {
        fail(file.source, "parameter 'lobes' is not an integer");
    }
    // Files written before the options "diffuse" and "colour" existed hold the default model.
    Variant variant;
    const auto hasDiffuse = file.parameters.find("diffuse");
    if (hasDiffuse != file.parameters.end()) {
        if (hasDiffuse->second != "0" && hasDiffuse->second != "1")
            fail(file.source, "parameter 'diffuse' must be 0 or 1, got " + hasDiffuse->second);
        variant.diffuse = hasDiffuse->second == "1";
    }
    const auto colour = file.parameters.find("colour");
    if (colour != file.parameters.end()) {
        if (colour->second != "luminance" && colour->second != "rgb")
            fail(file.source, "parameter 'colour' must be luminance or rgb, got " + colour->second);
        variant.rgb = colour->second == "rgb";
    }
    try {
        // No arrays: the file's are taken below (sized zeros would double the peak).
        m->setShape(m->_width, m->_height, m->_views, m->_lights, lobeCount, variant, false);
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    for (const StoredArray& a : storedArrays(m->_views.size(), lobeCount, variant)) {
        MaterialTexture& t = file.texture(a.name);  // the file is ours: its values are taken
        if (t.width != m->_width || t.height != m->_height || t.depth != a.depth ||
            t.channels != a.channels || t.kind != a.kind)
            fail(file.source, std::string("texture '") + a.name + "' must be " +
                                  std::to_string(m->_width) + "x" + std::to_string(m->_height) +
                                  ", " + std::to_string(a.depth) + " layer(s) of " +
                                  std::to_string(a.channels) + " channels, stored as " +
                                  (a.kind == MaterialTexture::UNorm8 ? "8-bit" : "half"));
        StoredValues& values = (*m).*a.member;
        values = StoredValues::take(t, a.kind);
        if (!values.allFinite())
            fail(file.source, std::string("texture '") + a.name + "' holds non-finite values");
    }
    return m;
}

// ---- StateSet --------------------------------------------------------------------------------

osg::ref_ptr<osg::StateSet> RfMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    int unit = 0;
    if (!_variant.diffuse) {
        // The shader samples rfRhoD either way (one program for every variant); without the
        // diffuse term it reads texel (0, 0) of this black 1x1 texture, so the sampler still has
        // a unit of its own type.
        const MaterialTexture black{"rhoD", 1, 1, 1, 3, MaterialTexture::UNorm8, {0, 0, 0}};
        addTexture(*stateSet, createFloatTexture(black).get(), "rfRhoD", unit++);
    }
    for (const StoredArray& a : storedArrays(_views.size(), _lobes, _variant)) {
        const MaterialTexture t =
            (this->*a.member).texture(a.name, _width, _height, a.depth, a.channels);
        // rhoD is one 2D texture; the others are arrays even with one layer (one measured
        // view, one lobe), as the shader samples them.
        if (a.member == &RfMaterial::rhoD)
            addTexture(*stateSet, createFloatTexture(t).get(), a.sampler, unit++);
        else
            addTexture(*stateSet, createFloatTextureArray(t).get(), a.sampler, unit++);
    }
    _viewLookup.addToStateSet(*stateSet, "rfViewTable", unit);
    stateSet->addUniform(new osg::Uniform("rfLobeCount", _lobes));
    stateSet->addUniform(new osg::Uniform("rfLobeChannels", lobeChannels()));
    stateSet->addUniform(new osg::Uniform("rfDiffuse", _variant.diffuse ? 1 : 0));
    return stateSet;
}

// ---- registration ----------------------------------------------------------------------------

namespace {
const bool rfRegistered = registerMethodClass<RfMaterial>([] {
    const RfMaterial::Settings defaults;
    MethodInfo m;
    m.description =
        "reflectance fields (Meseth 2003): per measured view, rho_d + rho_v(v) RGB x k light "
        "lobes (a l_x + b l_y + c l_z)^n, views blended with interpolation weights; diffuse=0 "
        "and colour=rgb give the per-view Lafortune BTF of Boßerhoff and Nicoll 2003";
    m.options = {
        OptionSpec::integer(
            "lobes", defaults.lobes, 1, RfMaterial::kMaxLobes,
            "lobes per view, or per view and colour channel with colour=rgb (8 x 151 "
            "UBO2014 views = 1208 array layers < 2048)"),
        OptionSpec::integer("iterations", defaults.iterations, 1, OptionSpec::kNoLimit,
                            "Levenberg-Marquardt iterations per start"),
        OptionSpec::integer("starts", defaults.starts, 1, 3,
                            "initialisations tried per texel and view while the fit is poor: "
                            "greedy, the left neighbour's lobes, greedy with the lobe at the "
                            "mirror direction"),
        // Above 256 a base a little over 1 overflows half precision; below 1 no cosine fits.
        OptionSpec::number("max-exponent", defaults.maxExponent, 1, 256,
                           "largest lobe exponent n (the Bonn lights are 15 degrees apart: "
                           "sharper lobes are unconstrained between them)"),
        OptionSpec::flag("diffuse", defaults.variant.diffuse,
                         "1: the light- and view-independent floor rho_d (Meseth et al. 2003); 0: "
                         "lobes only, the per-view Lafortune BTF of Boßerhoff and Nicoll 2003"),
        OptionSpec::choice("colour", "luminance", {"luminance", "rgb"},
                           "luminance: k lobes per view times an RGB rho_v (the luminance model of "
                           "Boßerhoff and Nicoll 2003 with its base colour); rgb: k lobes per view "
                           "and colour channel (their RGB model; 3x the lobe layers: Bonn's 81 "
                           "views take up to 8, UBO2014's 151 up to 4)")};
    m.shaderCost = [](const Material& material) {
        // View lookup, rhoD (fetched from a black 1x1 texture without the diffuse term); per
        // blended view (3): weight test, rhoV fetch, per lobe: layer index 2, 3-term dot 5,
        // test, select, pow, add; then 3 for the weighted add. rgb: every lobe once per channel.
        const RfMaterial& m = static_cast<const RfMaterial&>(material);
        const int k = m.lobeCount(), c = m.lobeChannels();
        const DirectionLookup::Cost v = m.viewLookup().cost();
        return ShaderCost::ofEvaluate(
            v.alu + 3 * (4 + 11 * c * k), v.tex + 1 + 3 * (1 + c * k),
            "ALU " + std::to_string(33 * c) + "k+22+L, TEX " + std::to_string(3 * c) +
                "k+4+T (k lobes per view" + (c == 3 ? " and colour channel" : "") + "; L = " +
                std::to_string(v.alu) + ", T = " + std::to_string(v.tex) + ": the view lookup)");
    };
    m.order = 30;
    // Two lobes as the default (the shaders' lobe loop and array layers as fitted files have
    // them), one start of a few iterations: the tests that fit every method check round trips,
    // filtering and lighting, not the fit's quality, and the default fit took 10 s of a 5 x 4
    // sample under AddressSanitizer.
    m.quickFitOptions = "starts=1 iterations=5";
    return m;
}());
}  // namespace

}  // namespace osgBTF
