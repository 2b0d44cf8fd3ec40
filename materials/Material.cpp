#include "materials/Material.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>
#include <sstream>
#include <tuple>

#include <glm/common.hpp>
#include <osg/Shader>
#include <osg/State>

#include "core/Error.h"
#include "core/ShaderSource.h"
#include "materials/BilinearTaps.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/EnvironmentState.h"
#include "materials/LightVisibility.h"
#include "materials/MaterialSerializer.h"
#include "materials/MaterialState.h"
#include "materials/ShaderInterface.h"

namespace osgBTF {

namespace {
// The base size of a mip-mapped material's atlas; the layout follows from it.
constexpr const char* kMipBaseParameter = "mip.base";
}  // namespace

// ---- FitOptions ------------------------------------------------------------------------------

FitOptions FitOptions::parse(const std::string& text) {
    std::string normalised = text;
    std::replace(normalised.begin(), normalised.end(), ',', ' ');
    std::istringstream in(normalised);
    std::string item;
    FitOptions options;
    while (in >> item) {
        const auto eq = item.find('=');
        if (eq == std::string::npos || eq == 0)
            throw Error("option '" + item + "': expected KEY=VALUE");
        options.set(item.substr(0, eq), item.substr(eq + 1));
    }
    return options;
}

// ---- Material --------------------------------------------------------------------------------

Material::Material(const Material& other, const osg::CopyOp& copyop)
    : osg::Object(other, copyop),
      fitInfo(other.fitInfo),
      sourceFile(other.sourceFile),
      _width(other._width),
      _height(other._height),
      _views(other._views),
      _lights(other._lights),
      _mipLayout(other._mipLayout) {}

void Material::evaluateMeasured(std::size_t texel, float* abrdf) const {
    const int x = int(texel % std::size_t(_width)), y = int(texel / std::size_t(_width));
    for (std::size_t v = 0; v < _views.size(); ++v) {
        const glm::vec3 view = _views.vector(v);
        for (std::size_t l = 0; l < _lights.size(); ++l) {
            const glm::vec3 value = evaluate(x, y, view, _lights.vector(l));
            *abrdf++ = value.r;
            *abrdf++ = value.g;
            *abrdf++ = value.b;
        }
    }
}

void Material::setMipLayout(const MipLayout& layout) {
    if (layout.mipMapped() && (layout.atlasWidth() != _width || layout.atlasHeight() != _height))
        throw Error("a mip pyramid of a " + std::to_string(layout.baseWidth()) + "x" +
                    std::to_string(layout.baseHeight()) + " base needs " +
                    std::to_string(layout.atlasWidth()) + "x" +
                    std::to_string(layout.atlasHeight()) + " texels, the material has " +
                    std::to_string(_width) + "x" + std::to_string(_height));
    _mipLayout = layout.mipMapped() ? layout : MipLayout();
    _sharedStateSet = nullptr;
}

glm::vec3 Material::evaluateFiltered(float u, float v, float lod, const glm::vec3& view,
                                     const glm::vec3& light) const {
    if (filtersParameters()) {
        // The hardware filters the parameters, which blends evaluateLinear's values; the rest of
        // the evaluation applies to the blend (GL_LINEAR's weights are exact where they are
        // multiples of a power of two, which its fixed-point weights represent too).
        FilterTaps taps;
        addBilinearTaps(taps, u, v, MipLevel{0, 0, _width, _height}, 1.0f);
        glm::vec3 linear(0.0f);
        for (int k = 0; k < taps.count; ++k)
            linear +=
                taps.taps[k].weight * evaluateLinear(taps.taps[k].x, taps.taps[k].y, view, light);
        return finishLinear(linear, view, light);
    }
    // The level selection environment lighting shares (evaluateFoldedFiltered).
    const FilterTaps taps = mipFilterTaps(_mipLayout, _width, _height, u, v, lod);
    glm::vec3 value(0.0f);
    for (int k = 0; k < taps.count; ++k)
        value += taps.taps[k].weight * evaluate(taps.taps[k].x, taps.taps[k].y, view, light);
    return value;
}

Material::TexelFilter Material::texelFilter() const {
    const MethodInfo* method = findMethodIfRegistered(methodName());
    // A material of no registered method (BSVTF's StreamedFmfMaterial, made by its streamer,
    // never loaded by name) has no MethodInfo to declare it: its linearInParameters() does.
    const bool filters = method ? method->filtersParameters : true;
    return filters && !_mipLayout.mipMapped() && linearInParameters() ? TexelFilter::Parameters
                                                                      : TexelFilter::Values;
}

void Material::throwMethodMismatch(const Material& other) const {
    throw Error("cannot assign a " + other.methodName() + " material to a " + methodName() +
                " material");
}

osg::StateSet* Material::sharedStateSet() const {
    // One lock for all materials: this runs once per material, the lock only guards the check.
    static std::mutex mutex;
    std::lock_guard<std::mutex> lock(mutex);
    if (!_sharedStateSet) _sharedStateSet = createStateSet();
    return _sharedStateSet.get();
}

void Material::setGeometry(int width, int height, DirectionSet views, DirectionSet lights) {
    _width = width;
    _height = height;
    _views = std::move(views);
    _lights = std::move(lights);
}

void Material::readCommon(const FittedMaterial& file) {
    if (file.method != methodName())
        fail(file.source, "is a '" + file.method + "' material, not '" + methodName() + "'");
    try {
        _width = std::stoi(file.parameter("width"));
        _height = std::stoi(file.parameter("height"));
    } catch (const std::invalid_argument&) {
        fail(file.source, "width/height parameters are not integers");
    }
    if (_width <= 0 || _height <= 0) fail(file.source, "invalid texel size");
    _views = file.views;
    _lights = file.lights;
    for (const auto& [key, value] : file.parameters)
        if (key.rfind("fit.", 0) == 0) fitInfo[key.substr(4)] = value;
    _mipLayout = MipLayout();
    const auto mip = file.parameters.find(kMipBaseParameter);
    if (mip != file.parameters.end()) {
        int baseWidth = 0, baseHeight = 0;
        char x = 0, extra = 0;
        std::istringstream in(mip->second);
        if (!(in >> baseWidth >> x >> baseHeight) || x != 'x' || in >> extra || baseWidth <= 0 ||
            baseHeight <= 0 || baseWidth > _width || baseHeight > _height)
            fail(file.source, std::string(kMipBaseParameter) + " '" + mip->second +
                                  "' is not a base size WxH within the material's texels");
        try {
            setMipLayout(MipLayout::forBase(baseWidth, baseHeight));
        } catch (const Error& e) {
            fail(file.source, e.what());
        }
    }
}

FittedMaterial Material::writeCommon() const {
    FittedMaterial file;
    file.method = methodName();
    file.views = _views;
    file.lights = _lights;
    file.parameters["width"] = std::to_string(_width);
    file.parameters["height"] = std::to_string(_height);
    for (const auto& [key, value] : fitInfo) file.parameters["fit." + key] = value;
    if (_mipLayout.mipMapped())
        file.parameters[kMipBaseParameter] =
            std::to_string(_mipLayout.baseWidth()) + "x" + std::to_string(_mipLayout.baseHeight());
    return file;
}

// ---- registry --------------------------------------------------------------------------------

namespace {
std::map<std::string, MethodInfo>& registry() {
    static std::map<std::string, MethodInfo> methods;
    return methods;
}

// Every registerFitter call, kept for a method registered (again) after it: a library's static
// initialisers run in an order of their own.
std::map<std::string, decltype(MethodInfo::fit)>& registeredFitters() {
    static std::map<std::string, decltype(MethodInfo::fit)> fitters;
    return fitters;
}
}  // namespace

bool registerMethod(MethodInfo info) {
    const std::string name = info.name;
    if (!info.fit) {
        if (const auto it = registeredFitters().find(name); it != registeredFitters().end())
            info.fit = it->second;
        else
            // A program that links only the render library: say what it lacks rather than let
            // std::function throw bad_function_call.
            info.fit = [name](const BtfSource&, const FitOptions&) -> osg::ref_ptr<Material> {
                throw Error("method '" + name +
                            "': fitting needs libosgBTFFit (link osgBTF::osgBTFFit or pkg-config "
                            "osgBTFFit); this program has only the render library libosgBTF");
            };
    }
    if (!info.fragmentShader.empty()) addShaderSource(name + ".frag", info.fragmentShader);
    const MethodInfo& stored = registry()[name] = std::move(info);
    addMaterialWrapper(stored);
    return true;
}

bool registerFitter(const std::string& name, decltype(MethodInfo::fit) fit) {
    if (const auto it = registry().find(name); it != registry().end()) it->second.fit = fit;
    registeredFitters()[name] = std::move(fit);
    return true;
}

std::vector<std::string> methodNames() {
    std::vector<std::string> names;
    for (const auto& entry : registry()) names.push_back(entry.first);
    return names;
}

std::vector<std::string> methodNamesInOrder() {
    std::vector<std::string> names = methodNames();
    std::stable_sort(names.begin(), names.end(), [](const std::string& a, const std::string& b) {
        return registry().at(a).order < registry().at(b).order;
    });
    return names;
}

const MethodInfo& findMethod(const std::string& name) {
    const MethodInfo* method = findMethodIfRegistered(name);
    if (!method) {
        std::string known;
        for (const auto& n : methodNames()) known += (known.empty() ? "" : ", ") + n;
        throw Error("unknown method '" + name + "' (known: " + known + ")");
    }
    return *method;
}

const MethodInfo* findMethodIfRegistered(const std::string& name) {
    const auto it = registry().find(name);
    return it == registry().end() ? nullptr : &it->second;
}

namespace {

const MethodInfo& methodWith(bool MethodInfo::*flag, const std::string& role) {
    for (const std::string& name : methodNamesInOrder())
        if (registry().at(name).*flag) return registry().at(name);
    throw Error("no method is registered as the " + role);
}

}  // namespace

const MethodInfo& baselineMethod() {
    return methodWith(&MethodInfo::baseline, "baseline");
}

const MethodInfo& pluginDefaultMethod() {
    return methodWith(&MethodInfo::pluginDefault, "plugins' default");
}

void saveMaterial(const Material& material, const std::string& path) {
    saveFittedMaterial(material.toFittedMaterial(), path);
}

osg::ref_ptr<Material> materialFromFile(const FittedMaterial& file) {
    const auto it = registry().find(file.method);
    if (it == registry().end())
        fail(
            file.source, "unknown method '" + file.method + "' (this osgBTF knows: " + [] {
                std::string known;
                for (const auto& n : methodNames()) known += (known.empty() ? "" : ", ") + n;
                return known;
            }() + ")");
    return it->second.load(file);
}

osg::ref_ptr<Material> loadMaterial(const std::string& path) {
    osg::ref_ptr<Material> material = materialFromFile(loadFittedMaterial(path));
    material->sourceFile = path;
    return material;
}

namespace {

/** One program per method and variant for the whole process (every material of a method shares
 *  it, so OSG compiles it once per context); releaseCachedPrograms empties its per-context part. */
struct ProgramCache {
    std::mutex mutex;
    std::map<std::tuple<std::string, bool, bool>, osg::ref_ptr<osg::Program>> programs;
};

ProgramCache& programCache() {
    static ProgramCache cache;
    return cache;
}

osg::ref_ptr<osg::Program> programVariant(const std::string& method, bool coordinateMap,
                                          bool shadowMap = false) {
    ProgramCache& cache = programCache();
    std::lock_guard<std::mutex> lock(cache.mutex);
    auto& program = cache.programs[{method, coordinateMap, shadowMap}];
    if (!program) {
        osg::ref_ptr<osg::Program> created = new osg::Program;
        created->setName("osgBTF_" + method + (coordinateMap ? "_coordinateMap" : "") +
                         (shadowMap ? "_shadowMap" : ""));
        const std::string vert = "common/btf.vert", frag = method + ".frag";
        std::string vertex = shaderSource(vert);
        // The shadow variant reads the technique's TexGen in the vertex stage too.
        if (shadowMap) vertex = addShaderDefine(vertex, shader::kShadowMapDefine);
        osg::ref_ptr<osg::Shader> vs = new osg::Shader(osg::Shader::VERTEX, vertex);
        vs->setName(shaderOrigin(vert));
        std::string fragment = shaderSource(frag);
        if (coordinateMap) fragment = addShaderDefine(fragment, shader::kCoordinateMapDefine);
        if (shadowMap) fragment = addShaderDefine(fragment, shader::kShadowMapDefine);
        osg::ref_ptr<osg::Shader> fs = new osg::Shader(osg::Shader::FRAGMENT, fragment);
        fs->setName(shaderOrigin(frag));
        created->addShader(vs);
        created->addShader(fs);
        created->addBindAttribLocation(shader::kTangentAttributeName, shader::kTangentAttribute);
        for (int a = 0; a < shader::kLightVisibilityAttributes; ++a)
            created->addBindAttribLocation(shader::kLightVisibilityAttributeName[a],
                                           shader::kLightVisibilityAttribute[a]);
        program = created;
    }
    return program;
}

}  // namespace

osg::ref_ptr<osg::Program> methodProgram(const std::string& method) {
    return programVariant(method, false);
}

void releaseCachedPrograms(osg::State* state) {
    {
        ProgramCache& cache = programCache();
        std::lock_guard<std::mutex> lock(cache.mutex);
        for (const auto& entry : cache.programs) entry.second->releaseGLObjects(state);
    }
    releaseCachedEnvironmentPrograms(state);
}

osg::ref_ptr<osg::Program> coordinateMapProgram(const std::string& method) {
    return programVariant(method, true);
}

osg::ref_ptr<osg::Program> shadowMapProgram(const std::string& method, bool coordinateMap) {
    return programVariant(method, coordinateMap, true);
}

}  // namespace osgBTF
