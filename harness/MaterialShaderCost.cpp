#include "harness/MaterialShaderCost.h"
#include "materials/MethodRegistry.h"

#include <algorithm>

namespace osgBTF {

ShaderCost shaderCost(const Material& material) {
    const std::vector<std::string> names = methodNames();
    const std::string method = material.methodName();
    if (std::find(names.begin(), names.end(), method) != names.end()) {
        const MethodInfo& info = findMethod(method);
        if (info.shaderCost) {
            // The method counts one evaluation per light; the blend of texel values (every
            // method that does not filter its parameters, every mip-mapped material) evaluates
            // four texels, eight between two mip levels (the worst case, as the counting rule
            // takes every branch).
            const ShaderCost one = info.shaderCost(material);
            // A method that blends its inputs (TexelFilter::Inputs) counts their blend in its own
            // count: one evaluation.
            if (material.texelFilter() != Material::TexelFilter::Values) return one;
            return material.mipLayout().mipMapped() ? one.blendingTexels(8, 2)
                                                    : one.blendingTexels(4, 1);
        }
    }
    ShaderCost unknown;
    unknown.formula = "not counted";
    return unknown;
}

}  // namespace osgBTF
