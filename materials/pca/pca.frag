#version 330 compatibility
// Method "pca" (materials/pca/Pca.h): per-view Eigen-Textures, Meseth et al. 2003 eq. 6. The same
// loops as PcaMaterial::evaluate/combination on the CPU, so both agree to float rounding.
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

// Layer = measured view; component k is tile (k % pcaTileColumns, k / pcaTileColumns) of the layer.
uniform sampler2DArray pcaEigenTextures;
// Layer = measured view, texel (k, light): RGB weight of component k; k = pcaComponents: the bias
// (unorm8 offsets folded into the weights).
uniform sampler2DArray pcaWeights;
uniform sampler2D pcaViewTable;   // exact view interpolation (common/directions.glsl)
uniform sampler2D pcaLightTable;
uniform int pcaComponents;
uniform int pcaTileColumns;

// Filtered (btfBilinear): the value is linear in the Eigen-Textures (unorm8 with the offsets
// folded into the weights, or half or float), so blending each component's four texels blends the
// texels' values. Blended here rather than by GL's filter: the components are tiles of one
// layer, and the filter would blend across a tile's edge instead of wrapping within the tile. Four
// fetches per component instead of one. The four texels and weights, set by btfEvaluate:
ivec2 pcaCorner0, pcaCorner1;
vec2 pcaBlend;

vec3 pcaEigen(ivec2 tile, ivec2 texel, int view) {
    if (!btfBilinear) return texelFetch(pcaEigenTextures, ivec3(tile + texel, view), 0).rgb;
    vec3 e00 = texelFetch(pcaEigenTextures, ivec3(tile + pcaCorner0, view), 0).rgb;
    vec3 e10 = texelFetch(pcaEigenTextures, ivec3(tile + ivec2(pcaCorner1.x, pcaCorner0.y), view),
                          0).rgb;
    vec3 e01 = texelFetch(pcaEigenTextures, ivec3(tile + ivec2(pcaCorner0.x, pcaCorner1.y), view),
                          0).rgb;
    vec3 e11 = texelFetch(pcaEigenTextures, ivec3(tile + pcaCorner1, view), 0).rgb;
    vec3 bottom = (1.0 - pcaBlend.x) * e00 + pcaBlend.x * e10;
    vec3 top = (1.0 - pcaBlend.x) * e01 + pcaBlend.x * e11;
    return (1.0 - pcaBlend.y) * bottom + pcaBlend.y * top;
}

vec3 pcaCombination(ivec2 texel, int view, int light) {
    vec3 sum = texelFetch(pcaWeights, ivec3(pcaComponents, light, view), 0).rgb;
    for (int k = 0; k < pcaComponents; ++k) {
        ivec2 tile = ivec2(k % pcaTileColumns, k / pcaTileColumns) * osgBTF_size;
        sum += texelFetch(pcaWeights, ivec3(k, light, view), 0).rgb * pcaEigen(tile, texel, view);
    }
    return sum;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
    if (btfBilinear) {
        // GL's bilinear filter with GL_REPEAT (Material::evaluateFiltered).
        vec2 size = vec2(osgBTF_size);
        vec2 s = btfBilinearCoordinate * size - 0.5;
        vec2 first = floor(s);
        pcaBlend = s - first;
        pcaCorner0 = ivec2(mod(first, size));
        pcaCorner1 = (pcaCorner0 + ivec2(1)) % osgBTF_size;
    }
    ivec3 vi, li;
    vec3 vw, lw;
    btfLookupDirections(pcaViewTable, view, vi, vw);
    btfLookupDirections(pcaLightTable, light, li, lw);
    vec3 sum = vec3(0.0);
    for (int i = 0; i < 3; ++i) {
        if (!(vw[i] > 0.0)) continue;
        for (int j = 0; j < 3; ++j) {
            float w = vw[i] * lw[j];
            if (!(w > 0.0)) continue;
            sum += w * pcaCombination(texel, vi[i], li[j]);
        }
    }
    return sum;
}
