#include "materials/CoordinateMapRendering.h"

#include <algorithm>
#include <map>
#include <mutex>

#include <osg/Uniform>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "materials/BilinearTaps.h"
#include "materials/MaterialState.h"
#include "materials/ShaderInterface.h"

namespace osgBTF {

namespace {

std::string sizeText(int width, int height) {
    return std::to_string(width) + "x" + std::to_string(height);
}

/** Texture `t` of a material of size width x height, each tile's texels remapped. */
MaterialTexture remapTexture(const MaterialTexture& t, int width, int height,
                             const CoordinateMap& map, const std::string& method) {
    if (t.width % width != 0 || t.height % height != 0)
        throw Error("fitted material '" + method + "': texture '" + t.name + "' (" +
                    sizeText(t.width, t.height) + ") is not a grid of " + sizeText(width, height) +
                    " texel tiles (a method declares the tables all texels share with "
                    "declareSharedTextures)");
    const int tilesX = t.width / width, tilesY = t.height / height;
    MaterialTexture out = t;
    out.width = tilesX * map.width;
    out.height = tilesY * map.height;
    const bool bytes = !t.bytes.empty();
    checkMemory(std::uint64_t(out.valueCount()) * (bytes ? 1 : sizeof(float)),
                "texture '" + t.name + "' remapped to " + sizeText(out.width, out.height));
    if (bytes)
        out.bytes.assign(out.valueCount(), 0);
    else
        out.data.assign(out.valueCount(), 0.0f);
    const std::size_t channels = std::size_t(t.channels);
    for (int z = 0; z < t.depth; ++z)
        for (int ty = 0; ty < tilesY; ++ty)
            for (int y = 0; y < map.height; ++y)
                for (int tx = 0; tx < tilesX; ++tx)
                    for (int x = 0; x < map.width; ++x) {
                        const std::size_t srcRow = std::size_t(z) * t.height +
                                                   std::size_t(ty) * height + map.sampleY(x, y);
                        const std::size_t src =
                            (srcRow * t.width + std::size_t(tx) * width + map.sampleX(x, y)) *
                            channels;
                        const std::size_t dstRow =
                            std::size_t(z) * out.height + std::size_t(ty) * map.height + y;
                        const std::size_t dst =
                            (dstRow * out.width + std::size_t(tx) * map.width + x) * channels;
                        if (bytes)
                            std::copy_n(t.bytes.begin() + std::ptrdiff_t(src), channels,
                                        out.bytes.begin() + std::ptrdiff_t(dst));
                        else
                            std::copy_n(t.data.begin() + std::ptrdiff_t(src), channels,
                                        out.data.begin() + std::ptrdiff_t(dst));
                    }
    return out;
}

int intParameter(const FittedMaterial& file, const std::string& key) {
    try {
        return std::stoi(file.parameter(key));
    } catch (const std::logic_error&) {
        fail(file.source, "parameter '" + key + "' is not an integer");
    }
}

std::mutex& sharedTexturesMutex() {
    static std::mutex mutex;
    return mutex;
}

std::map<std::string, std::vector<std::string>>& sharedTexturesByMethod() {
    static std::map<std::string, std::vector<std::string>> declared;
    return declared;
}

}  // namespace

bool declareSharedTextures(const std::string& method, std::vector<std::string> textures) {
    std::lock_guard<std::mutex> lock(sharedTexturesMutex());
    sharedTexturesByMethod()[method] = std::move(textures);
    return true;
}

std::vector<std::string> sharedTextures(const std::string& method) {
    std::lock_guard<std::mutex> lock(sharedTexturesMutex());
    const auto it = sharedTexturesByMethod().find(method);
    return it == sharedTexturesByMethod().end() ? std::vector<std::string>() : it->second;
}

void checkCoordinateMapMatches(const Material& material, const CoordinateMap& map,
                               const std::string& mapName) {
    // The map's entries are base texels; the levels' averages do not follow a map's layout.
    if (material.mipLayout().mipMapped())
        throw Error(mapName + ": material '" +
                    (material.sourceFile.empty() ? material.methodName() : material.sourceFile) +
                    "' is mip-mapped; a coordinate map needs a material fitted without mip levels");
    if (map.sampleWidth == material.width() && map.sampleHeight == material.height()) return;
    const std::string name =
        material.sourceFile.empty() ? material.methodName() : material.sourceFile;
    throw Error(mapName + ": made for a " + sizeText(map.sampleWidth, map.sampleHeight) +
                " sample, but material '" + name + "' is " +
                sizeText(material.width(), material.height()));
}

FittedMaterial remapFittedMaterial(const FittedMaterial& file, const CoordinateMap& map) {
    validateCoordinateMap(map, "coordinate map");
    const int width = intParameter(file, "width"), height = intParameter(file, "height");
    if (file.parameters.count("mip.base"))
        throw Error("coordinate map: fitted material '" + file.method +
                    "' is mip-mapped; a coordinate map needs a material fitted without mip levels");
    if (map.sampleWidth != width || map.sampleHeight != height)
        throw Error("coordinate map: made for a " + sizeText(map.sampleWidth, map.sampleHeight) +
                    " sample, but fitted material '" + file.method + "' is " +
                    sizeText(width, height));
    findMethod(file.method);  // an unknown method fails here, naming the known ones
    const std::vector<std::string> shared = sharedTextures(file.method);
    FittedMaterial out;
    out.method = file.method;
    out.parameters = file.parameters;
    out.parameters["width"] = std::to_string(map.width);
    out.parameters["height"] = std::to_string(map.height);
    out.views = file.views;
    out.lights = file.lights;
    for (const MaterialTexture& t : file.textures)
        out.textures.push_back(std::find(shared.begin(), shared.end(), t.name) != shared.end()
                                   ? t
                                   : remapTexture(t, width, height, map, file.method));
    return out;
}

osg::ref_ptr<Material> remapMaterial(const Material& material, const CoordinateMap& map) {
    checkCoordinateMapMatches(material, map, "coordinate map");
    return materialFromFile(remapFittedMaterial(material.toFittedMaterial(), map));
}

glm::vec3 evaluateThroughMap(const Material& material, const CoordinateMap& map, float u, float v,
                             const glm::vec3& view, const glm::vec3& light) {
    const BilinearTaps taps(u, v, map.width, map.height);
    glm::vec3 value(0.0f);
    for (int k = 0; k < 4; ++k)
        // As the shader: an entry of weight 0 is not evaluated.
        if (taps.weight[k] > 0.0f)
            value +=
                taps.weight[k] * material.evaluate(map.sampleX(taps.x[k], taps.y[k]),
                                                   map.sampleY(taps.x[k], taps.y[k]), view, light);
    return value;
}

osg::ref_ptr<osg::Texture2D> createCoordinateMapTexture(const CoordinateMap& map) {
    validateCoordinateMap(map, "coordinate map");
    if (map.sampleWidth > 65535 || map.sampleHeight > 65535)
        throw Error(
            "coordinate map: samples up to 65535x65535 texels can be drawn through a map, "
            "got " +
            sizeText(map.sampleWidth, map.sampleHeight));
    // One R32I texel per entry, x in the low 16 bits and y above: OSG 3.6.5's osg::Image knows no
    // two-channel integer format (GL_RG_INTEGER), and one channel is also the smallest texture.
    osg::ref_ptr<osg::Image> image = new osg::Image;
    image->allocateImage(map.width, map.height, 1, GL_RED_INTEGER, GL_INT);
    image->setInternalTextureFormat(GL_R32I);
    auto* texels = reinterpret_cast<std::int32_t*>(image->data());
    // Rows bottom-up in both: the map's row y is the texture's row y, as texelFetch reads it.
    const std::size_t entries = std::size_t(map.width) * std::size_t(map.height);
    for (std::size_t i = 0; i < entries; ++i)
        texels[i] = std::int32_t((std::uint32_t(map.coordinates[2 * i + 1]) << 16) |
                                 std::uint32_t(map.coordinates[2 * i]));
    osg::ref_ptr<osg::Texture2D> texture = new osg::Texture2D(image.get());
    texture->setInternalFormat(GL_R32I);
    texture->setSourceFormat(GL_RED_INTEGER);
    texture->setSourceType(GL_INT);
    texture->setResizeNonPowerOfTwoHint(false);
    texture->setUseHardwareMipMapGeneration(false);
    texture->setFilter(osg::Texture::MIN_FILTER, osg::Texture::NEAREST);
    texture->setFilter(osg::Texture::MAG_FILTER, osg::Texture::NEAREST);
    texture->setWrap(osg::Texture::WRAP_S, osg::Texture::CLAMP_TO_EDGE);
    texture->setWrap(osg::Texture::WRAP_T, osg::Texture::CLAMP_TO_EDGE);
    texture->setName("osgBTF_coordinateMap");
    return texture;
}

osg::ref_ptr<osg::StateSet> createCoordinateMapStateSet(const Material& material,
                                                        const osg::StateSet& materialState,
                                                        osg::Texture2D* mapTexture) {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    const osg::ref_ptr<osg::Program> program = coordinateMapProgram(material.methodName());
    stateSet->setAttributeAndModes(program.get(), osg::StateAttribute::ON);
    const int unit = shader::kCoordinateMapUnit;
    if (int(materialState.getTextureAttributeList().size()) > unit)
        throw Error("method '" + material.methodName() + "' uses texture unit " +
                    std::to_string(unit) + ", which the coordinate map needs");
    stateSet->setTextureAttribute(unit, mapTexture, osg::StateAttribute::ON);
    stateSet->addUniform(new osg::Uniform(shader::kCoordinateMap, unit));
    // The compile pass makes this program current with this StateSet's uniforms alone (see
    // addSamplerUnits): every sampler gets its unit here too.
    addSamplerUnits(*stateSet, *program, materialState);
    return stateSet;
}

}  // namespace osgBTF
