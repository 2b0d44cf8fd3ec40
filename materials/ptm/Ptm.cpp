// Reads top to bottom: shape and storage, options, fitter, CPU evaluator, memory, save/load,
// StateSet builder, registration. The model and its equation: Ptm.h.
#include "materials/ptm/Ptm.h"

#include <algorithm>
#include <cfloat>
#include <chrono>
#include <cmath>
#include <sstream>

#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>
#include <Eigen/Core>
#include <Eigen/SVD>
#include <glm/common.hpp>
#include <osg/Uniform>

#include "core/Error.h"
#include "core/Progress.h"
#include "materials/MaterialMath.h"
#include "materials/MaterialState.h"

namespace osgBTF {

// ---- shape and storage -------------------------------------------------------------------------

namespace {

constexpr int kMaxLayers = 2048;  // GL_MAX_ARRAY_TEXTURE_LAYERS guaranteed by GL 3.3+

const char* storageName(MaterialTexture::PixelKind kind) {
    return kind == MaterialTexture::Float ? "float" : "half";
}

double bytesPerValue(MaterialTexture::PixelKind kind) {
    return kind == MaterialTexture::Float ? 4 : 2;
}

float toStorage(double value, MaterialTexture::PixelKind kind) {
    return kind == MaterialTexture::Float ? float(value) : roundHalf(value);
}

}  // namespace

PtmMaterial::PtmMaterial(const PtmMaterial& other, const osg::CopyOp& copyop)
    : Material(other, copyop),
      coefficients(other.coefficients),
      colour(other.colour),
      _shape(other._shape),
      _slots(other._slots),
      _frontView(other._frontView),
      _viewLookup(other._viewLookup),
      _lightVectors(other._lightVectors) {}

void PtmMaterial::assignFrom(const Material& other) {
    const PtmMaterial& o = assignCommon<PtmMaterial>(other);
    coefficients = o.coefficients;
    colour = o.colour;
    _shape = o._shape;
    _slots = o._slots;
    _frontView = o._frontView;
    _viewLookup = o._viewLookup;
    _lightVectors = o._lightVectors;
}

void PtmMaterial::setShape(int width, int height, DirectionSet views, DirectionSet lights,
                           Shape shape, std::size_t frontView) {
    if (width <= 0 || height <= 0)
        throw Error("ptm: invalid size " + std::to_string(width) + "x" + std::to_string(height));
    if (lights.size() == 0) throw Error("ptm: needs at least one measured light");
    if (views.size() == 0) throw Error("ptm: needs at least one measured view");
    if (shape.perView && views.size() < 3)
        throw Error("ptm: views=all needs at least 3 measured views to interpolate, got " +
                    std::to_string(views.size()));
    if (frontView >= views.size())
        throw Error("ptm: front view " + std::to_string(frontView) + " is not one of the " +
                    std::to_string(views.size()) + " measured views");
    if (shape.storage == MaterialTexture::UNorm8)
        throw Error("ptm: coefficients are stored as half or float, not 8-bit");
    _shape = shape;
    _slots = shape.perView ? int(views.size()) : 1;
    const std::size_t layers = std::size_t(_slots) * std::size_t(layersPerSlot());
    if (layers > std::size_t(kMaxLayers))
        throw Error("ptm: " + std::to_string(_slots) + " views x " +
                    std::to_string(layersPerSlot()) + " coefficient layers need " +
                    std::to_string(layers) + " texture layers, more than the " +
                    std::to_string(kMaxLayers) + " OpenGL guarantees");
    const std::size_t texels = std::size_t(width) * std::size_t(height);
    const std::size_t colourValues = shape.luminance ? texels * std::size_t(_slots) * 3 : 0;
    checkMemory(std::uint64_t(texels * layers * 3 + colourValues) * sizeof(float), "ptm model");
    _frontView = shape.perView ? 0 : frontView;
    _viewLookup = shape.perView ? DirectionLookup(views) : DirectionLookup();
    _lightVectors.clear();
    for (std::size_t l = 0; l < lights.size(); ++l) _lightVectors.push_back(lights.vector(l));
    coefficients.assign(texels * layers * 3, 0.0f);
    colour.assign(colourValues, 0.0f);
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
        coefficients[((std::size_t(slot) * 2 + k / 3) * texels + texel) * 3 + k % 3] = value;
    else
        coefficients[((std::size_t(slot) * kTerms + k) * texels + texel) * 3 + c] = value;
}

void PtmMaterial::roundToStorage() {
    for (float& v : coefficients) v = toStorage(v, _shape.storage);
    for (float& v : colour) v = toStorage(v, _shape.storage);
}

// ---- fitter ------------------------------------------------------------------------------------

namespace {

/** The lights' design matrix and what the fit derives from it once for all texels. */
struct Design {
    Eigen::MatrixXd pinvT;  ///< (A+)^T, lights x 6: coefficients of a column y are y^T (A+)^T
    Eigen::MatrixXd gram;   ///< A^T A, 6 x 6
    int rank = 0;
    double condition = 0;  ///< largest / smallest kept singular value
};

Design makeDesign(const DirectionSet& lights) {
    const Eigen::Index n = Eigen::Index(lights.size());
    Eigen::MatrixXd a(n, PtmMaterial::kTerms);
    for (Eigen::Index l = 0; l < n; ++l) {
        const auto row = PtmMaterial::monomials(lights.vector(std::size_t(l)));
        for (int k = 0; k < PtmMaterial::kTerms; ++k) a(l, k) = row[std::size_t(k)];
    }
    const Eigen::JacobiSVD<Eigen::MatrixXd> svd(a, Eigen::ComputeThinU | Eigen::ComputeThinV);
    const Eigen::VectorXd& s = svd.singularValues();
    // Singular values at the level of rounding are no information about the data: clamped to zero
    // (the seed's "clamp small eigenvalues"), so fewer than 6 lights, or lights on one line, give
    // the minimum-norm polynomial instead of amplified noise. Eigen's own rank threshold.
    const double threshold =
        s.size() > 0 ? s(0) * double(std::max<Eigen::Index>(n, PtmMaterial::kTerms)) * DBL_EPSILON
                     : 0.0;
    Eigen::VectorXd inverse = Eigen::VectorXd::Zero(s.size());
    Design d;
    for (Eigen::Index i = 0; i < s.size(); ++i)
        if (s(i) > threshold) {
            inverse(i) = 1.0 / s(i);
            ++d.rank;
        }
    d.condition = d.rank > 0 ? s(0) / s(d.rank - 1) : 0.0;
    d.pinvT = svd.matrixU() * inverse.asDiagonal() * svd.matrixV().transpose();
    d.gram = a.transpose() * a;
    return d;
}

/** Stores one texel's fit: `c` holds the unrounded least-squares coefficients of its R, G and B
 *  channels (rows), in double. */
void storeTexel(PtmMaterial& m, const Design& design, std::size_t texel, int slot,
                const Eigen::Matrix<double, 3, PtmMaterial::kTerms>& c) {
    const MaterialTexture::PixelKind kind = m.shape().storage;
    if (!m.shape().luminance) {
        for (int ch = 0; ch < 3; ++ch)
            for (int k = 0; k < PtmMaterial::kTerms; ++k)
                m.setCoefficient(texel, slot, k, ch, toStorage(c(ch, k), kind));
        return;
    }
    // The luminance PTM is the luminance of the channel PTMs (least squares is linear), rounded
    // to storage; the colour is then the least-squares colour for exactly that stored polynomial.
    Eigen::Matrix<double, PtmMaterial::kTerms, 1> stored;
    for (int k = 0; k < PtmMaterial::kTerms; ++k) {
        double y = 0;
        for (int ch = 0; ch < 3; ++ch) y += PtmMaterial::kLuminance[std::size_t(ch)] * c(ch, k);
        stored(k) = toStorage(y, kind);
        m.setCoefficient(texel, slot, k, 0, float(stored(k)));
    }
    const Eigen::Matrix<double, PtmMaterial::kTerms, 1> gp = design.gram * stored;
    const double pp = stored.dot(gp);  // <P, P> over the measured lights
    float* out = &m.colour[(std::size_t(slot) * m.texelCount() + texel) * 3];
    for (int ch = 0; ch < 3; ++ch)
        // <y_c, P> = (A^T y_c) . a = (A^T A c_c) . a; a zero polynomial (black texel) gets white,
        // which has unit luminance like every other colour.
        out[ch] = toStorage(pp > 0 ? c.row(ch).dot(gp.transpose()) / pp : 1.0, kind);
}

}  // namespace

osg::ref_ptr<PtmMaterial> PtmMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const OptionValues o = validateOptions("ptm", options);
    if (btf.empty()) throw Error("ptm: the BTF is empty");
    Shape shape;
    shape.luminance = o.choice("colour") == "luminance";
    shape.perView = o.choice("views") == "all";
    shape.storage = o.choice("storage") == "float" ? MaterialTexture::Float : MaterialTexture::Half;

