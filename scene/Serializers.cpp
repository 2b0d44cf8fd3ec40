// osgDB serializers of libosgBTF's scene classes (.osgt / .osgb / .osgx).
//
// osgBTF::MaterialNode (associates osg::Object osg::Node osg::Group osgBTF::MaterialNode):
//   MaterialFile      the fitted-material file the node refers to (written as given; read back
//                     through osgDB's file search, which includes the folder of the scene
//                     file). Reading it loads the material; a missing or bad file is an OSG_WARN
//                     naming the file, the node then draws its children without the material.
//   TextureScale      tiling (default 1).
//   EmbeddedMaterial  only for a material that has no file (fitted in memory): its whole
//                     FittedMaterial (method, parameters, direction sets, textures with their
//                     float bits as hex text, so .osgt is exact too).
// Every material class (osgBTF::LambertMaterial, LafMaterial, SlafMaterial, RfMaterial,
// PcaMaterial, LpcaMaterial, LpcaRevisedMaterial; associates osg::Object osgBTF::<class>):
//   FittedData        the same whole FittedMaterial, so osgDB::writeObjectFile / readObjectFile
//                     round-trip a material on its own (.osgt exact).
#include <cstdint>
#include <cstring>
#include <sstream>

#include <osgDB/InputStream>
#include <osgDB/ObjectWrapper>
#include <osgDB/OutputStream>
#include <osgDB/Registry>

#include "core/Error.h"
#include "materials/laf/Laf.h"
#include "materials/lambert/Lambert.h"
#include "materials/lpca-revised/LpcaRevised.h"
#include "materials/lpca/Lpca.h"
#include "materials/pca/Pca.h"
#include "materials/rf/Rf.h"
#include "materials/slaf/Slaf.h"
#include "scene/MaterialNode.h"

