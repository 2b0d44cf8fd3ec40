#include "materials/rbf/Rbf.h"

#include <algorithm>
#include <atomic>
#include <cmath>
#include <limits>
#include <sstream>

#include "core/Error.h"
#include "core/SizeGuard.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/ForeignFiles.h"
#include "materials/MaterialState.h"
#include "materials/MethodPrograms.h"
#include "materials/MethodRegistry.h"
#include "materials/RelightFolder.h"

namespace osgBTF {

// ---- shape -------------------------------------------------------------------------------------

std::uint64_t RbfMaterial::newSerial() {
    static std::atomic<std::uint64_t> next{1};
    return next++;
}

void RbfMaterial::setShape(int width, int height, DirectionSet views, DirectionSet lights,
                           int planes, int nodeCount, float sigma, int resolution,
                           MaterialTexture::PixelKind storage, bool allocate) {
    if (planes < 1 || planes > kMaxPlanes)
        throw Error("rbf: " + std::to_string(planes) + " planes, 1.." + std::to_string(kMaxPlanes) +
                    " are held");
    if (nodeCount < 1 || nodeCount > kMaxNodes)
        throw Error("rbf: " + std::to_string(nodeCount) + " nodes, 1.." +
                    std::to_string(kMaxNodes) + " are held");
    if (resolution != 0 &&
        (resolution < 2 || resolution > 64 || resolution * resolution != nodeCount))
        throw Error("rbf: a bilinear grid of resolution " + std::to_string(resolution) + " with " +
                    std::to_string(nodeCount) + " nodes (resolution 2..64, nodes its square)");
    // 1 / sigma^2 must stay a finite float: a narrower sigma would make the nearest node's
    // exponent 0 x infinity.
    if (!(sigma >= 1e-6f && sigma <= 1e6f)) {
        std::ostringstream text;
        text << "rbf: sigma " << sigma << " is not in 1e-06..1e+06";
        throw Error(text.str());
    }
    if (storage != MaterialTexture::Half && storage != MaterialTexture::Float)
        throw Error("rbf: coefficients are stored as half or float");
    setGeometry(width, height, std::move(views), std::move(lights));
    _weightsSerial = newSerial();
    _planes = planes;
    _sigma = sigma;
    _resolution = resolution;
    const std::size_t layers = std::size_t(this->layers());
    if (allocate) {
        checkMemory(saturatedProduct(
                        {texelCount(), layers * 3, storage == MaterialTexture::Half ? 2u : 4u}),
                    "rbf: the coefficients");
        coefficients = StoredValues(storage, texelCount() * layers * 3);
    }
    basis = MaterialTexture{"basis", planes + 1, nodeCount, 1, 3, MaterialTexture::Float, {}};
    basis.data.assign(basis.valueCount(), 0.0f);
    nodes = MaterialTexture{"nodes", nodeCount, 1, 1, 3, MaterialTexture::Float, {}};
    nodes.data.assign(nodes.valueCount(), 0.0f);
}

osg::ref_ptr<RbfMaterial> RbfMaterial::create(int width, int height, DirectionSet views,
                                              DirectionSet lights, int planes, int nodes,
                                              float sigma, int resolution,
                                              MaterialTexture::PixelKind storage) {
    osg::ref_ptr<RbfMaterial> m = new RbfMaterial;
    m->setShape(width, height, std::move(views), std::move(lights), planes, nodes, sigma,
                resolution, storage, true);
    return m;
}

// ---- evaluation --------------------------------------------------------------------------------

std::vector<std::pair<int, float>> RbfMaterial::lightWeights(const glm::vec3& light) const {
    // relight's light from its projection (the shader's same operations).
    const float lx = light.x, ly = light.y;
    const float lz = std::sqrt(std::max(0.0f, 1.0f - lx * lx - ly * ly));
    std::vector<std::pair<int, float>> weights;
    if (_resolution > 0) {
        const float r = float(_resolution) - 1.0f;
        const float s = std::abs(lx) + std::abs(ly) + lz;
        const float u = ((lx + ly) / s + 1.0f) * 0.5f * r;
        const float v = ((ly - lx) / s + 1.0f) * 0.5f * r;
        const float su = std::min(r - 1.0f, std::max(0.0f, std::floor(u)));
        const float sv = std::min(r - 1.0f, std::max(0.0f, std::floor(v)));
        const float du = u - su, dv = v - sv;
        const int i00 = int(su) + int(sv) * _resolution;
        weights = {{i00, (1.0f - du) * (1.0f - dv)},
                   {i00 + 1, du * (1.0f - dv)},
                   {i00 + _resolution, (1.0f - du) * dv},
                   {i00 + _resolution + 1, du * dv}};
        return weights;
    }
    const int n = nodeCount();
    const float inverse = 1.0f / (_sigma * _sigma);
    std::vector<float> d2(std::size_t(n), 0.0f);
    float nearest = std::numeric_limits<float>::max();
    for (int i = 0; i < n; ++i) {
        const glm::vec3 d = glm::vec3(lx, ly, lz) - node(i);
        d2[std::size_t(i)] = d.x * d.x + d.y * d.y + d.z * d.z;
        nearest = std::min(nearest, d2[std::size_t(i)]);
    }
    float total = 0.0f;
    for (int i = 0; i < n; ++i) total += std::exp(-(d2[std::size_t(i)] - nearest) * inverse);
    float kept = 0.0f;
    for (int i = 0; i < n; ++i) {
        const float w = std::exp(-(d2[std::size_t(i)] - nearest) * inverse) / total;
        if (w > kThreshold) {
            weights.emplace_back(i, w);
            kept += w;
        }
    }
    for (auto& w : weights) w.second /= kept;
    return weights;
}

glm::vec3 RbfMaterial::combine(std::size_t texel,
                               const std::vector<std::pair<int, float>>& weights) const {
    float a[kMaxPlanes];
    for (int p = 0; p < _planes; ++p) a[p] = coefficient(texel, p);
    glm::vec3 sum(0.0f);
    for (const auto& [i, w] : weights) {
        glm::vec3 s = basisValue(0, i);
        for (int p = 0; p < _planes; ++p) s += a[p] * basisValue(p + 1, i);
        sum += w * s;
    }
    return sum;
}

glm::vec3 RbfMaterial::evaluate(int x, int y, const glm::vec3&, const glm::vec3& light) const {
    // The weights depend on the light only: kept for the next texel under the same light.
    thread_local std::uint64_t lastSerial = 0;
    thread_local glm::vec3 lastLight(std::numeric_limits<float>::quiet_NaN());
    thread_local std::vector<std::pair<int, float>> lastWeights;
    if (lastSerial != _weightsSerial || lastLight != light) {
        lastWeights = lightWeights(light);
        lastSerial = _weightsSerial;
        lastLight = light;
    }
    return combine(std::size_t(y) * std::size_t(_width) + std::size_t(x), lastWeights);
}

void RbfMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    // The measured lights' weights, kept per thread for the next texel.
    thread_local std::uint64_t lastSerial = 0;
    thread_local std::vector<std::vector<std::pair<int, float>>> weights;
    if (lastSerial != _weightsSerial || weights.size() != _lights.size()) {
        weights.clear();
        for (std::size_t l = 0; l < _lights.size(); ++l)
            weights.push_back(lightWeights(_lights.vector(l)));
        lastSerial = _weightsSerial;
    }
    for (std::size_t v = 0; v < _views.size(); ++v)
        for (std::size_t l = 0; l < _lights.size(); ++l) {
            const glm::vec3 value = combine(texel, weights[l]);
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
}

// ---- memory ------------------------------------------------------------------------------------

MemoryFootprint RbfMaterial::memory() const {
    // Per texel: the coefficients (the last layer's unused channels included: they are stored);
    // shared: the basis and node tables, divided over the texels.
    const double texels = double(std::max<std::size_t>(texelCount(), 1));
    const double shared = double((basis.valueCount() + nodes.valueCount()) * sizeof(float));
    const double values = double(coefficients.size()) / texels +
                          double(basis.valueCount() + nodes.valueCount()) / texels;
    const double bytes = double(coefficients.bytes()) / texels + shared / texels;
    return {values, bytes, std::uint64_t(double(coefficients.bytes()) + shared),
            std::uint64_t(shared)};
}

// ---- save / load -------------------------------------------------------------------------------

FittedMaterial RbfMaterial::toFittedMaterial() const {
    FittedMaterial file = writeCommon();
    file.parameters["planes"] = std::to_string(_planes);
    file.parameters["sigma"] = floatText(_sigma);
    file.parameters["resolution"] = std::to_string(_resolution);
    file.textures.push_back(coefficients.texture("coefficients", _width, _height, layers(), 3));
    file.textures.push_back(basis);
    file.textures.push_back(nodes);
    return file;
}

osg::ref_ptr<RbfMaterial> RbfMaterial::fromFile(FittedMaterial file) {
    osg::ref_ptr<RbfMaterial> m = new RbfMaterial;
    m->readCommon(file);
    int planes = 0, resolution = 0;
    float sigma = 0;
    try {
        planes = std::stoi(file.parameter("planes"));
        resolution = std::stoi(file.parameter("resolution"));
        sigma = std::stof(file.parameter("sigma"));
    } catch (const std::logic_error&) {
        fail(file.source, "parameters 'planes', 'resolution' and 'sigma' must be numbers");
    }
    MaterialTexture& c = file.texture("coefficients");
    MaterialTexture& b = file.texture("basis");
    MaterialTexture& n = file.texture("nodes");
    try {
        m->setShape(m->_width, m->_height, m->_views, m->_lights, planes, b.height, sigma,
                    resolution, c.kind, false);
    } catch (const Error& e) {
        fail(file.source, e.what());
    }
    if (c.width != m->_width || c.height != m->_height || c.depth != m->layers() || c.channels != 3)
        fail(file.source, "texture 'coefficients' must be " + std::to_string(m->_width) + "x" +
                              std::to_string(m->_height) + ", " + std::to_string(m->layers()) +
                              " layer(s) of RGB");
    if (b.width != planes + 1 || b.depth != 1 || b.channels != 3 ||
        b.kind != MaterialTexture::Float)
        fail(file.source,
             "texture 'basis' must be " + std::to_string(planes + 1) + " x nodes float RGB");
    if (n.width != b.height || n.height != 1 || n.depth != 1 || n.channels != 3 ||
        n.kind != MaterialTexture::Float)
        fail(file.source, "texture 'nodes' must be " + std::to_string(b.height) +
                              " x 1 float RGB (one per basis row)");
    m->coefficients = StoredValues::take(c, c.kind);
    b.unpack();
    n.unpack();
    m->basis = std::move(b);
    m->nodes = std::move(n);
    m->_weightsSerial = newSerial();
    if (!m->coefficients.allFinite() ||
        !std::all_of(m->basis.data.begin(), m->basis.data.end(),
                     [](float v) { return std::isfinite(v); }) ||
        !std::all_of(m->nodes.data.begin(), m->nodes.data.end(),
                     [](float v) { return std::isfinite(v); }))
        fail(file.source, "holds non-finite values");
    return m;
}

// ---- relight's web layout ----------------------------------------------------------------------

osg::ref_ptr<RbfMaterial> rbfMaterialFromRelight(const std::string& infoPath,
                                                 const RelightPlanes& planes) {
    const bool bilinear = planes.resolution > 0;
    const int nodes =
        bilinear ? planes.resolution * planes.resolution : int(planes.rawLights.size());
    osg::ref_ptr<RbfMaterial> m;
    try {
        m = RbfMaterial::create(
            planes.width, planes.height, DirectionSet("relight file view", {{0, 0}}),
            relightLights(infoPath, planes), planes.planeCount, nodes,
            bilinear ? 0.125f : float(planes.sigma), planes.resolution, MaterialTexture::Float);
    } catch (const Error& e) {
        fail(infoPath, e.what());
    }
    // relight's basis: for p = 0 the mean profile (0..255), for the planes 127 + range_p E_p.
    // mycc: the profiles are (Y, Co, Cg); relight's renderer reads plane q's channel q % 3 for
    // the first 3 x yccplanes[1] planes (interleaved Y, Co, Cg) and channel 0 (Y) for the rest,
    // adds the mean's three channels and converts the sum to RGB with YCoCg's inverse (linear,
    // relight's Color3::toRgb): tmp = Y - Cg / 2, G = Cg + tmp, B = tmp - Co / 2, R = B + Co.
    // The weights sum to 1, so converting every basis value gives the same sum.
    const bool ycc = planes.colorspace == "mycc";
    const int interleaved = 3 * planes.yccPlanes[1];
    const auto toRgb = [](const glm::vec3& v) {
        const float tmp = v[0] - v[2] / 2;
        const float g = v[2] + tmp, b = tmp - v[1] / 2;
        return glm::vec3(b + v[1], g, b);
    };
    const std::size_t n = std::size_t(nodes);
    for (int p = 0; p <= planes.planeCount; ++p)
        for (int i = 0; i < nodes; ++i) {
            glm::vec3 e;
            for (int c = 0; c < 3; ++c) {
                const double b =
                    planes.basis[(std::size_t(p) * n + std::size_t(i)) * 3 + std::size_t(c)];
                e[c] = float(p == 0 ? b / 255.0 : (b - 127.0) / planes.range[std::size_t(p - 1)]);
                const int q = p - 1;
                if (ycc && p > 0 && c != (q < interleaved ? q % 3 : 0)) e[c] = 0;
            }
            m->setBasisValue(p, i, ycc ? toRgb(e) : e);
        }
    if (!bilinear)
        for (int i = 0; i < nodes; ++i) m->setNode(i, planes.rawLights[std::size_t(i)]);
    const std::size_t texels = m->texelCount();
    for (std::size_t t = 0; t < texels; ++t)
        for (int p = 0; p < planes.planeCount; ++p) m->setCoefficient(t, p, planes.at(p, t));
    m->sourceFile = infoPath;
    return m;
}

RelightModel relightModelOfRbf(const RbfMaterial& material, const std::string& infoPath) {
    const bool bilinear = material.resolution() > 0;
    RelightModel model = relightModelFrame(material, infoPath, bilinear ? "bilinear" : "rbf",
                                           "mrgb", material.planes());
    const std::size_t texels = material.texelCount();
    for (int p = 0; p < material.planes(); ++p) {
        float* plane = model.planes.data() + std::size_t(p) * texels;
        for (std::size_t t = 0; t < texels; ++t) plane[t] = material.coefficient(t, p);
    }
    const int nodes = material.nodeCount();
    for (int p = 0; p <= material.planes(); ++p)
        for (int i = 0; i < nodes; ++i) model.basis.push_back(material.basisValue(p, i));
    if (bilinear) {
        model.resolution = material.resolution();
    } else {
        // The weights interpolate between the nodes: they are the layout's lights.
        model.lights.clear();
        for (int i = 0; i < nodes; ++i) model.lights.push_back(material.node(i));
        model.sigma = material.sigma();
    }
    return model;
}

// ---- StateSet ----------------------------------------------------------------------------------

osg::ref_ptr<osg::StateSet> RbfMaterial::createStateSet() const {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    addCommonState(*stateSet, *this);
    addTexture(
        *stateSet,
        createFloatTextureArray(coefficients.texture("coefficients", _width, _height, layers(), 3),
                                filtersParameters())
            .get(),
        "rbfCoefficients", 0);
    addTexture(*stateSet, createFloatTexture(basis).get(), "rbfBasis", 1);
    addTexture(*stateSet, createFloatTexture(nodes).get(), "rbfNodes", 2);
    stateSet->addUniform(new osg::Uniform("rbfPlanes", _planes));
    stateSet->addUniform(new osg::Uniform("rbfNodeCount", nodeCount()));
    stateSet->addUniform(new osg::Uniform("rbfResolution", _resolution));
    stateSet->addUniform(new osg::Uniform("rbfInverseSigma2", 1.0f / (_sigma * _sigma)));
    return stateSet;
}

// ---- registration ------------------------------------------------------------------------------

namespace {
const bool rbfRegistered = registerMethodClass<RbfMaterial>([] {
    MethodInfo m;
    m.description =
        "the RTI field's default (relight's rbf): one PCA of the front view's light profiles to "
        "N planes per texel, the basis interpolated between the measured lights with normalised "
        "Gaussian weights";
    m.options = {
        OptionSpec::integer("planes", 9, 1, RbfMaterial::kMaxPlanes,
                            "coefficient planes per texel (principal light profiles; relight's "
                            "nplanes)"),
        OptionSpec::number("sigma", 0.125, 0.001, 4,
                           "width of the Gaussian weights between lights (relight's default "
                           "0.125, for about 100 lights)"),
        OptionSpec::choice("storage", "half", {"half", "float"},
                           "precision of the per-texel coefficients")};
    m.filtersParameters = true;  // linear in the coefficients
    m.shaderCost = [](const Material& material) {
        // Per node: rbf: distance 5, exp and sums 4 (pass 1: minimum 6; pass 2: 4; pass 3: weight
        // 5, test 1, the profile (P + 1) fetches and P multiply-adds (2P), weighted add 2),
        // bilinear: 4 nodes of the profile only plus 20 for the cell. Coefficients: layers fetches.
        const RbfMaterial& r = static_cast<const RbfMaterial&>(material);
        const int p = r.planes(), layers = r.layers();
        const int nodes = r.resolution() > 0 ? 4 : r.nodeCount();
        const int perNode = (r.resolution() > 0 ? 0 : 6 + 4 + 6) + 2 * p + 2;
        const int alu = 8 + nodes * perNode + (r.resolution() > 0 ? 20 : 0);
        const int tex = layers + nodes * (p + 1 + (r.resolution() > 0 ? 0 : 1));
        return ShaderCost::ofEvaluate(alu, tex,
                                      "ALU " + std::to_string(alu) + ", TEX " +
                                          std::to_string(tex) + " (" + std::to_string(nodes) +
                                          " nodes x " + std::to_string(p + 1) + " profiles)");
    };
    m.order = 87;  // beside the RTI field's other fits (ptm 80, hsh 85)
    m.fitWorkingSet = 0.5;
    m.quickFitOptions = "planes=3";
    return m;
}());

// The basis and the nodes are shared by all texels: a coordinate map remaps only the
// coefficients.
const bool rbfSharedTextures = declareSharedTextures(RbfMaterial::kMethod, {"basis", "nodes"});

const bool kRelightRbfWriter =
    registerRelightWriter("rbf", [](const Material& material, const std::string& path) {
        return relightModelOfRbf(static_cast<const RbfMaterial&>(material), path);
    });
const bool kRelightRbf = registerRelightType(
    "rbf",
    [](const std::string& path, const RelightPlanes& planes) -> osg::ref_ptr<Material> {
        return rbfMaterialFromRelight(path, planes);
    },
    RelightBasis::GaussianNodes);
const bool kRelightBilinear = registerRelightType(
    "bilinear",
    [](const std::string& path, const RelightPlanes& planes) -> osg::ref_ptr<Material> {
        return rbfMaterialFromRelight(path, planes);
    },
    RelightBasis::OctahedralGrid);
}  // namespace

}  // namespace osgBTF
