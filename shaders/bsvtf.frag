#version 330 compatibility
// BSVTF (streaming/StreamedMaterial.h, seed 003 sections 3 and 5): an fmf material whose
// Eigen-Textures are read from the tile cache that every streamed material shares, through the
// material's lookup table. Group g of texel (x, y) lives in the deepest resident tile containing
// finest tile (x / T, y / T): the LUT gives its level l and cache slot; the texel is then
// (x, y) >> (L - l) of that level, at its offset inside the tile (seed 003 eq. 3, with the
// levels of streaming/TileLayout.h). Filtered as fmf.frag (TexelFilter::Parameters: the sums
// are linear in the Eigen-Texture values; tiles without padding take Values): a fragment that
// reads the base texels (btfBilinear) samples the GL_LINEAR cache at its continuous position in
// level l inside that slot. The P texels of padding around every tile hold the level's
// neighbouring texels, wrapped at the level's edge as the material repeats, so the 2 x 2
// footprint of a fragment whose nearest texel lies in the tile stays inside the slot: tile edges
// and the material's border need nothing more. With every finest tile resident the render equals
// the fmf material's, filtered or not. A minified fragment is filtered bilinearly at the deepest
// resident level, which the feedback pass makes the finer of the two levels its footprint falls
// between (GL_LINEAR_MIPMAP_NEAREST, rounded toward the finer); no trilinear blend: once a
// tile's children are resident the scheduler evicts it, so the coarser level is gone
// (streaming/README.md, "Filtering").
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

uniform sampler2D bsvtfCache;      // RGBA16F, slots of (T + 2 P)^2 texels side by side
uniform usampler2DArray bsvtfLut;  // layer = group; texel = finest tile: (slot x, slot y, level)
uniform ivec3 bsvtfTile;           // T, P, finest level L

vec4 fmfEigenTexture(ivec2 texel, int group) {
    int T = bsvtfTile.x, P = bsvtfTile.y, L = bsvtfTile.z;
    uvec4 entry = texelFetch(bsvtfLut, ivec3(texel / T, group), 0);
    int shift = L - int(entry.z);
    ivec2 levelTexel = texel >> shift;
    // Cache texel of the tile's first own texel, minus that texel's place in the level.
    ivec2 origin = ivec2(entry.xy) * (T + 2 * P) + P - (levelTexel / T) * T;
    // Without padding (P = 0) the material takes TexelFilter::Values, with btfBilinear unset.
    if (!btfBilinear) return texelFetch(bsvtfCache, origin + levelTexel, 0);
    // The base coordinate in level texels (centres at i + 0.5): texel k of level l covers finest
    // texels k 2^(L-l) .. (k + 1) 2^(L-l) - 1, so `texel` (floor of the base coordinate) lies in
    // levelTexel and the footprint reaches one texel into the padding at most.
    vec2 level = fract(btfBilinearCoordinate) * vec2(osgBTF_size) / float(1 << shift);
    return textureLod(bsvtfCache, (vec2(origin) + level) / vec2(textureSize(bsvtfCache, 0)), 0.0);
}

#pragma include "common/fmf_eval.glsl"