namespace {

std::string toHex(const std::vector<float>& values) {
    static const char digits[] = "0123456789abcdef";
    std::string text;
    text.reserve(values.size() * 8);
    for (float value : values) {
        std::uint32_t bits;
        std::memcpy(&bits, &value, 4);
        for (int shift = 28; shift >= 0; shift -= 4) text += digits[(bits >> shift) & 0xf];
    }
    return text;
}

bool fromHex(const std::string& text, std::vector<float>& values) {
    if (text.size() % 8 != 0) return false;
    values.resize(text.size() / 8);
    for (std::size_t i = 0; i < values.size(); ++i) {
        std::uint32_t bits = 0;
        for (std::size_t k = 0; k < 8; ++k) {
            const char c = text[i * 8 + k];
            const int digit = c >= '0' && c <= '9'   ? c - '0'
                              : c >= 'a' && c <= 'f' ? c - 'a' + 10
                                                     : -1;
            if (digit < 0) return false;
            bits = (bits << 4) | std::uint32_t(digit);
        }
        std::memcpy(&values[i], &bits, 4);
    }
    return true;
}

bool checkMaterialFile(const osgBTF::MaterialNode& node) {
    return !node.getMaterialFile().empty();
}

bool readMaterialFile(osgDB::InputStream& is, osgBTF::MaterialNode& node) {
    std::string file;
    is.readWrappedString(file);
    node.setMaterialFile(file, is.getOptions());
    return true;
}

bool writeMaterialFile(osgDB::OutputStream& os, const osgBTF::MaterialNode& node) {
    os.writeWrappedString(node.getMaterialFile());
    os << std::endl;
    return true;
}

bool checkEmbeddedMaterial(const osgBTF::MaterialNode& node) {
    return node.getMaterial() && node.getMaterialFile().empty();
}

/** Reads what writeFitted wrote. Returns false on a stream error; throws Error for data that
 *  read but make no material. */
bool readFitted(osgDB::InputStream& is, osgBTF::FittedMaterial& fitted) {
    fitted.source = "material embedded in the scene";
    is.readWrappedString(fitted.method);
    unsigned count = 0;
    is >> count >> is.BEGIN_BRACKET;
    for (unsigned i = 0; i < count; ++i) {
        std::string key, value;
        is.readWrappedString(key);
        is.readWrappedString(value);
        fitted.parameters[key] = value;
    }
    is >> is.END_BRACKET;
    std::string views, lights;
    is.readWrappedString(views);
    is.readWrappedString(lights);
    is >> count >> is.BEGIN_BRACKET;
    bool ok = true;
    for (unsigned i = 0; i < count; ++i) {
        osgBTF::MaterialTexture texture;
        int kind = 0;
        std::string data;
        is.readWrappedString(texture.name);
        is >> texture.width >> texture.height >> texture.depth >> texture.channels >> kind;
        is.readWrappedString(data);
        texture.kind = osgBTF::MaterialTexture::PixelKind(kind);
        ok = ok && fromHex(data, texture.data) && texture.data.size() == texture.valueCount();
        fitted.textures.push_back(std::move(texture));
    }
    is >> is.END_BRACKET;
    if (is.getException()) return false;
    if (!ok) osgBTF::fail(fitted.source, "texture data is damaged");
    fitted.views = osgBTF::DirectionSet::deserialize(views);
    fitted.lights = osgBTF::DirectionSet::deserialize(lights);
    return true;
}

bool readEmbeddedMaterial(osgDB::InputStream& is, osgBTF::MaterialNode& node) {
    try {
        osgBTF::FittedMaterial fitted;
        if (!readFitted(is, fitted)) return false;
        node.setMaterial(osgBTF::materialFromFile(fitted).get());
    } catch (const std::exception& e) {
        OSG_WARN << "osgBTF::MaterialNode: " << e.what()
                 << " (the node draws its children without the material)" << std::endl;
    }
    return true;
}

/** A whole FittedMaterial (method, parameters, direction sets, textures as hex float bits). */
bool writeFitted(osgDB::OutputStream& os, const osgBTF::FittedMaterial& fitted) {
    os.writeWrappedString(fitted.method);
    os << std::endl;
    os << unsigned(fitted.parameters.size()) << os.BEGIN_BRACKET << std::endl;
    for (const auto& [key, value] : fitted.parameters) {
        os.writeWrappedString(key);
        os.writeWrappedString(value);
        os << std::endl;
    }
    os << os.END_BRACKET << std::endl;
    os.writeWrappedString(fitted.views.serialize());
    os << std::endl;
    os.writeWrappedString(fitted.lights.serialize());
    os << std::endl;
    os << unsigned(fitted.textures.size()) << os.BEGIN_BRACKET << std::endl;
    for (const osgBTF::MaterialTexture& texture : fitted.textures) {
        os.writeWrappedString(texture.name);
        os << texture.width << texture.height << texture.depth << texture.channels
           << int(texture.kind);
        os.writeWrappedString(toHex(texture.data));
        os << std::endl;
    }
    os << os.END_BRACKET << std::endl;
    return true;
}

bool writeEmbeddedMaterial(osgDB::OutputStream& os, const osgBTF::MaterialNode& node) {
    return writeFitted(os, node.getMaterial()->toFittedMaterial());
}

// Every material class: one property, FittedData, the material's whole FittedMaterial. Reading
// rebuilds it through the method registry and copies it into the object OSG created.
template <typename M>
bool checkFittedData(const M& material) {
    return material.texelCount() > 0;
}

template <typename M>
bool readFittedData(osgDB::InputStream& is, M& material) {
    try {
        osgBTF::FittedMaterial fitted;
        if (!readFitted(is, fitted)) return false;
        material.assignFrom(*osgBTF::materialFromFile(fitted));
    } catch (const std::exception& e) {
        OSG_WARN << "osgBTF::" << material.className() << ": " << e.what() << std::endl;
    }
    return true;
}

template <typename M>
bool writeFittedData(osgDB::OutputStream& os, const M& material) {
    return writeFitted(os, material.toFittedMaterial());
}

}  // namespace

REGISTER_OBJECT_WRAPPER(osgBTF_MaterialNode, new osgBTF::MaterialNode, osgBTF::MaterialNode,
                        "osg::Object osg::Node osg::Group osgBTF::MaterialNode") {
    ADD_USER_SERIALIZER(MaterialFile);
    ADD_USER_SERIALIZER(EmbeddedMaterial);
    ADD_FLOAT_SERIALIZER(TextureScale, 1.0f);
}

// REGISTER_OBJECT_WRAPPER declares a file-scope typedef MyClass: one namespace per wrapper.
#define OSGBTF_MATERIAL_WRAPPER(CLASS)                                            \
    namespace wrapper_##CLASS {                                                   \
        REGISTER_OBJECT_WRAPPER(osgBTF_##CLASS, new osgBTF::CLASS, osgBTF::CLASS, \
                                "osg::Object osgBTF::" #CLASS) {                  \
            ADD_USER_SERIALIZER(FittedData);                                      \
        }                                                                         \
    }

OSGBTF_MATERIAL_WRAPPER(LambertMaterial)
OSGBTF_MATERIAL_WRAPPER(LafMaterial)
OSGBTF_MATERIAL_WRAPPER(SlafMaterial)
OSGBTF_MATERIAL_WRAPPER(RfMaterial)
OSGBTF_MATERIAL_WRAPPER(PcaMaterial)
OSGBTF_MATERIAL_WRAPPER(LpcaMaterial)
OSGBTF_MATERIAL_WRAPPER(LpcaRevisedMaterial)
