#include "core/ShaderSource.h"

#include <fstream>
#include <map>
#include <sstream>

#include <osgDB/FileUtils>
#include <osgDB/Registry>

#include "core/Error.h"

namespace osgBTF {

namespace detail {
const std::map<std::string, std::string>& embeddedShaders();  // generated EmbeddedShaders.cpp
}

namespace {

std::string overridePath(const std::string& name) {
    // Only OSG_FILE_PATH (osgDB's data path list), not the current folder: running a tool from
    // the source tree must not silently pick up files.
    return osgDB::findFileInPath("shaders/" + name,
                                 osgDB::Registry::instance()->getDataFilePathList());
}

/** Sources added at run time (addShaderSource), e.g. by a method defined outside the library. */
std::map<std::string, std::string>& addedShaders() {
    static std::map<std::string, std::string> shaders;
    return shaders;
}

std::string rawSource(const std::string& name) {
    const std::string path = overridePath(name);
    if (!path.empty()) {
        std::ifstream in(path, std::ios::binary);
        std::ostringstream text;
        if (!in || !(text << in.rdbuf())) fail(path, "cannot read shader");
        return text.str();
    }
    const auto& embedded = detail::embeddedShaders();
    if (const auto it = embedded.find(name); it != embedded.end()) return it->second;
    if (const auto it = addedShaders().find(name); it != addedShaders().end()) return it->second;
    throw Error("shader '" + name + "': not found (neither on OSG_FILE_PATH as shaders/" + name +
                " nor embedded)");
}

std::string resolveIncludes(const std::string& name, int depth) {
    if (depth > 16) throw Error("shader '" + name + "': #pragma include nested too deeply");
    std::istringstream in(rawSource(name));
    std::ostringstream out;
    std::string line;
    const std::string directive = "#pragma include";
    while (std::getline(in, line)) {
        const auto start = line.find_first_not_of(" \t");
        if (start != std::string::npos && line.compare(start, directive.size(), directive) == 0) {
            const auto open = line.find('"'), close = line.rfind('"');
            if (open == std::string::npos || close <= open)
                throw Error("shader '" + name + "': malformed line '" + line + "'");
            out << resolveIncludes(line.substr(open + 1, close - open - 1), depth + 1);
            continue;
        }
        out << line << '\n';
    }
    return out.str();
}

}  // namespace

std::string shaderSource(const std::string& name) {
    return resolveIncludes(name, 0);
}

std::string shaderOrigin(const std::string& name) {
    const std::string path = overridePath(name);
    return path.empty() ? "embedded:" + name : path;
}

std::string addShaderDefine(const std::string& source, const std::string& name) {
    // "NAME VALUE" defines NAME as VALUE, a bare NAME as 1.
    const std::string line =
        "#define " + name + (name.find(' ') == std::string::npos ? " 1\n" : "\n");
    const auto start = source.find_first_not_of(" \t\r\n");
    if (start == std::string::npos || source.compare(start, 8, "#version") != 0)
        return line + source;
    const auto end = source.find('\n', start);
    if (end == std::string::npos) return source + "\n" + line;
    return source.substr(0, end + 1) + line + source.substr(end + 1);
}

void addShaderSource(const std::string& name, const std::string& text) {
    addedShaders()[name] = text;
}

std::vector<std::string> embeddedShaderNames() {
    std::vector<std::string> names;
    for (const auto& entry : detail::embeddedShaders()) names.push_back(entry.first);
    return names;
}

}  // namespace osgBTF
