// osgBTF: what a method registers whose material is a factorisation in the terms of the UBO2014
// files (core/FactoredBtf.h: Eigen-ABRDFs U and Eigen-Textures SxV, per channel or shared): such a
// material is saved as a UBO2014 .btf (`btf fit -o X.btf`), a UBO2014 file opens as one, used as
// stored (scene/OpenMaterial.h), and BSVTF streams it (streaming/). MethodInfo::factors,
// materials/MethodRegistry.h; one method registers it.
#pragma once

#include <functional>
#include <memory>

#include <osg/ref_ptr>

#include "core/FactoredBtf.h"
#include "core/FittedMaterialFile.h"

namespace osgBTF {

class Material;

/** A TexelFactorSink that makes the method's material: a reader hands it the texel factors as it
 *  reads them (LoadOptions::texelFactors), finish() takes the rest. */
class FactorReceiver : public TexelFactorSink {
public:
    /** The material of `factors`, read with this receiver (their SxV matrices have 0 rows).
     *  Throws Error as FactoredBtf::validate and the method's own checks. */
    virtual osg::ref_ptr<Material> finish(FactoredBtf&& factors) = 0;
};

/** The functions get materials of the method's own class. */
struct FactorHooks {
    /** The factors as rendered, described: model, colour model, ranks, S (their U and SxV
     *  matrices may be empty where the material keeps them as textures). No copy. */
    std::function<const FactoredBtf&(const Material&)> description;
    /** A copy with every matrix filled in: what a UBO2014 file stores, or a fit starts from. */
    std::function<FactoredBtf(const Material&)> complete;
    /** Bytes per scalar that a UBO2014 file of the material stores: 4 for float textures, 2 for
     *  half. */
    std::function<int(const Material&)> scalarBytes;
    /** The method's material of `factors`, used as stored (no refit), textures in `storage`.
     *  Throws Error as FactoredBtf::validate. */
    std::function<osg::ref_ptr<Material>(FactoredBtf&& factors, MaterialTexture::PixelKind storage)>
        fromFactors;
    /** Optional: a receiver for a reader, whose material equals fromFactors' on the factors read
     *  without it (textures in `storage`, half when the file stores halves), without holding the
     *  texel factors as floats on the way (scene/OpenMaterial.h opens UBO2014 files with it). */
    std::function<std::unique_ptr<FactorReceiver>(MaterialTexture::PixelKind storage)> receiver;
};

}  // namespace osgBTF
