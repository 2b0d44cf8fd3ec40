#include "harness/ShaderCost.h"

#include <algorithm>

namespace osgBTF {

ShaderCost shaderCost(const Material& material) {
    const std::vector<std::string> names = methodNames();
    const std::string method = material.methodName();
    if (std::find(names.begin(), names.end(), method) != names.end()) {
        const MethodInfo& info = findMethod(method);
        if (info.shaderCost) return info.shaderCost(material);
    }
    ShaderCost unknown;
    unknown.formula = "not counted";
    return unknown;
}

}  // namespace osgBTF
