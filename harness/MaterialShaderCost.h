// osgBTF harness: what one fragment of a fitted material's shader costs (Meseth et al. 2003 Table
// 3).
#pragma once

#include "materials/Material.h"
#include "materials/ShaderCost.h"

namespace osgBTF {

/** The static count for a fitted material of any registered method: its MethodInfo::shaderCost
 *  (one evaluation per light), times the texels btf_main.glsl blends unless the material filters
 *  its parameters (ShaderCost::blendingTexels; Material::TexelFilter), or counted = false ("not
 *  counted") for a method that supplies none. */
ShaderCost shaderCost(const Material& material);

}  // namespace osgBTF
