#include "materials/MaterialFiles.h"

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

std::string saveMaterial(const Material& material, const std::string& path) {
    std::string owner;
    if (const ForeignFileFormat* format = findForeignFile(path, &owner)) {
        if (!format->write)
            fail(path, "osgBTF reads " + format->description +
                           " but does not write it; save as .btfmat or another tool's file");
        if (material.methodName() != owner)
            fail(path, "a " + format->extension + " file holds a " + owner + " material, not " +
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
