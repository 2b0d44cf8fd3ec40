#include "fit/FitCache.h"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <sstream>
#include <system_error>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/Notify.h"
#include "fit/MipMapping.h"
#include "loaders/LoadBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "scene/OpenMaterial.h"

namespace fs = std::filesystem;

namespace osgBTF {

namespace {

std::string hex64(std::uint64_t value) {
    char text[17];
    std::snprintf(text, sizeof text, "%016llx", static_cast<unsigned long long>(value));
    return text;
}

std::uint64_t fnv1a64(const std::string& text) {
    std::uint64_t hash = 14695981039346656037ull;
    for (unsigned char c : text) {
        hash ^= c;
        hash *= 1099511628211ull;
    }
    return hash;
}

}  // namespace

std::string defaultFitCacheFolder() {
    if (const char* dir = std::getenv("OSGBTF_CACHE_DIR"); dir && *dir) return dir;
    if (const char* xdg = std::getenv("XDG_CACHE_HOME"); xdg && *xdg)
        return (fs::path(xdg) / "osgbtf").string();
    if (const char* home = std::getenv("HOME"); home && *home)
        return (fs::path(home) / ".cache" / "osgbtf").string();
    return {};
}

std::string fitCacheKey(const std::string& path, const std::string& method,
                        const FitOptions& options, bool mipmap) {
    std::error_code error;
    const fs::path absolute = fs::absolute(path, error);
    std::ostringstream key;
    key << "osgbtf-fit-cache-1|" << (error ? fs::path(path) : absolute).lexically_normal().string()
        << "|";
    if (fs::is_directory(path, error)) {
        // A folder of images: its newest member stands for its modification time.
        std::uintmax_t size = 0;
        fs::file_time_type newest{};
        for (const auto& entry : fs::directory_iterator(path, error)) {
            if (!entry.is_regular_file(error)) continue;
            size += entry.file_size(error);
            newest = std::max(newest, entry.last_write_time(error));
        }
        key << size << "|" << newest.time_since_epoch().count();
    } else {
        key << fs::file_size(path, error) << "|"
            << fs::last_write_time(path, error).time_since_epoch().count();
    }
    key << "|" << method << (mipmap ? "|mipmap" : "");
    for (const auto& [name, value] : options.values()) key << "|" << name << "=" << value;
    return key.str();
}

osg::ref_ptr<Material> fitCached(const std::string& path, const MethodInfo& method,
                                 const FitOptions& options, const std::string& cacheFolder,
                                 bool mipmap) {
    std::string optionText;
    for (const auto& [name, value] : options.values())
        optionText += (optionText.empty() ? "" : " ") + name + "=" + value;
    const std::string key = fitCacheKey(path, method.name, options, mipmap);

    fs::path cacheFile;
    if (!cacheFolder.empty()) {
        cacheFile = fs::path(cacheFolder) / (fs::path(path).filename().string() + "-" +
                                             method.name + "-" + hex64(fnv1a64(key)) + ".btfmat");
        std::error_code error;
        if (fs::exists(cacheFile, error)) {
            try {
                osg::ref_ptr<Material> material = loadSharedMaterial(cacheFile.string());
                const auto it = material->fitInfo.find("cacheKey");
                if (it != material->fitInfo.end() && it->second == key) {
                    OSGBTF_NOTIFY(osg::NOTICE, "osgBTF: " << path << ": using the cached fit "
                                                          << cacheFile.string());
                    return material;
                }
                OSGBTF_NOTIFY(osg::NOTICE,
                              "osgBTF: " << cacheFile.string()
                                         << " was fitted from something else; fitting again");
            } catch (const Error& e) {
                OSGBTF_NOTIFY(osg::WARN, "osgBTF: ignoring the damaged cache file " << e.what());
            }
        }
    }
    OSGBTF_NOTIFY(osg::NOTICE,
                  "osgBTF: " << path << ": fitting method '" << method.name << "'"
                             << (optionText.empty() ? std::string() : " (" + optionText + ")")
                             << (cacheFile.empty() ? std::string(", cache off")
                                                   : ", then caching it in " + cacheFile.string()));
    osg::ref_ptr<Material> material;
    {
        // A UBO2014 file is fitted from its factors, decoded block by block, never whole.
        const std::unique_ptr<BtfSource> source = openBtfSource(path);
        material = mipmap ? fitMipMapped(method, *source, options) : method.fit(*source, options);
    }
    material->fitInfo["cacheKey"] = key;
    if (!cacheFile.empty()) {
        try {
            std::error_code error;
            fs::create_directories(cacheFile.parent_path(), error);
            if (error) fail(cacheFile.parent_path().string(), "cannot create: " + error.message());
            // Temporaries of cache writers that were killed (ENTRY.btfmat.tmp<pid>): one folder
            // scan per fit, which takes far longer.
            removeStaleTemporaries(cacheFile.parent_path().string(), [](const std::string& stem) {
                return stem.size() > 7 && stem.compare(stem.size() - 7, 7, ".btfmat") == 0;
            });
            saveMaterial(*material, cacheFile.string());  // atomic: temporary name, then rename
            material->sourceFile = cacheFile.string();
        } catch (const Error& e) {
            OSGBTF_NOTIFY(osg::WARN, "osgBTF: cannot cache the fit: " << e.what());
        }
    }
    return material;
}

}  // namespace osgBTF
