#include "core/Modules.h"

#include <dlfcn.h>

namespace osgBTF {

void* loadModuleSymbol(const void* addressInLibrary, const std::string& fileName,
                       const char* symbol, std::string& error) {
    Dl_info library{};
    std::string folder = ".";
    if (dladdr(addressInLibrary, &library) && library.dli_fname) {
        folder = library.dli_fname;
        const auto slash = folder.rfind('/');
        folder = slash == std::string::npos ? "." : folder.substr(0, slash);
    }
    const std::string path = folder + "/" + fileName;
    // RTLD_LOCAL: the module's dependencies stay out of the symbols other code resolves against.
    void* module = dlopen(path.c_str(), RTLD_NOW | RTLD_LOCAL);
    if (!module) {
        const char* reason = dlerror();
        error = reason ? reason : path + ": cannot be loaded";
        return nullptr;
    }
    void* address = dlsym(module, symbol);
    if (!address) error = path + ": has no symbol " + symbol;
    return address;
}

}  // namespace osgBTF
