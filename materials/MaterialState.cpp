#include "materials/MaterialState.h"

#include <algorithm>
#include <cmath>
#include <regex>
#include <vector>

#include <osg/GLExtensions>
#include <osg/State>
#include <osg/Uniform>

#include "core/Error.h"
#include "materials/LightVisibility.h"
#include "materials/Material.h"
#include "materials/MethodPrograms.h"
#include "materials/ShaderInterface.h"

namespace osgBTF {

namespace {

GLenum pixelFormat(int channels) {
    switch (channels) {
        case 1:
            return GL_RED;
        case 2:
            return GL_RG;
        case 3:
            return GL_RGB;
        case 4:
            return GL_RGBA;
    }
    throw Error("textures need 1 to 4 channels, got " + std::to_string(channels));
}

GLint internalFormat(int channels, bool half) {
    static const GLint f32[] = {GL_R32F, GL_RG32F, GL_RGB32F_ARB, GL_RGBA32F_ARB};
    static const GLint f16[] = {GL_R16F, GL_RG16F, GL_RGB16F_ARB, GL_RGBA16F_ARB};
    pixelFormat(channels);
    return half ? f16[channels - 1] : f32[channels - 1];
}

GLint internalFormat(const MaterialTexture& t) {
    static const GLint u8[] = {GL_R8, GL_RG8, GL_RGB8, GL_RGBA8};
    if (t.kind == MaterialTexture::UNorm8) return u8[t.channels - 1];
    return internalFormat(t.channels, t.kind == MaterialTexture::Half);
}

osg::ref_ptr<osg::Image> sliceImage(const MaterialTexture& t, int z, int depthForImage) {
    osg::ref_ptr<osg::Image> image = new osg::Image;
    const bool bytes = t.kind == MaterialTexture::UNorm8;
    image->allocateImage(t.width, t.height, depthForImage, pixelFormat(t.channels),
                         bytes ? GL_UNSIGNED_BYTE : GL_FLOAT);
    image->setInternalTextureFormat(internalFormat(t));
    const std::size_t count = std::size_t(t.width) * t.height * depthForImage * t.channels;
    const std::size_t first = std::size_t(z) * t.width * t.height * t.channels;
    if (!t.bytes.empty()) {
        std::copy_n(t.bytes.data() + first, count, image->data());
        return image;
    }
    if (!t.halves.empty()) {
        std::copy_n(t.halves.data() + first, count, reinterpret_cast<float*>(image->data()));
        return image;
    }
    const float* src = t.data.data() + first;
    if (bytes) {
        unsigned char* dst = image->data();
        for (std::size_t i = 0; i < count; ++i)
            dst[i] = (unsigned char)std::lround(std::clamp(src[i], 0.0f, 1.0f) * 255.0f);
    } else {
        std::copy(src, src + count, reinterpret_cast<float*>(image->data()));
    }
    return image;
}

void configure(osg::Texture& texture, const MaterialTexture& t, bool linear, bool repeat = false) {
    texture.setInternalFormat(internalFormat(t));
    // OSG allocates a texture without texture storage by glTexImage* with no data and this
    // format, which is the internal (sized, so invalid there) one when left unset.
    texture.setSourceFormat(pixelFormat(t.channels));
    texture.setSourceType(t.kind == MaterialTexture::UNorm8 ? GL_UNSIGNED_BYTE : GL_FLOAT);
    texture.setResizeNonPowerOfTwoHint(false);
    texture.setUseHardwareMipMapGeneration(false);
    const auto filter = linear ? osg::Texture::LINEAR : osg::Texture::NEAREST;
    texture.setFilter(osg::Texture::MIN_FILTER, filter);
    texture.setFilter(osg::Texture::MAG_FILTER, filter);
    // A tiled material's last texel blends with its first (Material::evaluateFiltered).
    const auto wrap = repeat ? osg::Texture::REPEAT : osg::Texture::CLAMP_TO_EDGE;
    texture.setWrap(osg::Texture::WRAP_S, wrap);
    texture.setWrap(osg::Texture::WRAP_T, wrap);
    texture.setWrap(osg::Texture::WRAP_R, osg::Texture::CLAMP_TO_EDGE);
}

class ReuploadingTexture2DArray : public osg::Texture2DArray {
public:
    void apply(osg::State& state) const override {
        if (!getTextureObject(state.getContextID()) && !_subloadCallback && imagesValid())
            allocate(state);
        osg::Texture2DArray::apply(state);
    }

