#include "materials/CoordinateMapRendering.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

#include <osg/Uniform>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "materials/BilinearTaps.h"
#include "materials/MaterialFiles.h"
#include "materials/MaterialState.h"
#include "materials/MethodPrograms.h"
#include "materials/MethodRegistry.h"
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
    // The values stay in the representation they come in (bytes, halves or floats).
    const std::size_t valueBytes = !t.bytes.empty()    ? 1
                                   : !t.halves.empty() ? sizeof(Imath::half)
                                                       : sizeof(float);
    checkMemory(std::uint64_t(out.valueCount()) * valueBytes,
                "texture '" + t.name + "' remapped to " + sizeText(out.width, out.height));
    const std::size_t channels = std::size_t(t.channels);
    const auto remap = [&](const auto& from, auto& to) {
        to.assign(out.valueCount(), {});
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
                            std::copy_n(from.begin() + std::ptrdiff_t(src), channels,
                                        to.begin() + std::ptrdiff_t(dst));
                        }
    };
    if (!t.bytes.empty())
        remap(t.bytes, out.bytes);
    else if (!t.halves.empty())
        remap(t.halves, out.halves);
    else
        remap(t.data, out.data);
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
    // A mip-mapped material's texels are an atlas; the map names texels of its base level.
    const MipLayout& layout = material.mipLayout();
    const int width = layout.mipMapped() ? layout.baseWidth() : material.width();
    const int height = layout.mipMapped() ? layout.baseHeight() : material.height();
    if (map.sampleWidth == width && map.sampleHeight == height) return;
    const std::string name =
        material.sourceFile.empty() ? material.methodName() : material.sourceFile;
    throw Error(mapName + ": made for a " + sizeText(map.sampleWidth, map.sampleHeight) +
                " sample, but material '" + name + "' is " + sizeText(width, height));
}

std::vector<CoordinateMap> coordinateMapChain(const CoordinateMap& map,
                                              const MipLayout& sampleLayout) {
    std::vector<CoordinateMap> chain{map};
    if (!sampleLayout.mipMapped()) return chain;
    const std::vector<MipLevel>& levels = sampleLayout.levels();
    for (int l = 1; chain.back().width > 1 || chain.back().height > 1; ++l) {
        const MipLevel& r = levels[std::size_t(std::min(l, sampleLayout.levelCount() - 1))];
        const int shift = std::min(l, sampleLayout.levelCount() - 1);
        CoordinateMap level(std::max(1, map.width >> l), std::max(1, map.height >> l),
                            sampleLayout.atlasWidth(), sampleLayout.atlasHeight());
        for (int y = 0; y < level.height; ++y)
            for (int x = 0; x < level.width; ++x) {
                // The level texel whose footprint ([j 2^l, (j + 1) 2^l)) holds the sample texel
                // of the block's first entry.
                const int bx = x << l, by = y << l;
                level.sampleX(x, y) = r.x + std::min(map.sampleX(bx, by) >> shift, r.width - 1);
                level.sampleY(x, y) = r.y + std::min(map.sampleY(bx, by) >> shift, r.height - 1);
            }
        chain.push_back(std::move(level));
    }
    return chain;
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
    if (material.mipLayout().mipMapped())
        throw Error("coordinate map: material '" +
                    (material.sourceFile.empty() ? material.methodName() : material.sourceFile) +
                    "' is mip-mapped; only a material without mip levels can be remapped through "
                    "a map (a render through the map filters its levels)");
    checkCoordinateMapMatches(material, map, "coordinate map");
    return materialFromFile(remapFittedMaterial(material.toFittedMaterial(), map));
}

namespace {

/** btf_main.glsl's btfAddMapLevelTaps: the four entries of a map level around (u, v) with
 *  GL_LINEAR's weights times `share`, each tap the sample texel the entry names; the arithmetic
 *  of addBilinearTaps (an identity map gives the material's own taps). */
void addMapTaps(FilterTaps& taps, const CoordinateMap& level, float u, float v, float share) {
    int x0, x1, y0, y1;
    float a, b;
    bilinearAxis(u, level.width, x0, x1, a);
    bilinearAxis(v, level.height, y0, y1, b);
    const auto add = [&](int x, int y, float weight) {
        taps.add(level.sampleX(x, y), level.sampleY(x, y), weight);
    };
    add(x0, y0, share * (1.0f - a) * (1.0f - b));
    add(x1, y0, share * a * (1.0f - b));
    add(x0, y1, share * (1.0f - a) * b);
    add(x1, y1, share * a * b);
}

/** The entries' values blended, or their inputs blended and evaluated once
 *  (Material::evaluateTaps; TexelFilter::Inputs), as btf_main.glsl does through a map. */
glm::vec3 blend(const Material& material, const FilterTaps& taps, const glm::vec3& view,
                const glm::vec3& light) {
    return material.evaluateTaps(taps, view, light);
}

}  // namespace

glm::vec3 evaluateThroughMap(const Material& material, const CoordinateMap& map, float u, float v,
                             const glm::vec3& view, const glm::vec3& light) {
    FilterTaps taps;
    addMapTaps(taps, map, u, v, 1.0f);
    return blend(material, taps, view, light);
}

