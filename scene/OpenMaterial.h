// osgBTF: opening a material file the way every front end does (the osgDB plugins, MaterialNode,
// `btf eval`, btfviewer through the plugins): a fitted-material file as saved, and a UBO2014
// ".btf" as what it is, a material of the method with UBO2014 factors (MethodInfo::factors: fmf)
// made of its stored factors: no
// decode of the measured data and no refit, so a full-size file (22 GB decoded, ~100 MB stored)
// opens in seconds. Fitting a method to a .btf (`-O method=...`, `btf fit`) decodes it as
// before. And the same, shared: every open of one unchanged file gives one Material
// (loadSharedMaterial; coordinate maps likewise), which MaterialNode, the plugins and the fit
// cache (fit/FitCache.cpp) use; here, not beside MaterialNode, so that opening a material needs
// no scene-graph node. Lives in scene/ because it joins loaders/ and materials/, which may not
// include each other.
#pragma once

#include <cstddef>
#include <memory>
#include <string>

#include <osg/ref_ptr>

#include "core/CoordinateMap.h"
#include "core/FittedMaterialFile.h"
#include "materials/Material.h"

namespace osgBTF {

/** The stored factorisation of a UBO2014 file (readUbo2014) as a material of factorMethod()
 *  (FactorHooks::fromFactors): DFMF with its colour model and per-channel ranks, FMF with its
 *  dynamic-range reduction, and the cosine flag, applied after the factor sums as the decoder
 *  does. Textures in `storage`: Half (default), or Float, which is kept only when the file
 *  stores float or double scalars (a half file gains nothing from float textures).
 *  Material::sourceFile is `path`. Throws Error "<path>: problem" like readUbo2014; the memory
 *  guard sees only the factors, never the decoded size. */
osg::ref_ptr<Material> openUbo2014Material(
    const std::string& path, MaterialTexture::PixelKind storage = MaterialTexture::Half);

/** A UBO2014 file (loaders' isUbo2014File) through openUbo2014Material, any other file through
 *  loadMaterial (a fitted-material file). */
osg::ref_ptr<Material> openMaterial(const std::string& path,
                                    MaterialTexture::PixelKind storage = MaterialTexture::Half);

/** Opens a material file (openMaterial: a fitted-material file, or a
 *  UBO2014 .btf as the `fmf` material of its stored factors, textures in `factorStorage`),
 *  sharing the Material with every earlier open of the same file (same path, size and
 *  modification time, same storage) that is still alive. Throws Error like loadMaterial. */
osg::ref_ptr<Material> loadSharedMaterial(
    const std::string& path, MaterialTexture::PixelKind factorStorage = MaterialTexture::Half);

/** Deletes the shared objects nothing outside their caches holds any more: materials
 *  (loadSharedMaterial), coordinate-map textures and terminator textures; returns how many. Each
 *  cache drops its unused objects whenever it is asked for one, and MaterialNode's destructor and
 *  setMaterial call this, so a material goes with the last node drawing it; an application that
 *  holds materials itself and drops them can call it to free their memory at once.
 *  Thread-safe. */
std::size_t releaseUnusedSharedObjects();
/** The same for the materials alone (loadSharedMaterial); returns how many. Thread-safe. */
std::size_t releaseUnusedSharedMaterials();

/** Reads a coordinate map file (readCoordinateMap), sharing it with every earlier read of the
 *  same file (same path, size and modification time) that is still alive. Throws Error "FILE:
 *  problem". */
std::shared_ptr<const CoordinateMap> loadSharedCoordinateMap(const std::string& path);

}  // namespace osgBTF
