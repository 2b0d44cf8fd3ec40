#include "materials/laf/LobeMaterial.h"

#include <algorithm>
#include <cmath>

#include "core/Error.h"
#include "materials/MaterialMath.h"
#include "materials/MaterialState.h"
#include "materials/laf/Lobes.h"

namespace osgBTF {

// ---- storage ---------------------------------------------------------------------------------

void LobeMaterial::initLobes(int lobeCount) {
    _lobes = lobeCount;
    _cosine = true;
    rhoD = StoredValues(MaterialTexture::UNorm8, texelCount() * 3);
    rhoS = StoredValues(MaterialTexture::UNorm8, texelCount() * 3);
    lobes = StoredValues(MaterialTexture::Half, texelCount() * lobeCount * lobes::kValuesPerLobe);
    for (std::size_t i = 3; i < lobes.size(); i += lobes::kValuesPerLobe) lobes.set(i, 1.0f);
}

glm::vec3 LobeMaterial::bracket(std::size_t t, const glm::vec3& view,
                                const glm::vec3& light) const {
    const std::size_t texels = texelCount();
    float sum = 0.0f, lobe[lobes::kValuesPerLobe];
    for (int i = 0; i < _lobes; ++i) {
        lobes.read((i * texels + t) * lobes::kValuesPerLobe, lobes::kValuesPerLobe, lobe);
        sum += lobes::lobeValue(lobe, view, light);
    }
    return (glm::vec3(rhoD[t * 3], rhoD[t * 3 + 1], rhoD[t * 3 + 2]) +
            glm::vec3(rhoS[t * 3], rhoS[t * 3 + 1], rhoS[t * 3 + 2]) * sum) *
           (_cosine ? light.z : 1.0f);
}

void LobeMaterial::writeLobes(FittedMaterial& file) const {
    file.parameters["lobes"] = std::to_string(_lobes);
    file.parameters["cosine"] = _cosine ? "1" : "0";
    file.textures.push_back(rhoD.texture("rhoD", _width, _height, 1, 3));
    file.textures.push_back(rhoS.texture("rhoS", _width, _height, 1, 3));
    file.textures.push_back(lobes.texture("lobes", _width, _height, _lobes, 4));
}

void LobeMaterial::readLobeParameters(const FittedMaterial& file) {
    try {
        _lobes = std::stoi(file.parameter("lobes"));
    } catch (const std::invalid_argument&) {
        fail(file.source, "parameter 'lobes' is not an integer");
    }
    if (_lobes < 1 || _lobes > lobes::kMaxLobes)
        fail(file.source, "parameter 'lobes' must be between 1 and 8");
    const std::string& cosine = file.parameter("cosine");
    if (cosine != "0" && cosine != "1") fail(file.source, "parameter 'cosine' must be 0 or 1");
    _cosine = cosine == "1";
}

void LobeMaterial::readLobeTextures(FittedMaterial& file) {
    rhoD = readTexture(file, "rhoD", 1, 3, MaterialTexture::UNorm8);
    rhoS = readTexture(file, "rhoS", 1, 3, MaterialTexture::UNorm8);
    lobes = readTexture(file, "lobes", _lobes, 4, MaterialTexture::Half);
}

StoredValues LobeMaterial::readTexture(FittedMaterial& file, const std::string& name, int depth,
                                       int channels, MaterialTexture::PixelKind kind) const {
    // The file is the caller's own (fromFile takes it by value): its values are taken.
    MaterialTexture& t = file.texture(name);
    if (t.width != _width || t.height != _height || t.depth != depth || t.channels != channels)
        fail(file.source, "texture '" + name + "' must be " + std::to_string(_width) + "x" +
                              std::to_string(_height) + "x" + std::to_string(depth) + " with " +
                              std::to_string(channels) + " channels");
    return StoredValues::take(t, kind);
}

void LobeMaterial::addLobeState(osg::StateSet& stateSet, const std::string& prefix) const {
    addTexture(stateSet, createFloatTexture(rhoD.texture("rhoD", _width, _height, 1, 3)).get(),
               prefix + "RhoD", 0);
    addTexture(stateSet, createFloatTexture(rhoS.texture("rhoS", _width, _height, 1, 3)).get(),
               prefix + "RhoS", 1);
    // The lobe slices stacked as one atlas (lobe i in rows [i h, (i + 1) h)): the same memory
    // layout as the [lobe][y][x] array, and a plain sampler2D for any lobe count, 1 included.
    addTexture(stateSet,
               createFloatTexture(lobes.texture("lobes", _width, _height * _lobes, 1, 4)).get(),
               prefix + "Lobes", 2);
    stateSet.addUniform(new osg::Uniform((prefix + "LobeCount").c_str(), _lobes));
    stateSet.addUniform(new osg::Uniform((prefix + "Cosine").c_str(), _cosine ? 1 : 0));
}

}  // namespace osgBTF