    // The measured view nearest the normal (the seed's front view).
    std::size_t front = 0;
    for (std::size_t v = 1; v < btf.viewCount(); ++v)
        if (btf.views().vector(v).z > btf.views().vector(front).z) front = v;

    const std::size_t texels = btf.texelCount(), lights = btf.lightCount(), rows = texels * 3;
    const int slots = shape.perView ? int(btf.viewCount()) : 1;
    // The model plus, per worker fitting a view, that view's images (a views=all fit runs views in
    // parallel; a front fit reads its one view in parallel blocks into one buffer).
    const std::size_t workers = std::min<std::size_t>(
        std::size_t(slots), std::size_t(std::max(1, tbb::this_task_arena::max_concurrency())));
    const std::size_t layers = shape.luminance ? 2 : kTerms;
    const std::uint64_t modelBytes = std::uint64_t(texels) * std::size_t(slots) *
                                     (layers * 3 + (shape.luminance ? 3 : 0)) * sizeof(float);
    checkMemory(modelBytes + std::uint64_t(workers) * rows * lights * sizeof(float),
                "ptm: the model and the images of " + std::to_string(workers) + " view(s)");
    osg::ref_ptr<PtmMaterial> m =
        create(btf.width(), btf.height(), btf.views(), btf.lights(), shape, front);
    const Design design = makeDesign(btf.lights());