    void releaseGLObjects(osg::State* state) const override {
        osg::Texture2DArray::releaseGLObjects(state);
        // One less than the image's count never matches it, now or after later dirty() calls.
        for (std::size_t layer = 0; layer < _modifiedCount.size(); ++layer) {
            const osg::Image* image = layer < _images.size() ? _images[layer].get() : nullptr;
            if (!image) continue;
            const unsigned stale = image->getModifiedCount() - 1u;
            if (state)
                _modifiedCount[layer][state->getContextID()] = stale;
            else
                _modifiedCount[layer].setAllElementsTo(stale);
        }
    }

protected:
    ~ReuploadingTexture2DArray() override = default;

private:
    /** What OSG 3.6.5's Texture2DArray::apply does for a new texture object up to the layers'
     *  upload, except that it allocates storage only for an object without any. OSG recycles the
     *  texture object of a deleted texture of the same size and format (another material loaded
     *  after one was deleted) with its storage, and then specifies that storage again with
     *  glTexImage3D, an error on the immutable storage glTexStorage3D made. With the object in
     *  place, the base class's apply() uploads the layers into it. */
    void allocate(osg::State& state) const {
        const unsigned context = state.getContextID();
        const osg::GLExtensions* gl = state.get<osg::GLExtensions>();
        computeInternalFormat();
        const GLenum storage = gl->isTextureStorageEnabled && _borderWidth == 0
                                   ? selectSizedInternalFormat(_images[0].get())
                                   : 0;
        computeRequiredTextureDimensions(state, *_images[0], _textureWidth, _textureHeight,
                                         _numMipmapLevels);
        const GLsizei depth = computeTextureDepth();
        const GLenum format = storage ? storage : GLenum(_internalFormat);
        TextureObject* object =
            generateAndAssignTextureObject(context, GL_TEXTURE_2D_ARRAY, _numMipmapLevels, format,
                                           _textureWidth, _textureHeight, depth, _borderWidth);
        object->bind();
        applyTexParameters(GL_TEXTURE_2D_ARRAY, state);
        if (!object->isAllocated()) {
            if (storage)
                gl->glTexStorage3D(GL_TEXTURE_2D_ARRAY, std::max(_numMipmapLevels, 1), storage,
                                   _textureWidth, _textureHeight, depth);
            else
                gl->glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, _internalFormat, _textureWidth,
                                 _textureHeight, depth, _borderWidth, _sourceFormat, _sourceType,
                                 nullptr);
            object->setAllocated(_numMipmapLevels, format, _textureWidth, _textureHeight, depth,
                                 _borderWidth);
        }
        // Whatever the object held before, every layer goes into it now.
        for (std::size_t layer = 0; layer < _modifiedCount.size() && layer < _images.size();
             ++layer)
            _modifiedCount[layer][context] = _images[layer]->getModifiedCount() - 1u;
    }
};

/** Allocates a texture array object with glTexImage3D (mutable storage, so that an object OSG
 *  recycles for it is simply specified again) and uploads each layer as `source` writes it. */
/** Uploads a stored texture's values as they are held (halves as GL_HALF_FLOAT, floats as
 *  GL_FLOAT) in one call: nothing converted or copied on this side, and the driver stores halves
 *  into a half texture as they come. */
class StoredLayers : public osg::Texture2DArray::SubloadCallback {
public:
    explicit StoredLayers(std::shared_ptr<const MaterialTexture> stored)
        : _stored(std::move(stored)), _internalFormat(internalFormat(*_stored)) {}

