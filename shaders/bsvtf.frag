#version 330 compatibility
// BSVTF (streaming/StreamedMaterial.h, seed 003 sections 3 and 5): an fmf material whose
// Eigen-Textures are read from the tile cache that every streamed material shares, through the
// material's lookup table. Group g of texel (x, y) lives in the deepest resident tile containing
// finest tile (x / T, y / T): the LUT gives its level l and cache slot; the texel is then
// (x, y) >> (L - l) of that level, at its offset inside the tile (seed 003 eq. 3, with the
// levels of streaming/TileLayout.h). Nearest texels, as fmf.frag: with every finest tile
// resident the render equals the fmf material's.
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

uniform sampler2D bsvtfCache;      // RGBA16F, slots of (T + 2 P)^2 texels side by side
uniform usampler2DArray bsvtfLut;  // layer = group; texel = finest tile: (slot x, slot y, level)
uniform ivec3 bsvtfTile;           // T, P, finest level L

vec4 fmfEigenTexture(ivec2 texel, int group) {
    int T = bsvtfTile.x, P = bsvtfTile.y, L = bsvtfTile.z;
    uvec4 entry = texelFetch(bsvtfLut, ivec3(texel / T, group), 0);
    ivec2 levelTexel = texel >> (L - int(entry.z));
    ivec2 inTile = levelTexel - (levelTexel / T) * T;
    return texelFetch(bsvtfCache, ivec2(entry.xy) * (T + 2 * P) + P + inTile, 0);
}

#pragma include "common/fmf_eval.glsl"