    // Images per read: ~16 MiB, at least what the source reads efficiently.
    const std::size_t perRead =
        std::clamp<std::size_t>((std::size_t(16) << 20) / std::max<std::size_t>(rows * 4, 1),
                                std::max<std::size_t>(btf.imageBlock(), 1), lights);
    const std::size_t reads = (lights + perRead - 1) / perRead;
    // Texels per coefficient product: the double copy of their rows stays small.
    const std::size_t texelBlock = 4096;
    const std::size_t texelBlocks = (texels + texelBlock - 1) / texelBlock;

    Progress progress(shape.perView ? "ptm: fitting " + std::to_string(slots) + " views"
                                    : std::string("ptm: fitting the front view"),
                      std::size_t(slots) * lights);
    const auto fitSlot = [&](int slot, bool parallelInside) {
        const std::size_t view = shape.perView ? std::size_t(slot) : front;
        // Column l = image (view, l): the view's values as a rows x lights matrix Y^T.
        std::vector<float> images(rows * lights);
        const auto read = [&](std::size_t r) {
            const std::size_t first = r * perRead, count = std::min(perRead, lights - first);
            btf.readImages(view * lights + first, count, images.data() + first * rows);
            progress.advance(count);
        };
        const auto solve = [&](std::size_t b) {
            const std::size_t first = b * texelBlock, count = std::min(texelBlock, texels - first);
            const Eigen::Map<const Eigen::MatrixXf> y(images.data(), Eigen::Index(rows),
                                                      Eigen::Index(lights));
            // One product for the block: row 3 t + c = the coefficients of texel t, channel c.
            const Eigen::MatrixXd c =
                y.middleRows(Eigen::Index(first * 3), Eigen::Index(count * 3)).cast<double>() *
                design.pinvT;
            for (std::size_t t = 0; t < count; ++t)
                storeTexel(*m, design, first + t, slot, c.middleRows(Eigen::Index(t * 3), 3));
        };
        if (parallelInside) {
            tbb::parallel_for(std::size_t(0), reads, read);
            tbb::parallel_for(std::size_t(0), texelBlocks, solve);
        } else {
            for (std::size_t r = 0; r < reads; ++r) read(r);
            for (std::size_t b = 0; b < texelBlocks; ++b) solve(b);
        }
    };
    if (shape.perView)
        // One view per task and nothing parallel inside: at most one image buffer per worker.
        tbb::parallel_for(0, slots, [&](int slot) { fitSlot(slot, false); });
    else
        fitSlot(0, true);
    progress.finish();

