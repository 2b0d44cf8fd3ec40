// osgBTF: what one fragment of a method's shader costs, counted statically from the GLSL.
//
// Each method supplies its count through MethodInfo::shaderCost (its shader is in its folder's
// care); harness/MaterialShaderCost.h applies it to a fitted material for the comparison's Table 3.
#pragma once

#include <string>

namespace osgBTF {

/** Operations of one fragment, split like Meseth et al. 2003 Table 3 into a fixed part and a part
 * per light.
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

    // shaders/common/btf_main.glsl, once per fragment: normal 1, Gram-Schmidt tangent 3,
    // degenerate test 2, normalize 1, bitangent 4, eye direction 4, local view 3 dots, fixed-view
    // test 1, texel selection 5 (the nearest texel; the filtered blends add blendingTexels' own
    // count), view.z test 1.
    static constexpr int kFrameAlu = 25;
    // The light loop body around btfEvaluate: direction select + normalize 4, 3 dots, horizon
    // test 1, colour multiply-add 2.
    static constexpr int kLightLoopAlu = 10;
    // shaders/common/directions.glsl btfLookupDirections, exact Delaunay weights: disc map 4,
    // cell 4, cell address 2 + texel address 2, loop bound 2, outside test 3, index address 2 +
    // rounding 1 = 20 ALU and 2 fetches (cell, indices); per candidate triangle tested: loop 2,
    // 2 texel addresses 5, barycentric weights 14, lowest 2, best test 1 + index address 1, break
    // test 1 = 26 ALU, 2 fetches; inside the triangulation clamp and normalise 4; outside it the
    // loop bound 2 and per hull edge tested: loop 2, texel address 2, projection 9, distance 1,
    // best test 1 + weights and index address 2 = 17 ALU, 1 fetch. How many candidates a lookup
    // tests depends on the direction (it stops at the triangle that holds it): those loops are
    // counted at their mean over directions uniform on the hemisphere, measured on the material's
    // own table (DirectionLookup::cost), not at the worst cell.
    static constexpr int kLookupAlu = 20, kLookupTex = 2;
    static constexpr int kLookupTriangleAlu = 26, kLookupTriangleTex = 2;
    static constexpr int kLookupInsideAlu = 4, kLookupOutsideAlu = 2;
    static constexpr int kLookupEdgeAlu = 17, kLookupEdgeTex = 1;

    // btf_main.glsl's blend of texel values (Material::TexelFilter::Values), per fragment and
    // level: btfAddBilinearTaps = fract, scale, offset 3, floor and weights 2, clamp 2, wrap
    // below 6, wrap above 8, four weights 12, four texel addresses 4, four btfAddTap (test,
    // count) 8 = 45; per light and evaluated texel: loop test and count 2, weight multiply-add 2.
    static constexpr int kBlendLevelAlu = 45;
    static constexpr int kBlendTapAlu = 4;

    /** This count (a method's, for one evaluation per light) when btf_main.glsl evaluates
     *  `texels` texels per light and blends them (4: bilinear; 8: trilinear between two mip
     *  levels, the worst case), over `levels` levels: the evaluation's part of the per-light
     *  count (all but the light loop's kLightLoopAlu) once per texel. */
    ShaderCost blendingTexels(int texels, int levels) const {
        ShaderCost c = *this;
        if (!counted) return c;
        c.fixedAlu += levels * kBlendLevelAlu;
        c.perLightAlu = kLightLoopAlu + texels * (perLightAlu - kLightLoopAlu + kBlendTapAlu);
        c.perLightTex = texels * perLightTex;
        c.formula = std::to_string(texels) + " texels x (" + formula + ", less the light loop's " +
                    std::to_string(kLightLoopAlu) + ", plus " + std::to_string(kBlendTapAlu) +
                    " ALU to blend)";
        return c;
    }

    /** The count of a method whose btfEvaluate costs `evaluateAlu` / `evaluateTex`: the shared
     *  frame set-up as the fixed part, the light loop body plus btfEvaluate per light. */
    static ShaderCost ofEvaluate(int evaluateAlu, int evaluateTex, std::string formula) {
        ShaderCost c;
        c.fixedAlu = kFrameAlu;
        c.fixedTex = 0;
        c.perLightAlu = kLightLoopAlu + evaluateAlu;
        c.perLightTex = evaluateTex;
        c.counted = true;
        c.formula = std::move(formula);
        return c;
    }
};

}  // namespace osgBTF