    void load(const osg::Texture2DArray& texture, osg::State& state) const override {
        const MaterialTexture& t = *_stored;
        const osg::GLExtensions* gl = state.get<osg::GLExtensions>();
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
        const bool half = !t.halves.empty();
        gl->glTexImage3D(GL_TEXTURE_2D_ARRAY, 0, _internalFormat, t.width, t.height, t.depth, 0,
                         pixelFormat(t.channels), half ? GL_HALF_FLOAT : GL_FLOAT,
                         half ? static_cast<const void*>(t.halves.data())
                              : static_cast<const void*>(t.data.data()));
        if (osg::Texture::TextureObject* object = texture.getTextureObject(state.getContextID()))
            object->setAllocated(1, _internalFormat, t.width, t.height, t.depth, 0);
    }

    // Everything is uploaded by load(); there is nothing to update later.
    void subload(const osg::Texture2DArray&, osg::State&) const override {}

private:
    std::shared_ptr<const MaterialTexture> _stored;
    GLint _internalFormat;
};

}  // namespace

osg::ref_ptr<osg::Texture2DArray> createStoredTextureArray(
    std::shared_ptr<const MaterialTexture> stored, bool bilinear) {
    const MaterialTexture& t = *stored;
    if (t.kind == MaterialTexture::UNorm8 || !t.bytes.empty())
        throw Error("texture '" + t.name + "': stored textures are half or float");
    if (t.width < 1 || t.height < 1 || t.depth < 1)
        throw Error("texture '" + t.name + "': stored texture of no texels");
    if (t.storedCount() != t.valueCount())
        throw Error("texture '" + t.name + "': data size does not match its dimensions");
    osg::ref_ptr<osg::Texture2DArray> array = new osg::Texture2DArray;
    array->setTextureSize(t.width, t.height, t.depth);
    configure(*array, t, bilinear, bilinear);
    array->setName(t.name);
    array->setSubloadCallback(new StoredLayers(std::move(stored)));
    return array;
}

osg::ref_ptr<osg::Texture2DArray> newTexture2DArray() {
    return new ReuploadingTexture2DArray;
}

osg::ref_ptr<osg::Texture> createFloatTexture(const MaterialTexture& t, bool bilinear) {
    if (t.storedCount() != t.valueCount())
        throw Error("texture '" + t.name + "': data size does not match its dimensions");
    if (t.depth == 1) {
        osg::ref_ptr<osg::Texture2D> texture = new osg::Texture2D(sliceImage(t, 0, 1));
        configure(*texture, t, bilinear, bilinear);
        texture->setName(t.name);
        return texture;
    }
    return createFloatTextureArray(t, bilinear);
}

osg::ref_ptr<osg::Texture2DArray> createFloatTextureArray(const MaterialTexture& t, bool bilinear) {
    if (t.storedCount() != t.valueCount())
        throw Error("texture '" + t.name + "': data size does not match its dimensions");
    osg::ref_ptr<osg::Texture2DArray> array = newTexture2DArray();
    array->setTextureSize(t.width, t.height, t.depth);
    for (int z = 0; z < t.depth; ++z) array->setImage(z, sliceImage(t, z, 1));
    configure(*array, t, bilinear, bilinear);
    array->setName(t.name);
    return array;
}

osg::ref_ptr<osg::Texture3D> createFloatTexture3D(const MaterialTexture& t, bool linear) {
    osg::ref_ptr<osg::Texture3D> texture = new osg::Texture3D(sliceImage(t, 0, t.depth));
    configure(*texture, t, linear);
    texture->setName(t.name);
    return texture;
}

void addTexture(osg::StateSet& stateSet, osg::Texture* texture, const std::string& sampler,
                int unit) {
    stateSet.setTextureAttribute(unit, texture, osg::StateAttribute::ON);
    stateSet.addUniform(new osg::Uniform(sampler.c_str(), unit));
}

