#include "scene/OpenMaterial.h"

#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <system_error>
#include <utility>

#include "loaders/LoadBtf.h"
#include "loaders/LoadOptions.h"
#include "loaders/Ubo2014.h"
#include "materials/FactorHooks.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "scene/SharedObjects.h"

namespace osgBTF {

namespace {

/** Path + size + modification time: a file rewritten since is read again. */
std::string fileStamp(const std::string& path, std::string& canonicalPath) {
    namespace fs = std::filesystem;
    std::error_code error;
    fs::path canonical = fs::weakly_canonical(path, error);
    if (error) canonical = path;
    canonicalPath = canonical.string();
    const auto size = fs::file_size(canonical, error);
    const auto time = fs::last_write_time(canonical, error);
    return std::to_string(size) + ":" + std::to_string(time.time_since_epoch().count());
}

/** The materials opened from files: two nodes naming the same file (same path, size and
 *  modification time, same texture storage) use one Material, hence one StateSet and one copy of
 *  its textures per context. Never destroyed: materials still held at exit would otherwise be
 *  deleted during static destruction, after OSG's own singletons may be gone. */
SharedObjects<std::string, Material, std::string>& sharedMaterials() {
    static auto* const cache = new SharedObjects<std::string, Material, std::string>;
    return *cache;
}

}  // namespace

osg::ref_ptr<Material> openUbo2014Material(const std::string& path,
                                           MaterialTexture::PixelKind storage) {
    const FactorHooks& hooks = *factorMethod().factors;
    osg::ref_ptr<Material> material;
    if (hooks.receiver) {
        // The texel factors straight into the material's layout, never as floats (the first
        // image's time and memory: docs/viewing.md).
        std::unique_ptr<FactorReceiver> receiver = hooks.receiver(storage);
        LoadOptions options;
        options.texelFactors = receiver.get();
        Ubo2014Factors file = readUbo2014(path, options);
        material = receiver->finish(std::move(static_cast<FactoredBtf&>(file)));
    } else {
        Ubo2014Factors file = readUbo2014(path);
        if (file.scalarSize == 2) storage = MaterialTexture::Half;
        material = hooks.fromFactors(std::move(static_cast<FactoredBtf&>(file)), storage);
    }
    material->sourceFile = path;
    return material;
}

osg::ref_ptr<Material> openMaterial(const std::string& path, MaterialTexture::PixelKind storage) {
    return isUbo2014File(path) ? openUbo2014Material(path, storage) : loadMaterial(path);
}

osg::ref_ptr<Material> loadSharedMaterial(const std::string& path,
                                          MaterialTexture::PixelKind factorStorage) {
    std::string canonical;
    const std::string stamp = fileStamp(path, canonical);
    // A file in two storages is two entries.
    return sharedMaterials().get(canonical + "|" + std::to_string(int(factorStorage)), stamp,
                                 [&] { return openMaterial(path, factorStorage); });
}

std::size_t releaseUnusedSharedMaterials() {
    return sharedMaterials().releaseUnused();
}

std::shared_ptr<const CoordinateMap> loadSharedCoordinateMap(const std::string& path) {
    std::string canonical;
    const std::string stamp = fileStamp(path, canonical);
    static std::mutex mutex;
    static std::map<std::string, std::pair<std::string, std::weak_ptr<const CoordinateMap>>> loaded;
    {
        std::lock_guard<std::mutex> lock(mutex);
        const auto it = loaded.find(canonical);
        if (it != loaded.end() && it->second.first == stamp)
            if (std::shared_ptr<const CoordinateMap> map = it->second.second.lock()) return map;
    }
    auto map = std::make_shared<const CoordinateMap>(readCoordinateMap(path));
    std::lock_guard<std::mutex> lock(mutex);
    loaded[canonical] = {stamp, map};
    return map;
}

}  // namespace osgBTF
