// osgBTF BSVTF (Schwartz et al. 2013 section 6): the transmission codec of one tile of
// Eigen-Textures.
//
// A tile is side x side RGBA half floats (side = T + 2P, 72 for the defaults; a multiple of 8),
// channel-interleaved, rows from the bottom. It is coded as its difference to a prediction (the
// upsampled decoded parent, given by the caller), so only what the parent does not already say is
// sent:
//   - per channel, per 8x8 block: the orthonormal DCT-II of the difference (DC = 8 x block mean).
//     Orthonormal, so quantisation noise keeps its energy through the inverse and the worst case
//     per texel has a closed form (tileCodecErrorBound).
//   - JPEG's quantisation: the step of coefficient (u, v) is max(1, floor((Q50[v][u] scale + 50)
//     / 100)) x unit with the ITU T.81 Annex K.1 luminance table Q50 and scale = 5000 / quality
//     below 50, 200 - 2 quality from 50 (quality 100: every step is `unit`). The unit puts the
//     floating-point data on JPEG's 0..255 scale (the builder passes peak |value| / 255), so
//     quality means what it means for an 8-bit JPEG. Quantised value = lround(coefficient / step),
//     a 32-bit integer (the encoder refuses a tile needing more steps: unit far too small).
//   - serialisation: one version byte (kTileCodecVersion), then a zlib stream (deflate, written
//     with zlib's run-length strategy: within ~5 % of the default's size and several times faster)
//     of the quantised coefficients, per channel, per block (rows of blocks in memory order), each
//     block in JPEG's zigzag order, each a zigzag-signed LEB128 varint: small values take one byte,
//     any 32-bit value at most five, and the high-frequency zero runs become long runs of 0 bytes,
//     which deflate codes in a few bits. Varints must be minimal (the format is canonical).
//   - reconstruction: out = half(prediction + inverse DCT(q x step)), computed in double and
//     rounded once through float to half. encodeTile reconstructs with the same function as
//     decodeTile, so its `decoded` output is what a receiver gets, bit for bit, and the builder
//     can predict children from decoded parents without drift.
// The decoder trusts nothing: the inflated size is bounded (5 bytes per coefficient), exactly
// side*side*4 minimal varints must fill it, and a non-finite result is an error.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Imath/half.h>

namespace osgBTF {

/** The first byte of every payload. */
constexpr std::uint8_t kTileCodecVersion = 1;

struct TileCodecSettings {
    int quality = 90;   ///< 1..100, JPEG's quality scale
    float unit = 1.0f;  ///< the value of one quantisation step at step size 1 (the builder sets
                        ///< it to the material's peak |Eigen-Texture value| / 255, so quality
                        ///< means what JPEG's does on the first Eigen-Texture); finite, > 0
};

/** Codes `tile` (side*side*4 halfs) as the DCT-quantised, deflated difference to `prediction`
 *  (same layout; nullptr = zeros). `decoded`, when not null, receives exactly what decodeTile
 *  will return for the payload (the builder predicts children from decoded parents so errors do
 *  not drift). Throws osgBTF::Error "tile codec: ..." for invalid settings, a side that is not a
 *  positive multiple of 8 up to 8192, non-finite values in the tile or the prediction, a unit so
 *  small that a coefficient needs 2^31 steps or more, or a tile whose decoded values would
 *  overflow the half range. */
std::vector<std::uint8_t> encodeTile(const Imath::half* tile, const Imath::half* prediction,
                                     int side, const TileCodecSettings& settings,
                                     std::vector<Imath::half>* decoded = nullptr);

/** Decodes a payload into `out` (side*side*4 halfs) against `prediction` (nullptr = zeros; the
 *  same prediction and settings as the encoder's). Throws osgBTF::Error "SOURCE: tile payload
 *  ..." naming the problem for a payload that is empty, does not inflate, is truncated, inflates
 *  to too much, has trailing bytes (after the deflate stream or after the last coefficient), has
 *  a wrong version byte, too few coefficients or an overlong varint, or decodes to non-finite
 *  values; "tile codec: ..." for invalid settings or side. Never crashes or reads out of bounds
 *  on arbitrary bytes. After a throw the contents of `out` are unspecified. */
void decodeTile(const std::uint8_t* data, std::size_t size, const Imath::half* prediction, int side,
                const TileCodecSettings& settings, Imath::half* out, const std::string& source);

/** The largest possible |decoded - original| per texel for these settings, from the
 *  quantisation (each coefficient off by at most half its step) through the orthonormal inverse
 *  DCT (the exact worst case over the 64 texel positions of a block), plus half-float rounding
 *  of the result relative to `magnitude` (the largest |value| of the tile; the prediction's, if
 *  larger), plus a margin for the double arithmetic. Throws Error for invalid settings. */
float tileCodecErrorBound(const TileCodecSettings& settings, float magnitude);

/** Building blocks, exposed for the tests. Blocks are row-major, index y*8 + x; coefficients
 *  index v*8 + u (v the vertical frequency). */
namespace tilecodec_detail {
/** Orthonormal 8x8 DCT-II: C(u,v) = a(u) a(v) sum f(x,y) cos((2x+1)u pi/16) cos((2y+1)v pi/16),
 *  a(0) = sqrt(1/8), a(k > 0) = 1/2. */
void forwardDct8x8(const double* block, double* coefficients);
/** Its inverse (DCT-III), the transpose. */
void inverseDct8x8(const double* coefficients, double* block);
/** The quantisation step of coefficient (u, v), in values (multiplied by unit). */
double quantisationStep(const TileCodecSettings& settings, int u, int v);
/** JPEG's zigzag order: the coefficient index v*8 + u of the k-th coded coefficient. */
int zigzagIndex(int k);
}  // namespace tilecodec_detail

}  // namespace osgBTF
