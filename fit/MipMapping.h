// osgBTF: fitting any method as a mip-mapped material (core/MipPyramid.h).
#pragma once

#include "core/BtfSource.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

/** (libosgBTFFit) `method` fitted on the mip-map atlas of `source` (every level's box-filtered
 * ABRDFs), marked mip-mapped: its shader then picks levels from screen-space derivatives. The fit
 * sees 1.5x the base's texels, and reads each base texel once per level (ABRDF reads) or each image
 * once. */
osg::ref_ptr<Material> fitMipMapped(const MethodInfo& method, const BtfSource& source,
                                    const FitOptions& options);

}  // namespace osgBTF
