#include "materials/MaterialSerializer.h"

#include <cstdint>
#include <cstring>
#include <istream>

#include <osgDB/ObjectWrapper>
#include <osgDB/Registry>
#include <osgDB/Serializer>

#include "core/Error.h"
#include "core/Notify.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"

namespace osgBTF {

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

/** Reaches InputStream's protected iterator: a member pointer formed in a derived class is a
 *  pointer to InputStream's member, usable on any InputStream (no cast of the object). */
struct IteratorAccess : osgDB::InputStream {
    static osgDB::InputIterator* of(osgDB::InputStream& is) {
        return (is.*(&IteratorAccess::_in)).get();
    }
};

/** Whether OSG 3.6.5's AsciiInputIterator::readWrappedString would find the end of the string
 *  that starts at the stream's position: it skips ' ', '\n', '\r', then reads a quoted string
 *  up to its closing '"' ('\\' escapes the next character) or a bare word up to ' ', '\n' or
 *  '\0'. It reads with istream::get, which at the end of the stream leaves the character it was
 *  given unchanged, so there each of those loops spins forever (the string loops appending that
 *  character: memory grows too). Looks ahead in the stream buffer and seeks back. */
bool wrappedStringEnds(std::istream& in) {
    // A failed or ended stream: get() extracts nothing, OSG then tests an uninitialised char.
    if (!in.good()) return false;
    std::streambuf* buffer = in.rdbuf();
    const std::streampos start = buffer->pubseekoff(0, std::ios::cur, std::ios::in);
    // A stream that cannot seek back: leave it to OSG's reader (files and string streams can).
    if (start == std::streampos(std::streamoff(-1))) return true;
    using Traits = std::char_traits<char>;
    const Traits::int_type eof = Traits::eof();
    Traits::int_type c = buffer->sbumpc();
    while (c == ' ' || c == '\n' || c == '\r') c = buffer->sbumpc();
    bool ends = false;
    if (c == '"') {
        for (c = buffer->sbumpc(); c != eof && c != '"'; c = buffer->sbumpc())
            if (c == '\\' && (c = buffer->sbumpc()) == eof) break;
        ends = c == '"';
    } else if (c != eof) {
        while (c != eof && c != ' ' && c != '\n' && c != 0) c = buffer->sbumpc();
        ends = c != eof;
    }
    buffer->pubseekpos(start, std::ios::in);
    return ends;
}

// Every material class: one property, FittedData, the material's whole FittedMaterial. Reading
// rebuilds it through the method registry and copies it into the object OSG created.
bool checkFittedData(const Material& material) {
    return material.texelCount() > 0;
}

bool readFittedData(osgDB::InputStream& is, Material& material) {
    try {
        FittedMaterial fitted;
        if (!readFittedMaterial(is, fitted)) return false;
        material.assignFrom(*materialFromFile(std::move(fitted)));
    } catch (const std::exception& e) {
        OSGBTF_NOTIFY(osg::WARN, "osgBTF::" << material.className() << ": " << e.what());
    }
    return true;
}

bool writeFittedData(osgDB::OutputStream& os, const Material& material) {
    return writeFittedMaterial(os, material.toFittedMaterial());
}

}  // namespace

bool readWrappedStringChecked(osgDB::InputStream& is, std::string& text) {
    text.clear();
    if (is.getException()) return false;
    if (!is.isBinary()) {
        osgDB::InputIterator* iterator = IteratorAccess::of(is);
        std::istream* in = iterator ? iterator->getStream() : nullptr;
        if (!in || !wrappedStringEnds(*in)) {
            is.throwException(
                "InputStream: the stream ends inside a string (truncated or damaged)");
            return false;
        }
    }
    is.readWrappedString(text);
    return !is.getException();
}

/** Reads what writeFitted wrote. Returns false on a stream error; throws Error for data that
 *  read but make no material. */
