// osgBTF BSVTF: `btf tiles` — the tile pyramid, weights, coded tiles and U packets of an fmf
// material, written as the folder TileSet.h describes (Schwartz et al. 2013 sections 5-7).
#pragma once

#include <cstdint>
#include <string>

#include "streaming/TileLayout.h"

namespace osgBTF {

class FmfMaterial;
class Material;

struct TileBuildOptions {
    int tileSize = TileLayout::kDefaultTileSize;
    int padding = TileLayout::kDefaultPadding;
    std::string codec = "dct";  ///< dct | raw
    /** JPEG-like quality of the dct codec, 1..100. 98 by default: on the built-in sample's fmf
     *  fit (64 x 64, 8 components, 16-texel tiles) it keeps the rendered SSIM >= 0.99 against
     *  raw tiles at every tested view, the grazing one included (quality 90: 0.94 there), at
     *  4.4:1 (tests/streaming_tiles_test.cpp). Schwartz et al. 2013 report "up to 6:1 with no
     * perceivable artefacts" on larger, smoother materials. */
    int quality = 98;
};

struct TileBuildReport {
    int groups = 0, levels = 0;
    std::size_t tiles = 0;
    std::uint64_t rawTileBytes = 0;     ///< tiles x tileBytes()
    std::uint64_t storedTileBytes = 0;  ///< what the tile files hold
    std::uint64_t uBytes = 0;           ///< all U packets
    std::uint64_t indexBytes = 0;
    /** Largest |decoded - original| over every tile texel (0 for raw). */
    double largestTileError = 0;
    double seconds = 0;
};

/** Writes `material`'s tile set to `folder` (created, or replaced as a whole: the set is built in
 *  "<folder>.tmp<pid>" and published by rename, so a kill leaves the old folder or the new one).
 *  Throws Error "<material source>: ..." for a DFMF material (BSVTF streams FMF: one
 *  factorisation with the colour in U's rows), a mip-mapped one (the pyramid is BSVTF's own),
 *  and invalid options; "<folder>: ..." when it cannot write. Progress under "tiles". */
TileBuildReport buildTileSet(const FmfMaterial& material, const std::string& folder,
                             const TileBuildOptions& options = {});
/** The same for a material of any method: throws Error "<material source>: is a 'M' material;
 *  BSVTF tiles an fmf material" unless it is one. */
TileBuildReport buildTileSet(const Material& material, const std::string& folder,
                             const TileBuildOptions& options = {});

}  // namespace osgBTF
