#version 330 compatibility
// Method "fmf" (materials/fmf/Fmf.h): B = U * SxV^T (Schwartz et al. 2013 section 3), evaluated by
// fmf/fmf_eval.glsl (this folder) with the Eigen-Textures in one texture array.
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

// Layer = group of 4 components (dfmf: channel c's groups start at fmfLayerOffset[c]).
uniform sampler2DArray fmfSxV;

// Filtered (btfBilinear): the sums are linear in SxV (half or float, filtered as the floats they
// are), so filtering it blends the texels' sums; fmf_eval.glsl decodes the blend
// (FmfMaterial::finishLinear). U, a per-direction table, is still fetched unfiltered.
vec4 fmfEigenTexture(ivec2 texel, int layer) {
    return btfBilinear ? textureLod(fmfSxV, vec3(btfBilinearCoordinate, float(layer)), 0.0)
                       : texelFetch(fmfSxV, ivec3(texel, layer), 0);
}

#pragma include "fmf/fmf_eval.glsl"
