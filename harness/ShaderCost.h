// osgBTF harness: what one fragment of a fitted material's shader costs (seed 001 Table 3).
#pragma once

#include "materials/Material.h"
#include "materials/ShaderCost.h"

namespace osgBTF {

/** The static count for a fitted material of any registered method: its MethodInfo::shaderCost,
 *  or counted = false ("not counted") for a method that supplies none. */
ShaderCost shaderCost(const Material& material);

}  // namespace osgBTF
