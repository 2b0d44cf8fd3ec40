#version 330 compatibility
// Method "pca" (materials/pca/Pca.h): per-view Eigen-Textures, seed 001 eq. 6. The same loops as
// PcaMaterial::evaluate/combination on the CPU, so both agree to float rounding.
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

vec3 pcaCombination(ivec2 texel, int view, int light) {
    vec3 sum = texelFetch(pcaWeights, ivec3(pcaComponents, light, view), 0).rgb;
    for (int k = 0; k < pcaComponents; ++k) {
        ivec2 tile = ivec2(k % pcaTileColumns, k / pcaTileColumns) * osgBTF_size;
        sum += texelFetch(pcaWeights, ivec3(k, light, view), 0).rgb *
               texelFetch(pcaEigenTextures, ivec3(tile + texel, view), 0).rgb;
    }
    return sum;
}

vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) {
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
