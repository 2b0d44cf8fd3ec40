// osgBTF: opening a material file the way every front end does (the osgDB plugins, MaterialNode,
// `btf eval`, btfviewer through the plugins): a fitted-material file as saved, and a UBO2014
// ".btf" as what it is, a material of the method with UBO2014 factors (MethodInfo::factors: fmf)
// made of its stored factors: no
// decode of the measured data and no refit, so a full-size file (22 GB decoded, ~100 MB stored)
// opens in seconds. Fitting a method to a .btf (`-O method=...`, `btf fit`) decodes it as
// before. Lives in scene/ because it joins loaders/ and materials/, which may not include each
// other.
#pragma once

#include <string>

#include <osg/ref_ptr>

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

}  // namespace osgBTF
