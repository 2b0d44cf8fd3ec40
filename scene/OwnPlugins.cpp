#include "scene/OwnPlugins.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <system_error>
#include <utility>
#include <vector>

#include <osg/Version>
#include <osgDB/FileUtils>
#include <osgDB/Registry>

namespace osgBTF {

namespace {

/** The folder of the shared object this function is compiled into: libosgBTF's, wherever it was
 *  built or installed (dladdr, not /proc/self/exe: an application linking the library may live
 *  anywhere). */
std::filesystem::path libraryFolder() {
    Dl_info info{};
    if (!dladdr(reinterpret_cast<void*>(&libraryFolder), &info) || !info.dli_fname) return {};
    std::error_code error;
    const std::filesystem::path library = std::filesystem::canonical(info.dli_fname, error);
    return error ? std::filesystem::path() : library.parent_path();
}

std::string addToLibraryPath() {
    const std::filesystem::path folder = libraryFolder();
    std::error_code error;
    if (folder.empty() || !std::filesystem::is_directory(
                              folder / (std::string("osgPlugins-") + osgGetVersion()), error))
        return {};
    osgDB::FilePathList& paths = osgDB::Registry::instance()->getLibraryFilePathList();
    const std::string entry = folder.string();
    if (std::find(paths.begin(), paths.end(), entry) != paths.end()) return {};
    if (std::getenv("OSG_LIBRARY_PATH"))
        paths.push_back(entry);
    else
        paths.push_front(entry);
    return entry;
}

}  // namespace

std::string useOwnPlugins() {
    static std::once_flag once;
    static std::string added;
    std::call_once(once, [] { added = addToLibraryPath(); });
    aliasOwnPlugins();
    return added;
}

std::vector<std::string> aliasOwnPlugins() {
    // (extension, the module osgBTF reads it with): OSG's own plugins for these extensions are
    // osgdb_zip and osgdb_exr, names osgBTF must not take (tests/plugin_names_test.cpp).
    static const std::pair<const char*, const char*> kAliases[] = {{"zip", "btfzip"},
                                                                   {"exr", "btfexr"}};
    static std::mutex mutex;
    static std::vector<std::string> aliased;
    const std::lock_guard<std::mutex> lock(mutex);
    osgDB::Registry* registry = osgDB::Registry::instance();
    for (const auto& [extension, module] : kAliases) {
        if (std::find(aliased.begin(), aliased.end(), extension) != aliased.end()) continue;
        if (osgDB::findLibraryFile(registry->createLibraryNameForExtension(module)).empty())
            continue;
        registry->addFileExtensionAlias(extension, module);
        aliased.push_back(extension);
    }
    return aliased;
}

namespace {
// Any program that loads libosgBTF (an application linking it, or stock osgviewer reading an
// osgBTF scene or material through osgBTF's plugins) reads BTF zips and EXR images by name.
struct AliasOnLoad {
    AliasOnLoad() { aliasOwnPlugins(); }
} aliasOnLoad;
}  // namespace

}  // namespace osgBTF
