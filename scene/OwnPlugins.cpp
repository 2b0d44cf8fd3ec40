#include "scene/OwnPlugins.h"

#include <dlfcn.h>

#include <algorithm>
#include <cstdlib>
#include <filesystem>
#include <mutex>
#include <system_error>

#include <osg/Version>
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
    return added;
}

}  // namespace osgBTF
