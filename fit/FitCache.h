// osgBTF: the fit cache (libosgBTFFit). A measured BTF is fitted once per method and options;
// the fitted material is saved in a cache folder and read back on the next request, so that an
// application, like the osgDB plugins that fit on load (plugins/btf), opens a measured BTF at the
// cost of reading a fitted file after the first time.
#pragma once

#include <string>

#include <osg/ref_ptr>

#include "materials/Material.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

/** The cache folder by default: $OSGBTF_CACHE_DIR, else $XDG_CACHE_HOME/osgbtf, else
 *  ~/.cache/osgbtf; empty (no cache) when none of them is set. */
std::string defaultFitCacheFolder();

/** Everything a fit of the measured BTF at `path` depends on, as one line: its absolute path,
 *  size and modification time (of a folder of images: their total size and the newest), the
 *  method, mip-mapping and the options. Stored in the fitted file (fit info "cacheKey"), so that
 *  a cache entry whose name collides with another input's is not taken for it. */
std::string fitCacheKey(const std::string& path, const std::string& method,
                        const FitOptions& options, bool mipmap = false);

/** The measured BTF at `path` (a UBO2003 zip or folder, or a UBO2014 .btf, read block by block)
 *  fitted with `method` and `options` (validated by the caller; fitMipMapped when `mipmap`),
 *  through the cache in `cacheFolder`: the entry <folder>/<file name>-<method>-<16 hex digits of
 *  a hash of fitCacheKey>.btfmat is read (loadSharedMaterial) when its key matches, and written
 *  atomically after a fit otherwise (a damaged or foreign entry is fitted again and replaced).
 *  An empty `cacheFolder` fits every time. A folder that cannot be written only costs the
 *  caching (a warning), not the fit. OSG's notify says at NOTICE which of the two happened.
 *  Throws Error for a file that cannot be read or fitted. */
osg::ref_ptr<Material> fitCached(const std::string& path, const MethodInfo& method,
                                 const FitOptions& options, const std::string& cacheFolder,
                                 bool mipmap = false);

}  // namespace osgBTF