void addSamplerUnits(osg::StateSet& stateSet, const osg::Program& program,
                     const osg::StateSet& materialState) {
    static const std::regex declaration(R"(\buniform\s+[iu]?sampler\w*\s+(\w+))");
    for (unsigned i = 0; i < program.getNumShaders(); ++i) {
        const std::string& source = program.getShader(i)->getShaderSource();
        for (auto it = std::sregex_iterator(source.begin(), source.end(), declaration);
             it != std::sregex_iterator(); ++it) {
            const std::string name = (*it)[1].str();
            const osg::Uniform* unit = materialState.getUniform(name);
            int value = 0;
            if (!stateSet.getUniform(name) && unit && unit->get(value))
                stateSet.addUniform(new osg::Uniform(name.c_str(), value));
        }
    }
}

void addCommonState(osg::StateSet& stateSet, const Material& material) {
    stateSet.setAttributeAndModes(methodProgram(material).get(), osg::StateAttribute::ON);
    stateSet.addUniform(new osg::Uniform(shader::kSize, material.width(), material.height()));
    const MipLayout layout = material.mipLayout().mipMapped()
                                 ? material.mipLayout()
                                 : MipLayout::forBase(material.width(), material.height());
    const int levels = material.mipLayout().mipMapped() ? layout.levelCount() : 1;
    static_assert(MipLayout::kMaxLevels == shader::kMaxMipLevels, "one limit for both");
    osg::ref_ptr<osg::Uniform> rectangles =
        new osg::Uniform(osg::Uniform::INT_VEC4, shader::kMipLevel, shader::kMaxMipLevels);
    for (int i = 0; i < levels; ++i) {
        const MipLevel& l = layout.levels()[std::size_t(i)];
        rectangles->setElement(unsigned(i), l.x, l.y, l.width, l.height);
    }
    stateSet.addUniform(rectangles.get());
    stateSet.addUniform(new osg::Uniform(shader::kMipLevels, levels));
    stateSet.addUniform(new osg::Uniform(shader::kTextureScale, 1.0f));
    // btf_main.glsl filters the texels one of two ways (Material::TexelFilter): the method's
    // per-texel lookups sample the filtered textures at the texture coordinate, or main() blends
    // the evaluations of the four texels (per mip level).
    stateSet.addUniform(new osg::Uniform(shader::kBilinear, material.filtersParameters()));
    stateSet.addUniform(new osg::Uniform(shader::kBlendTexels, !material.filtersParameters()));
    // Or the method blends its inputs over those texels itself and main() evaluates it once.
    stateSet.addUniform(new osg::Uniform(shader::kBlendInputs,
                                         material.texelFilter() == Material::TexelFilter::Inputs));
    // The real eye direction unless a rectified image fixes the view (addRectifiedLighting,
    // harness/MaterialImage.h: on this StateSet, below it, or above it with OVERRIDE). Set here
    // for the same reason as the terminator below: a draw after a rectified one would otherwise
    // be shaded as seen from that image's view direction.
    stateSet.addUniform(new osg::Uniform(shader::kFixedView, osg::Vec4(0.0f, 0.0f, 0.0f, 0.0f)));
    // Off unless a MaterialNode's StateSet (applied after this one) turns it on. Set here, not
    // left to the GLSL default: a program keeps the last value any StateSet gave a uniform, so
    // a draw after a MaterialNode's would otherwise inherit its terminator.
    stateSet.addUniform(new osg::Uniform(shader::kTerminator, false));
    stateSet.addUniform(new osg::Uniform(shader::kTerminatorAlpha, 0.0f));
    stateSet.addUniform(new osg::Uniform(shader::kTerminatorTexture, shader::kTerminatorUnit));
    // Every light seen unless a MaterialNode's StateSet names its visibility slot.
    osg::ref_ptr<osg::Uniform> slots =
        new osg::Uniform(osg::Uniform::INT, shader::kLightVisibilitySlot, shader::kMaxLights);
    for (int i = 0; i < shader::kMaxLights; ++i) slots->setElement(unsigned(i), -1);
    stateSet.addUniform(slots.get());
}

}  // namespace osgBTF
