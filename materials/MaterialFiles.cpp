#include "materials/MaterialFiles.h"

#include <algorithm>
#include <cctype>
#include <filesystem>

#include "core/Error.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

const ForeignFileFormat* findForeignFile(const std::string& path, std::string* method) {
    // The file name's ending: an extension (".ptm") or a whole name ("info.json").
    std::string fileName = std::filesystem::path(path).filename().string();
    for (char& c : fileName) c = char(std::tolower(static_cast<unsigned char>(c)));
    // An extension needs a name before it (".ptm" alone is a hidden file, as for
    // std::filesystem); a whole name matches only itself ("myinfo.json" is not relight's).
    const auto matches = [&](const std::string& ending) {
        if (ending.empty() || ending[0] != '.') return fileName == ending;
        return fileName.size() > ending.size() &&
               fileName.compare(fileName.size() - ending.size(), ending.size(), ending) == 0;
    };
    for (const std::string& name : methodNames())
        for (const ForeignFileFormat& format : findMethod(name).foreignFiles)
            if (matches(format.extension)) {
                if (method) *method = name;
                return &format;
            }
    return nullptr;
}

bool ForeignFileFormat::writes(const std::string& owner, const std::string& method) const {
    if (!methods) return method == owner;
    const std::vector<std::string> list = methods();
    return std::find(list.begin(), list.end(), method) != list.end();
}

std::string writtenMethodsText(const ForeignFileFormat& format, const std::string& owner) {
    if (!format.methods) return "a " + owner;
    std::string text;
    const std::vector<std::string> list = format.methods();
    for (std::size_t i = 0; i < list.size(); ++i)
        text += (i == 0 ? "" : i + 1 == list.size() ? " or " : ", ") + list[i];
    return "a " + text;
}

std::string saveMaterial(const Material& material, const std::string& path) {
    std::string owner;
    if (const ForeignFileFormat* format = findForeignFile(path, &owner)) {
        if (!format->write)
            fail(path, "osgBTF reads " + format->description +
                           " but does not write it; save as .btfmat or another tool's file");
        if (!format->writes(owner, material.methodName()))
            fail(path, "a " + format->extension + " file holds " +
                           writtenMethodsText(*format, owner) + " material, not " +
                           material.methodName());
        return format->write(material, path);
    }
    saveFittedMaterial(material.toFittedMaterial(), path);
    return {};
}

osg::ref_ptr<Material> materialFromFile(FittedMaterial file) {
    const MethodInfo* info = findMethodIfRegistered(file.method);
    if (!info)
        fail(
            file.source, "unknown method '" + file.method + "' (this osgBTF knows: " + [] {
                std::string known;
                for (const auto& n : methodNames()) known += (known.empty() ? "" : ", ") + n;
                return known;
            }() + ")");
    return info->load(std::move(file));
}

osg::ref_ptr<Material> loadMaterial(const std::string& path) {
    if (const ForeignFileFormat* format = findForeignFile(path)) {
        osg::ref_ptr<Material> material = format->read(path);
        material->sourceFile = path;
        return material;
    }
    osg::ref_ptr<Material> material =
        materialFromFile(loadFittedMaterial(path, [](const std::string& method) {
            const MethodInfo* info = findMethodIfRegistered(method);
            return info ? info->compactTextures : CompactTextures{};
        }));
    material->sourceFile = path;
    return material;
}

}  // namespace osgBTF
