#version 330 compatibility
// BSVTF (streaming/StreamedMaterial.h, Schwartz et al. 2013 sections 3 and 5): an fmf material
// whose Eigen-Textures are read from the tile cache that every streamed material shares, through
// the material's lookup table. Group g of texel (x, y) lives in the deepest resident tile
// containing finest tile (x / T, y / T): the LUT gives its level l and cache slot; the texel is
// then (x, y) >> (L - l) of that level, at its offset inside the tile (Schwartz et al. 2013 eq. 3,
// with the levels of streaming/TileLayout.h). Filtered as fmf.frag (TexelFilter::Parameters: the
// sums are linear in the Eigen-Texture values; tiles without padding take Values): a fragment that
// reads the base texels (btfBilinear) samples the GL_LINEAR cache at its continuous position in
// level l inside that slot. The P texels of padding around every tile hold the level's neighbouring
// texels, wrapped at the level's edge as the material repeats, so the 2 x 2 footprint of a fragment
// whose nearest texel lies in the tile stays inside the slot: tile edges and the material's border
// need nothing more. With every finest tile resident the render equals the fmf material's, filtered
// or not.
//
// Minified, a fragment is filtered trilinearly as GL_LINEAR_MIPMAP_LINEAR with its level of
// detail clamped to the two levels its LUT entry reaches: its tile's deepest resident level d
// and d's parent level (the scheduler keeps every ancestor of a resident tile resident). With
// lod = log2 of finest texels per pixel and s = L - d, the parent's share is lod - s clamped to
// [0, 1]: the fractional lod where the feedback has made d the finer of the two levels the
// footprint falls between, 0 where the wanted level is not resident yet (no level finer than
// d exists to read), 1 where d is finer than the footprint needs (d was resident for another
// view). Magnified fragments and those at their level (lod <= s) read d alone, as before.
// StreamedFmfMaterial::evaluateResidentFiltered is the CPU reference.
#pragma include "common/btf_main.glsl"
#pragma include "common/directions.glsl"

uniform sampler2D bsvtfCache;      // RGBA16F, slots of (T + 2 P)^2 texels side by side
uniform usampler2DArray bsvtfLut;  // layer = group; texel = finest tile: (slot x, slot y, level,
                                   // parent's slot number)
uniform ivec3 bsvtfTile;           // T, P, finest level L

/** GL_LINEAR in the slot at `slot` holding the tile of level L - shift that contains finest
 *  texel `texel`, at the fragment's coordinate in that level. */
vec4 bsvtfSample(ivec2 slot, int shift, ivec2 texel) {
    int T = bsvtfTile.x, P = bsvtfTile.y;
    ivec2 levelTexel = texel >> shift;
    // Cache texel of the tile's first own texel, minus that texel's place in the level.
    ivec2 origin = slot * (T + 2 * P) + P - (levelTexel / T) * T;
    // The base coordinate in level texels (centres at i + 0.5): texel k of level l covers finest
    // texels k 2^(L-l) .. (k + 1) 2^(L-l) - 1, so `texel` (floor of the base coordinate) lies in
    // levelTexel and the footprint reaches one texel into the padding at most.
    vec2 level = fract(btfBilinearCoordinate) * vec2(osgBTF_size) / float(1 << shift);
    return textureLod(bsvtfCache, (vec2(origin) + level) / vec2(textureSize(bsvtfCache, 0)), 0.0);
}

vec4 fmfEigenTexture(ivec2 texel, int group) {
    int T = bsvtfTile.x, P = bsvtfTile.y, L = bsvtfTile.z;
    uvec4 entry = texelFetch(bsvtfLut, ivec3(texel / T, group), 0);
    int shift = L - int(entry.z);
    // Without padding (P = 0) the material takes TexelFilter::Values, with btfBilinear unset,
    // and reads its deepest level alone: nothing to filter from inside a slot.
    if (!btfBilinear) {
        ivec2 levelTexel = texel >> shift;
        ivec2 origin = ivec2(entry.xy) * (T + 2 * P) + P - (levelTexel / T) * T;
        return texelFetch(bsvtfCache, origin + levelTexel, 0);
    }
    vec4 fine = bsvtfSample(ivec2(entry.xy), shift, texel);
    // NaN (no derivative) compares false: the deepest level alone.
    // btfFragmentLod: log2 of finest texels per pixel (the material has no mip levels, so its
    // level 0 is the finest level), taken by btf_main.glsl's main() in uniform control flow.
    float excess = btfFragmentLod - float(shift);
    float coarser = entry.z > 0u && excess > 0.0 ? min(excess, 1.0) : 0.0;
    if (!(coarser > 0.0)) return fine;
    int slotsPerRow = textureSize(bsvtfCache, 0).x / (T + 2 * P);
    ivec2 parentSlot = ivec2(int(entry.w) % slotsPerRow, int(entry.w) / slotsPerRow);
    // The parent tile contains the fragment's level texel of the coarser level: tile i of level
    // l + 1 lies inside tile i / 2 of level l.
    return mix(fine, bsvtfSample(parentSlot, shift + 1, texel), coarser);
}

#pragma include "fmf/fmf_eval.glsl"