    std::ostringstream seconds, condition;
    seconds << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    condition << design.condition;
    m->fitInfo["seconds"] = seconds.str();
    m->fitInfo["colour"] = o.choice("colour");
    m->fitInfo["views"] = o.choice("views");
    m->fitInfo["storage"] = storageName(shape.storage);
    std::ostringstream frontView;
    frontView << btf.views()[front].theta << "/" << btf.views()[front].phi;
    m->fitInfo["front-view"] = frontView.str();
    m->fitInfo["rank"] = std::to_string(design.rank);
    m->fitInfo["condition"] = condition.str();
    return m;
}

// ---- CPU evaluator -----------------------------------------------------------------------------

glm::vec3 PtmMaterial::field(std::size_t texel, int slot, float lx, float ly) const {
    // ptm.frag's ptmField, operation for operation.
    const float mx = lx * lx, my = ly * ly, mxy = lx * ly;
    const std::size_t texels = texelCount();
    if (_shape.luminance) {
        const float* a = &coefficients[((std::size_t(slot) * 2) * texels + texel) * 3];
        const float* b = &coefficients[((std::size_t(slot) * 2 + 1) * texels + texel) * 3];
        float l = b[2];
        l += a[0] * mx;
        l += a[1] * my;
        l += a[2] * mxy;
        l += b[0] * lx;
        l += b[1] * ly;
        const float* rgb = &colour[(std::size_t(slot) * texels + texel) * 3];
        return glm::vec3(rgb[0], rgb[1], rgb[2]) * l;
    }
    const auto term = [&](int k) {
        const float* p = &coefficients[((std::size_t(slot) * kTerms + k) * texels + texel) * 3];
        return glm::vec3(p[0], p[1], p[2]);
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
    // fitted data, and seed 002 Table 2 has nothing shared to count.
    const double values = double(coefficients.size() + colour.size());
    const double bytes = values * bytesPerValue(_shape.storage);
    return {values / double(texelCount()), bytes / double(texelCount()), std::uint64_t(bytes)};
}

// ---- save / load -------------------------------------------------------------------------------

FittedMaterial PtmMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["colour"] = _shape.luminance ? "luminance" : "rgb";
    file.parameters["views"] = _shape.perView ? "all" : "front";
    file.parameters["frontView"] = std::to_string(_frontView);
    file.textures.push_back({"coefficients", _width, _height, _slots * layersPerSlot(), 3,
                             _shape.storage, coefficients});
    if (_shape.luminance)
        file.textures.push_back({"colour", _width, _height, _slots, 3, _shape.storage, colour});
    return file;
}

