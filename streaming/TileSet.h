// osgBTF BSVTF: the files of a streamed FMF material (Schwartz et al. 2013 sections 6-7), as `btf
// tiles` writes them and the runtime reads them from a folder or a static HTTP server:
//
//   DIR/index.bsvtf               text: the layout, codec, material parameters, directions, and
//                                 one line per U packet and per tile (bytes, CRC-32, weight, norm)
//   DIR/u/G.half                  U packet of group G: components 4G..4G+3 of every U row
//                                 (views x lights x 3 rows x 4 half floats, little-endian)
//   DIR/tiles/G/L/X_Y.tile        tile (X, Y) of level L of group G: raw halfs or the codec's
//                                 payload (streaming/TileCodec.h), coded against the decoded
//                                 parent so errors never drift down the levels
//
// One file per tile, so any static file server serves them and a reader can check each alone
// (size and CRC from the index: a truncated or corrupted download is detected, not rendered).
// The index lists sizes of what exists; it is written last, inside a folder published by rename,
// so a reader never sees half a set.
#pragma once

#include <cstdint>
#include <map>
#include <string>
#include <vector>

#include <Imath/half.h>
#include <osg/ref_ptr>

#include "core/Directions.h"
#include "streaming/TileCodec.h"
#include "streaming/TileLayout.h"

namespace osgBTF {

class FmfMaterial;

struct TileRecord {
    std::uint32_t bytes = 0, crc = 0;
    /** w(i, l, l-1) of Schwartz et al. 2013 eq. 8: mean over the tile's texels of the squared
     * difference to the upsampled parent, summed over the 4 components (level 0: to zero). */
    float weight = 0.0f;
    /** ||T||_F^2 / T^2: mean squared value, summed over the 4 components (U packet priority). */
    float norm = 0.0f;
};

struct UPacketRecord {
    std::uint32_t bytes = 0, crc = 0;
};

struct TileSetIndex {
    static constexpr int kVersion = 1;
    static constexpr const char* kIndexName = "index.bsvtf";

    TileLayout layout;
    int components = 0;
    /** "dct" (TileCodec) or "raw" (the halfs as they are: tileBytes() per tile). */
    std::string codec = "dct";
    TileCodecSettings codecSettings;
    /** The fmf material's parameters (FittedMaterial::parameters) and directions. */
    std::map<std::string, std::string> parameters;
    DirectionSet views, lights;
    std::vector<UPacketRecord> uPackets;  ///< one per group
    std::vector<TileRecord> tiles;        ///< by layout.index()

    /** Half floats of one U packet: views x lights x 3 x 4. */
    std::size_t uPacketValues() const { return views.size() * lights.size() * 3 * 4; }
    static std::string tilePath(const TileId& tile);
    static std::string uPacketPath(int group);

    std::string serialize() const;
    /** Throws Error "SOURCE: line N: problem" for anything that is not a complete index of this
     *  version: unknown or missing keys, bad numbers, sizes that do not match the layout, a tile
     *  or packet listed twice or missing, no "end" line (a truncated download). */
    static TileSetIndex parse(const std::string& text, const std::string& source);

    /** Checks a downloaded tile against its record and decodes it; `parent` is the decoded parent
     *  tile (nullptr for level 0). Throws Error "SOURCE: ..." for a wrong size, a CRC mismatch
     *  or a payload the codec refuses. */
    std::vector<Imath::half> decodeTile(const TileId& tile, const std::vector<std::uint8_t>& data,
                                        const Imath::half* parent, const std::string& source) const;
    /** Checks and converts a U packet (4 x views x lights x 3 values, as float). */
    std::vector<float> decodeUPacket(int group, const std::vector<std::uint8_t>& data,
                                     const std::string& source) const;

    /** The fmf material of the given Eigen-Textures and U (zeros where a packet is missing):
     *  `sxv` width x height x groups x 4 (as FmfMaterial's sxv texture), `u` as its u texture. */
    osg::ref_ptr<FmfMaterial> material(std::vector<float> u, std::vector<float> sxv,
                                       const std::string& source) const;
};

/** The prediction of `child` from its decoded parent tile: texel (x, y) of level l takes the
 *  parent level's texel (x >> 1, y >> 1) (floor for the negative padding coordinates), which the
 *  padded parent tile always holds. Writes paddedTileSize()^2 x 4 halfs. */
void predictFromParent(const TileLayout& layout, const TileId& child, const Imath::half* parent,
                       Imath::half* out);

/** Reads DIR/index.bsvtf, then every packet and tile, decodes them, and returns the material
 *  with every finest tile: what a cache holding everything renders. Throws Error naming the
 *  file and the problem. */
osg::ref_ptr<FmfMaterial> loadTileSetFinest(const std::string& folder);

/** The CRC-32 (zlib's) the index records for a file's bytes. */
std::uint32_t tileSetCrc(const std::vector<std::uint8_t>& data);
/** Half floats as the files store them (U packets, raw tiles): little-endian, 2 bytes each. */
std::vector<std::uint8_t> halfBytes(const Imath::half* values, std::size_t count);
inline Imath::half halfAt(const std::vector<std::uint8_t>& bytes, std::size_t i) {
    Imath::half h;
    h.setBits(std::uint16_t(bytes[2 * i] | (bytes[2 * i + 1] << 8)));
    return h;
}

/** Reads a whole file; throws Error "PATH: cannot read ..." */
std::vector<std::uint8_t> readFileBytes(const std::string& path);

}  // namespace osgBTF