glm::vec3 evaluateThroughMap(const Material& material, const std::vector<CoordinateMap>& chain,
                             float u, float v, float lod, const glm::vec3& view,
                             const glm::vec3& light) {
    // btf_main.glsl's btfAddMapTaps: a material without levels reads the map's base level.
    const int last = material.mipLayout().mipMapped() ? int(chain.size()) - 1 : 0;
    const float clamped = std::clamp(std::isnan(lod) ? 0.0f : lod, 0.0f, float(last));
    const int a = int(std::floor(clamped)), b = std::min(a + 1, last);
    const float coarser = clamped - float(a);
    FilterTaps taps;
    addMapTaps(taps, chain[std::size_t(a)], u, v, 1.0f - coarser);
    if (coarser > 0.0f) addMapTaps(taps, chain[std::size_t(b)], u, v, coarser);
    return blend(material, taps, view, light);
}

osg::ref_ptr<osg::Texture2D> createCoordinateMapTexture(const std::vector<CoordinateMap>& chain) {
    if (chain.empty()) throw Error("coordinate map: no levels");
    const CoordinateMap& map = chain.front();
    validateCoordinateMap(map, "coordinate map");
    for (const CoordinateMap& level : chain)
        if (level.sampleWidth > 65535 || level.sampleHeight > 65535)
            throw Error(
                "coordinate map: samples up to 65535x65535 texels (with their mip levels) can "
                "be drawn through a map, got " +
                sizeText(level.sampleWidth, level.sampleHeight));
    // One R32I texel per entry, x in the low 16 bits and y above: OSG 3.6.5's osg::Image knows no
    // two-channel integer format (GL_RG_INTEGER), and one channel is also the smallest texture.
    // The levels follow each other in one block, as osg::Image keeps mip levels.
    std::size_t total = 0;
    osg::Image::MipmapDataType offsets;
    for (std::size_t l = 0; l < chain.size(); ++l) {
        if (l > 0) offsets.push_back(static_cast<unsigned int>(total * sizeof(std::int32_t)));
        total += std::size_t(chain[l].width) * std::size_t(chain[l].height);
    }
    auto* texels = new std::int32_t[total];
    std::size_t at = 0;
    // Rows bottom-up in both: the map's row y is the texture's row y, as texelFetch reads it.
    for (const CoordinateMap& level : chain) {
        const std::size_t entries = std::size_t(level.width) * std::size_t(level.height);
        for (std::size_t i = 0; i < entries; ++i)
            texels[at++] = std::int32_t((std::uint32_t(level.coordinates[2 * i + 1]) << 16) |
                                        std::uint32_t(level.coordinates[2 * i]));
    }
    osg::ref_ptr<osg::Image> image = new osg::Image;
    image->setImage(map.width, map.height, 1, GL_R32I, GL_RED_INTEGER, GL_INT,
                    reinterpret_cast<unsigned char*>(texels), osg::Image::USE_NEW_DELETE);
    image->setMipmapLevels(offsets);
    osg::ref_ptr<osg::Texture2D> texture = new osg::Texture2D(image.get());
    texture->setInternalFormat(GL_R32I);
    texture->setSourceFormat(GL_RED_INTEGER);
    texture->setSourceType(GL_INT);
    texture->setResizeNonPowerOfTwoHint(false);
    texture->setUseHardwareMipMapGeneration(false);
    // texelFetch ignores the filters; a mip-mapped one makes OSG upload the image's levels (an
    // integer texture is complete with NEAREST filters and every level down to 1 x 1).
    texture->setFilter(osg::Texture::MIN_FILTER, chain.size() > 1
                                                     ? osg::Texture::NEAREST_MIPMAP_NEAREST
                                                     : osg::Texture::NEAREST);
    texture->setFilter(osg::Texture::MAG_FILTER, osg::Texture::NEAREST);
    texture->setWrap(osg::Texture::WRAP_S, osg::Texture::CLAMP_TO_EDGE);
    texture->setWrap(osg::Texture::WRAP_T, osg::Texture::CLAMP_TO_EDGE);
    texture->setName("osgBTF_coordinateMap");
    return texture;
}

osg::ref_ptr<osg::Texture2D> createCoordinateMapTexture(const Material& material,
                                                        const CoordinateMap& map) {
    validateCoordinateMap(map, "coordinate map");
    checkCoordinateMapMatches(material, map, "coordinate map");
    return createCoordinateMapTexture(coordinateMapChain(map, material.mipLayout()));
}

osg::ref_ptr<osg::StateSet> createCoordinateMapStateSet(const Material& material,
                                                        const osg::StateSet& materialState,
                                                        osg::Texture2D* mapTexture) {
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    const osg::ref_ptr<osg::Program> program = coordinateMapProgram(material);
    stateSet->setAttributeAndModes(program.get(), osg::StateAttribute::ON);
    const int unit = shader::kCoordinateMapUnit;
    if (int(materialState.getTextureAttributeList().size()) > unit)
        throw Error("method '" + material.methodName() + "' uses texture unit " +
                    std::to_string(unit) + ", which the coordinate map needs");
    stateSet->setTextureAttribute(unit, mapTexture, osg::StateAttribute::ON);
    stateSet->addUniform(new osg::Uniform(shader::kCoordinateMap, unit));
    const osg::Image* image = mapTexture->getImage();
    stateSet->addUniform(new osg::Uniform(shader::kCoordinateMapLevels,
                                          int(image ? image->getNumMipmapLevels() : 1)));
    // The compile pass makes this program current with this StateSet's uniforms alone (see
    // addSamplerUnits): every sampler gets its unit here too.
    addSamplerUnits(*stateSet, *program, materialState);
    return stateSet;
}

}  // namespace osgBTF
