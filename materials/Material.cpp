#include "materials/Material.h"

#include <algorithm>
#include <mutex>
#include <sstream>

#include "core/Error.h"
#include "materials/BilinearTaps.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

namespace {
// The base size of a mip-mapped material's atlas; the layout follows from it.
constexpr const char* kMipBaseParameter = "mip.base";
}  // namespace

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
    return evaluateTaps(mipFilterTaps(_mipLayout, _width, _height, u, v, lod), view, light);
}

glm::vec3 Material::evaluateTaps(const FilterTaps& taps, const glm::vec3& view,
                                 const glm::vec3& light) const {
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
    if (method && method->blendsInputs) return TexelFilter::Inputs;
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

}  // namespace osgBTF
