// osgBTF harness: what one fragment of a method's shader costs, counted statically from the GLSL.
#pragma once

#include <string>

#include "materials/Material.h"

namespace osgBTF {

/** Operations of one fragment, split like seed 001 Table 3 into a fixed part and a part per light.
 *
 *  Counting rule (harness/README.md): the shader source as written, loops unrolled to the
 *  material's parameters (lobes, components) and every data-dependent branch taken (all three
 *  interpolation weights non-zero: the worst case). TEX = texture reads (texelFetch or a filtered
 *  texture(); textureSize queries are free). ALU = arithmetic operations: each binary operator,
 *  comparison or select, and each built-in call (dot, pow, normalize, clamp, floor, mix, atan,
 *  ...) counts 1 whatever the vector width; conversions and swizzles are free. The shared frame
 *  set-up of shaders/common/btf_main.glsl is the fixed part; btfEvaluate and the light loop body
 *  are the per-light part. */
struct ShaderCost {
    int fixedAlu = 0, fixedTex = 0;
    int perLightAlu = 0, perLightTex = 0;
    bool counted = false;  ///< false: unknown method, no count
    std::string formula;   ///< the per-light count in terms of the parameters, e.g. "TEX k+2"

    int alu(int lights) const { return fixedAlu + lights * perLightAlu; }
    int tex(int lights) const { return fixedTex + lights * perLightTex; }
};

/** The static count for a fitted material of any registered method (see ShaderCost). */
ShaderCost shaderCost(const Material& material);

}  // namespace osgBTF