osg::ref_ptr<PtmMaterial> PtmMaterial::fromFile(const FittedMaterial& file) {
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
    const MaterialTexture& coefficients = file.texture("coefficients");
    Shape shape;
    shape.luminance = colourModel == "luminance";
    shape.perView = views == "all";
    shape.storage = coefficients.kind;
    try {
        m->setShape(m->_width, m->_height, m->_views, m->_lights, shape, frontView);
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    const auto take = [&](const MaterialTexture& t, int depth, std::vector<float>& into) {
        if (t.width != m->_width || t.height != m->_height || t.depth != depth || t.channels != 3 ||
            t.kind != shape.storage)
            fail(file.source, "texture '" + t.name + "' must be " + std::to_string(m->_width) +
                                  "x" + std::to_string(m->_height) + ", " + std::to_string(depth) +
                                  " layer(s) of RGB " + storageName(shape.storage));
        if (std::any_of(t.data.begin(), t.data.end(), [](float v) { return !std::isfinite(v); }))
            fail(file.source, "texture '" + t.name + "' holds non-finite values");
        into = t.data;
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
               createFloatTextureArray({"coefficients", _width, _height, _slots * layersPerSlot(),
                                        3, _shape.storage, coefficients},
                                       filtersBilinearly())
                   .get(),
               "ptmCoefficients", 0);
    // Samplers the variant never reads still get units of their own: GL refuses to draw when
    // samplers of different types share a unit, and an unset sampler is unit 0.
    if (_shape.luminance)
        addTexture(
            *stateSet,
            createFloatTextureArray({"colour", _width, _height, _slots, 3, _shape.storage, colour})
                .get(),
            "ptmColour", 1);
    else
        stateSet->addUniform(new osg::Uniform("ptmColour", 1));
    if (_shape.perView)
        _viewLookup.addToStateSet(*stateSet, "ptmViewTable", 2);
    else
        stateSet->addUniform(new osg::Uniform("ptmViewTable", 2));
    stateSet->addUniform(new osg::Uniform("ptmLuminance", _shape.luminance ? 1 : 0));
    stateSet->addUniform(new osg::Uniform("ptmPerView", _shape.perView ? 1 : 0));
    return stateSet;
}

// ---- registration ------------------------------------------------------------------------------

namespace {
const bool registered = registerMethod([] {
    MethodInfo m;
    m.name = "ptm";
    m.description =
        "polynomial texture maps (Malzbender 2001, seed 002): per texel a biquadratic in the "
        "light's (l_x, l_y), per channel or on the luminance times a base colour, fitted by one "
        "shared pseudo-inverse; on the front view or one per view, blended";
    m.options = {
        OptionSpec::choice("colour", "rgb", {"rgb", "luminance"},
                           "rgb: a polynomial per channel (18 coefficients per texel); luminance: "
                           "one on the Rec. 709 luminance times an RGB base colour of unit "
                           "luminance (6 + 3)"),
        OptionSpec::choice("views", "front", {"front", "all"},
                           "front: one PTM fitted on the measured view nearest the normal, used "
                           "for every view (the seed's); all: one PTM per measured view, blended "
                           "over the 3 Delaunay-neighbour views"),
        OptionSpec::choice("storage", "half", {"half", "float"},
                           "precision of the coefficients and the colour")};
    m.fit = [](const BtfSource& btf, const FitOptions& o) -> osg::ref_ptr<Material> {
        return PtmMaterial::fit(btf, o);
    };
    m.load = [](const FittedMaterial& f) -> osg::ref_ptr<Material> {
        return PtmMaterial::fromFile(f);
    };
    m.createInstance = []() -> osg::Object* { return new PtmMaterial; };
    // A polynomial in the light whose coefficients are per texel (luminance materials excepted:
    // PtmMaterial::linearInParameters).
    m.filtersLinearly = true;
    m.shaderCost = [](const Material& material) {
        // ptmField: monomials 3, variant test 1; rgb: layer base 1, 5 layer offsets, 6 fetches,
        // 5 multiply-adds (10) = 20 ALU, 6 TEX; luminance: layer addresses 3, 5 multiply-adds
        // (10), colour multiply 1 = 18 ALU, 3 TEX. btfEvaluate: per-view test 1 and the final max
        // 1; views=all adds the view lookup and per blended view (3) loop 2, weight test 1,
        // weighted add 2.
        const PtmMaterial& m = static_cast<const PtmMaterial&>(material);
        const bool luminance = m.shape().luminance;
        const int fieldAlu = luminance ? 18 : 20, fieldTex = luminance ? 3 : 6;
        const std::string variant = luminance ? "luminance" : "rgb";
        if (!m.shape().perView)
            return ShaderCost::ofEvaluate(2 + fieldAlu, fieldTex,
                                          "ALU " + std::to_string(2 + fieldAlu) + ", TEX " +
                                              std::to_string(fieldTex) + " (" + variant +
                                              ", front view)");
        const DirectionLookup::Cost v = m.viewLookup().cost();
        const int alu = 2 + 3 * (5 + fieldAlu), tex = 3 * fieldTex;
        return ShaderCost::ofEvaluate(v.alu + alu, v.tex + tex,
                                      "ALU " + std::to_string(alu) + "+L, TEX " +
                                          std::to_string(tex) + "+T (" + variant +
                                          ", views=all; L = " + std::to_string(v.alu) +
                                          ", T = " + std::to_string(v.tex) + ": the view lookup)");
    };
    m.order = 80;
    return m;
}());
}  // namespace

}  // namespace osgBTF
