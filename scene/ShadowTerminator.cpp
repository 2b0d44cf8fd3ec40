#include "scene/ShadowTerminator.h"

#include <algorithm>
#include <cmath>
#include <map>
#include <mutex>

#include <glm/geometric.hpp>
#include <osg/Image>

#include "materials/ShaderInterface.h"
#include "scene/SharedObjects.h"

namespace osgBTF {

float terminatorCoordinate(const glm::vec3& normal, const glm::vec3& toLight, float alphaDegrees) {
    const float angle = std::acos(std::clamp(glm::dot(normal, toLight), -1.0f, 1.0f));
    const float alpha = alphaDegrees * float(M_PI / 180.0);
    return 0.5f * (1.0f + std::cos(alpha + angle));
}

float terminatorStep(float u, float softness) {
    if (!(softness > 0.0f)) return u < 0.5f ? 0.0f : 1.0f;
    const float x = std::clamp((u - (0.5f - 0.5f * softness)) / softness, 0.0f, 1.0f);
    return x * x * (3.0f - 2.0f * x);
}

std::vector<float> terminatorTexels(float softness, int texels) {
    std::vector<float> values(std::size_t(std::max(texels, 1)));
    for (std::size_t i = 0; i < values.size(); ++i)
        values[i] = terminatorStep((float(i) + 0.5f) / float(values.size()), softness);
    return values;
}

float sampleTerminatorTexels(const std::vector<float>& texels, float u) {
    // GL's LINEAR filter: texel centres at (i + 0.5) / n, edges clamped.
    const int n = int(texels.size());
    const float x = u * float(n) - 0.5f;
    const float i0 = std::floor(x);
    const float w = x - i0;
    const int a = std::clamp(int(i0), 0, n - 1), b = std::clamp(int(i0) + 1, 0, n - 1);
    return (1.0f - w) * texels[std::size_t(a)] + w * texels[std::size_t(b)];
}

float terminatorFactor(float u, float softness) {
    static std::mutex mutex;
    static std::map<float, std::vector<float>> cache;
    std::lock_guard<std::mutex> lock(mutex);
    auto it = cache.find(softness);
    if (it == cache.end()) it = cache.emplace(softness, terminatorTexels(softness)).first;
    return sampleTerminatorTexels(it->second, u);
}

namespace {

/** One StateSet (and texture) per softness, shared by every node (scene/SharedObjects.h; never
 *  destroyed, as the other caches there). */
SharedObjects<float, osg::StateSet, bool>& terminatorStateSets() {
    static auto* const cache = new SharedObjects<float, osg::StateSet, bool>;
    return *cache;
}

osg::ref_ptr<osg::Texture1D> createTerminatorTexture(float softness) {
    const std::vector<float> values = terminatorTexels(softness);
    osg::ref_ptr<osg::Image> image = new osg::Image;
    image->allocateImage(int(values.size()), 1, 1, GL_RED, GL_FLOAT);
    image->setInternalTextureFormat(GL_R32F);
    std::copy(values.begin(), values.end(), reinterpret_cast<float*>(image->data()));
    osg::ref_ptr<osg::Texture1D> texture = new osg::Texture1D(image.get());
    texture->setName("osgBTF_terminator");
    // Float texels and LINEAR: the factor is the CPU's sampleTerminatorTexels to filter precision.
    texture->setInternalFormat(GL_R32F);
    texture->setSourceFormat(GL_RED);
    texture->setSourceType(GL_FLOAT);
    texture->setFilter(osg::Texture::MIN_FILTER, osg::Texture::LINEAR);
    texture->setFilter(osg::Texture::MAG_FILTER, osg::Texture::LINEAR);
    texture->setWrap(osg::Texture::WRAP_S, osg::Texture::CLAMP_TO_EDGE);
    texture->setResizeNonPowerOfTwoHint(false);
    return texture;
}

}  // namespace

osg::ref_ptr<osg::StateSet> terminatorStateSet(float softness) {
    return terminatorStateSets().get(softness, true, [softness] {
        osg::ref_ptr<osg::StateSet> state = new osg::StateSet;
        // Its only parent, for its whole life: this StateSet.
        state->setTextureAttribute(shader::kTerminatorUnit,
                                   createTerminatorTexture(softness).get());
        return state;
    });
}

osg::Texture1D* terminatorTexture(const osg::StateSet& terminatorState) {
    return dynamic_cast<osg::Texture1D*>(
        const_cast<osg::StateAttribute*>(terminatorState.getTextureAttribute(
            shader::kTerminatorUnit, osg::StateAttribute::TEXTURE)));
}

std::size_t releaseUnusedTerminatorStateSets() {
    return terminatorStateSets().releaseUnused();
}

}  // namespace osgBTF