bool readFittedMaterial(osgDB::InputStream& is, FittedMaterial& fitted) {
    fitted.source = "material embedded in the scene";
    readWrappedStringChecked(is, fitted.method);
    unsigned count = 0;
    is >> count >> is.BEGIN_BRACKET;
    // Counts come from the file: stop at the first stream error or empty name (what reads past
    // the end give), or a damaged count (e.g. 4000000000) spins for minutes on reads that all
    // fail. Saved materials never have empty names.
    for (unsigned i = 0; i < count && !is.getException(); ++i) {
        std::string key, value;
        readWrappedStringChecked(is, key);
        readWrappedStringChecked(is, value);
        if (key.empty()) fail(fitted.source, "a parameter has no name (damaged or truncated)");
        fitted.parameters[key] = value;
    }
    is >> is.END_BRACKET;
    std::string views, lights;
    readWrappedStringChecked(is, views);
    readWrappedStringChecked(is, lights);
    is >> count >> is.BEGIN_BRACKET;
    bool ok = true;
    for (unsigned i = 0; i < count && !is.getException(); ++i) {
        MaterialTexture texture;
        int kind = 0;
        std::string data;
        readWrappedStringChecked(is, texture.name);
        is >> texture.width >> texture.height >> texture.depth >> texture.channels >> kind;
        readWrappedStringChecked(is, data);
        if (texture.name.empty())
            fail(fitted.source, "a texture has no name (damaged or truncated)");
        if (kind < MaterialTexture::Half || kind > MaterialTexture::UNorm8)
            fail(fitted.source, "texture '" + texture.name + "' has an unknown pixel kind " +
                                    std::to_string(kind));
        texture.kind = MaterialTexture::PixelKind(kind);
        // Positive sizes first: valueCount() of negative ones wraps around and can match.
        ok = ok && texture.width > 0 && texture.height > 0 && texture.depth > 0 &&
             texture.channels > 0 && fromHex(data, texture.data) &&
             texture.data.size() == texture.valueCount();
        fitted.textures.push_back(std::move(texture));
    }
    is >> is.END_BRACKET;
    if (is.getException()) return false;
    if (!ok) fail(fitted.source, "texture data is damaged");
    fitted.views = DirectionSet::deserialize(views);
    fitted.lights = DirectionSet::deserialize(lights);
    return true;
}

bool writeFittedMaterial(osgDB::OutputStream& os, const FittedMaterial& fitted) {
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
    for (const MaterialTexture& texture : fitted.textures) {
        os.writeWrappedString(texture.name);
        os << texture.width << texture.height << texture.depth << texture.channels
           << int(texture.kind);
        // Textures held as bytes or halves are written as their values.
        std::vector<float> values;
        if (texture.data.empty())
            for (std::size_t i = 0; i < texture.storedCount(); ++i)
                values.push_back(texture.value(i));
        os.writeWrappedString(toHex(texture.data.empty() ? values : texture.data));
        os << std::endl;
    }
    os << os.END_BRACKET << std::endl;
    return true;
}

void addMaterialWrapper(const MethodInfo& method) {
    if (!method.createInstance) return;
    const osg::ref_ptr<osg::Object> prototype = method.createInstance();
    const std::string name = std::string(prototype->libraryName()) + "::" + prototype->className();
    osg::ref_ptr<osgDB::ObjectWrapper> wrapper =
        new osgDB::ObjectWrapper(method.createInstance, name, "osg::Object " + name);
    wrapper->addSerializer(new osgDB::UserSerializer<Material>("FittedData", &checkFittedData,
                                                               &readFittedData, &writeFittedData),
                           osgDB::BaseSerializer::RW_USER);
    osgDB::ObjectWrapperManager* manager = osgDB::Registry::instance()->getObjectWrapperManager();
    // Not findWrapper: on a miss it searches for a serializer plugin, and this runs while the
    // library itself is being loaded. A method registered again replaces its wrapper quietly.
    manager->getWrapperMap().erase(name);
    manager->addWrapper(wrapper.get());
}

}  // namespace osgBTF
