#include "harness/ShaderCost.h"

#include "materials/laf/Laf.h"
#include "materials/lpca-revised/LpcaRevised.h"
#include "materials/lpca/Lpca.h"
#include "materials/pca/Pca.h"
#include "materials/rf/Rf.h"
#include "materials/slaf/Slaf.h"

namespace osgBTF {

namespace {

// shaders/common/btf_main.glsl, once per fragment: normal 1, Gram-Schmidt tangent 3, degenerate
// test 2, normalize 1, bitangent 4, eye direction 4, local view 3 dots, fixed-view test 1,
// btfTexel 5, view.z test 1.
constexpr int kFrameAlu = 25;
// The light loop body around btfEvaluate: direction select + normalize 4, 3 dots, horizon test 1,
// colour multiply-add 2.
constexpr int kLightLoopAlu = 10;
// shaders/common/directions.glsl btfLookupDirections: disc map 4, cell 6, index rounding 1; the
// index and weight tables are 2 fetches.
constexpr int kLookupAlu = 11, kLookupTex = 2;

ShaderCost cost(int evaluateAlu, int evaluateTex, std::string formula) {
    ShaderCost c;
    c.fixedAlu = kFrameAlu;
    c.fixedTex = 0;
    c.perLightAlu = kLightLoopAlu + evaluateAlu;
    c.perLightTex = evaluateTex;
    c.counted = true;
    c.formula = std::move(formula);
    return c;
}

}  // namespace

ShaderCost shaderCost(const Material& material) {
    const std::string method = material.methodName();
    if (method == "lambert") return cost(1, 1, "ALU 11, TEX 1");
    if (const auto* laf = dynamic_cast<const LafMaterial*>(&material)) {
        // v*l 1; per lobe: row index 2, dot, test, pow, add; bracket 5. Fetches: lobes + rhoD,
        // rhoS.
        const int k = laf->lobeCount();
        return cost(6 + 6 * k, k + 2, "ALU 6k+16, TEX k+2 (k lobes)");
    }
    if (const auto* slaf = dynamic_cast<const SlafMaterial*>(&material)) {
        // View lookup; T: 3 multiply-adds and 3 fetches; v*l 1; lobes as LAF; bracket 5; T* 1.
        const int k = slaf->lobeCount();
        return cost(kLookupAlu + 6 + 1 + 6 * k + 5 + 1, kLookupTex + 3 + k + 2,
                    "ALU 6k+34, TEX k+7 (k lobes)");
    }
    if (const auto* rf = dynamic_cast<const RfMaterial*>(&material)) {
        // View lookup, rhoD; per blended view (3): weight test, rhoV fetch, per lobe: layer index
        // 2, 3-term dot 5, test, select, pow, add; then 3 for the weighted add.
        const int k = rf->lobeCount();
        return cost(kLookupAlu + 3 * (4 + 11 * k), kLookupTex + 1 + 3 * (1 + k),
                    "ALU 33k+33, TEX 3k+6 (k lobes per view)");
    }
    if (const auto* pca = dynamic_cast<const PcaMaterial*>(&material)) {
        // View + light lookups; 3 view-weight tests; per (view, light) pair (9): weight product and
        // test, bias fetch, per component: tile address 4, multiply-add 2 and 2 fetches; weighted
        // add 2.
        const int c = pca->components();
        return cost(2 * kLookupAlu + 3 + 9 * (4 + 6 * c), 2 * kLookupTex + 9 * (1 + 2 * c),
                    "ALU 54c+71, TEX 18c+13 (c components)");
    }
    if (const auto* lpca = dynamic_cast<const LpcaMaterial*>(&material)) {
        // Cluster fetch and decode 2; two lookups; per component: alpha address 2 and fetch,
        // 9 x (weight product, row index 2, multiply-add 2, one fetch), weighted add 2.
        const int c = lpca->components();
        return cost(2 + 2 * kLookupAlu + 49 * c, 1 + 2 * kLookupTex + 10 * c,
                    "ALU 49c+34, TEX 10c+5 (c components)");
    }
    if (const auto* revised = dynamic_cast<const LpcaRevisedMaterial*>(&material)) {
        // Cluster 2; two concentric maps 17 each; grid coordinates 22; per component: row 2, two
        // filtered 3D fetches with their scaling 2, weight address 2 and fetch, mix, multiply-add
        // 2; offset test 1 (+3 and a fetch when the grid is 8-bit).
        const int c = revised->components();
        const bool offset = revised->eightBit();
        return cost(58 + 9 * c + 1 + (offset ? 3 : 0), 1 + 3 * c + (offset ? 1 : 0),
                    offset ? "ALU 9c+72, TEX 3c+2 (c components, 8-bit)"
                           : "ALU 9c+69, TEX 3c+1 (c components)");
    }
    ShaderCost unknown;
    unknown.formula = "not counted";
    return unknown;
}

}  // namespace osgBTF
