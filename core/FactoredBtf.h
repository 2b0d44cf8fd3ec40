// osgBTF: a BTF kept as low-rank factors, B = U * SxV^T (Schwartz et al. 2013 section 3: FMF; the
// UBO2014
// ".btf" files store exactly this, formats.md section 2).
//
// The ABRDF matrix has one row per (view, light[, channel]) and one column per texel. U holds the
// Eigen-ABRDFs (rows), SxV the Eigen-Textures with the singular values folded in (one row per
// texel). Two layouts exist, both as the Bonn files define them:
//   Dfmf: one factorisation per colour channel of a decorrelating colour model (per-channel ranks
//         may differ); U row = view * lights + light.
//   Fmf:  one factorisation with the colour interleaved in U's rows: (view * lights + light) * 3 +
//   c,
//         optionally of log(rgb + eps) ("dynamic-range reduction").
// Decoding a value: the factor sums first, then the colour model (Dfmf) or exp (Fmf with DRR), then
// the division by cos(theta_light) when the data include it. A full-size file is 22 GB decoded and
// ~100 MB factored, so everything here works on blocks of images or texels and never needs the
// decoded whole (decode() is for sizes that fit).
#pragma once

#include <array>
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Eigen/Core>
#include <glm/vec3.hpp>

#include "core/BtfSource.h"
#include "core/Directions.h"
#include "core/MeasuredBtf.h"

namespace osgBTF {

enum class FactorModel {
    Dfmf,  ///< one factorisation per (decorrelated) colour channel (3 factors)
    Fmf,   ///< one factorisation, colour interleaved in U's rows (1 factor)
};

/** Row-major so factor rows load straight from the files' row-major storage. */
using FactorMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/** One factorisation B = U * SxV^T with the singular values S already folded into SxV. */
struct BtfFactor {
    Eigen::VectorXf S;  ///< singular values as stored (not needed for decoding)
    FactorMatrix U;     ///< Dfmf: views*lights rows; Fmf: views*lights*3 rows
    FactorMatrix SxV;   ///< width*height rows, texel y*width+x with row 0 = the TOP image row
};

struct FactoredBtf {
    FactorModel model = FactorModel::Dfmf;
    std::string source;  ///< file name or description, used in messages

    DirectionSet views, lights;  ///< the row order of U: view-major
    int width = 0, height = 0;
    bool cosine = false;  ///< values include cos(theta_light); decoding divides it out

    // Dfmf only: btflib's colour models 0 RGB, 1 YUV, 3 PCA, 4 YCoCg, 11 exp-YUV.
    int colorModel = 0;
    std::array<float, 3> colorMean{};
    std::array<float, 9>
        colorMatrix{};  ///< row-major 3x3 (PCA: rgb_j = sum_i v_i M[i][j] + mean_j)

    // Fmf only.
    std::uint32_t dynamicRangeReduction = 0;  ///< non-zero: stored values are log(rgb + eps)
    float eps = 1e-5f;                        ///< not stored in the files (formats.md 2.7)

    /** Dfmf: one factor per channel (3); Fmf: exactly one. */
    std::vector<BtfFactor> factors;

    bool drr() const { return model == FactorModel::Fmf && dynamicRangeReduction != 0; }
    std::size_t texelCount() const { return std::size_t(width) * std::size_t(height); }
    std::size_t imageCount() const { return views.size() * lights.size(); }
    /** Components of channel c's factor (Fmf: the one factor's for every c). */
    int components(int channel) const;

    /** Throws Error "<source>: ..." when the factor count, the matrix sizes or the colour model
     *  do not fit the layout. texelFactorsElsewhere: the SxV matrices have 0 rows (read into a
     *  TexelFactorSink), only their columns are checked. */
    void validate(bool texelFactorsElsewhere = false) const;
    /** Throws Error "<source>: DFMF colour model N is not supported (...)". */
    static void checkColorModel(const std::string& source, int model);

    /** Colour model (Dfmf) or exp (Fmf with DRR) of the three factor sums, as btflib orders them.
     */
    void decodeColor(const float sums[3], float rgb[3]) const;
    /** The factor of the cosine division for a light of local z = cos(theta): 1 / z when the data
     *  include the cosine and z > 1e-3 (where the division is meaningful), else 1. */
    float cosineScale(float lightZ) const {
        return cosine && lightZ > 1e-3f ? 1.0f / lightZ : 1.0f;
    }
    /** SxV row of texel (x, y), y counted from the bottom as everywhere in osgBTF. */
    std::size_t factorRow(int x, int y) const {
        return std::size_t(height - 1 - y) * std::size_t(width) + std::size_t(x);
    }

    /** Decoded RGB of one texel (y from the bottom) at measured view and light. */
    glm::vec3 value(std::size_t view, std::size_t light, int x, int y) const;
    /** Decodes images [first, first + count) (image = view * lights + light) into `out`:
     *  count * texels * 3 floats, each image as MeasuredBtf::image (rows bottom-up). */
    void decodeImages(std::size_t first, std::size_t count, float* out) const;
    /** Decodes the ABRDFs of the given texels (MeasuredBtf texel indices, y from the bottom) into
     *  `out`: texels.size() * views * lights * 3 floats, each as MeasuredBtf::abrdf. */
    void decodeAbrdfs(const std::vector<std::size_t>& texels, float* out) const;
    void decodeAbrdfs(const std::size_t* texels, std::size_t count, float* out) const;
    /** Everything, decoded into a MeasuredBtf after checking memoryLimit(); in parallel blocks with
     *  progress under `progressLabel`. */
    MeasuredBtf decode(Storage storage = Storage::Float,
                       const std::string& progressLabel = "") const;

    /** Bytes of the factors as floats (U, SxV and S), and of the decoded data as floats. */
    std::uint64_t factorBytes() const;
    std::uint64_t decodedBytes() const;
};

/** A FactoredBtf as input of a fit: every read decodes its block with one GEMM per factor, so the
 *  decoded whole never exists. Throws Error (FactoredBtf::validate) for inconsistent factors. */
class FactoredBtfSource : public BtfSource {
public:
    /** Refers to `factors`, which must outlive this source. */
    explicit FactoredBtfSource(const FactoredBtf& factors);
    /** Owns the factors (e.g. those of a file it was opened from). */
    explicit FactoredBtfSource(std::shared_ptr<const FactoredBtf> factors);

    void readImages(std::size_t first, std::size_t count, float* out) const override;
    void readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const override;
    std::size_t abrdfBlockTexels() const override;
    std::size_t imageBlock() const override;
    bool inMemory() const override { return false; }
    std::uint64_t residentBytes() const override { return _factors.factorBytes(); }

    const FactoredBtf& factors() const { return _factors; }

private:
    std::shared_ptr<const FactoredBtf> _owned;
    const FactoredBtf& _factors;
};

/** `count` scalars of `scalarSize` bytes (2 half, 4 float, 8 double; little-endian, as UBO2014
 *  files store them) at `src` as floats in `out`: the switch outside the loop, a full-size file
 *  has 56 million of them. */
void scalarsToFloats(const unsigned char* src, std::uint64_t count, int scalarSize, float* out);

/** Takes a factorisation's texel factors (SxV) from a reader as it reads them, chunk by chunk and
 *  in the file's own bytes, so that a material keeping them in a layout of its own (fmf's texture
 *  of halves) never holds the reader's float matrices beside it: a full-size UBO2014 file's SxV
 *  is 192 MB as floats and 96 MB as the halves it stores. readUbo2014 with
 *  LoadOptions::texelFactors; the factors it returns have SxV matrices of 0 rows. */
class TexelFactorSink {
public:
    virtual ~TexelFactorSink() = default;
    /** Before factor `factor`'s rows: `described` has the header (size, directions, model and the
     *  factors read so far), the factor keeps `components` values per texel, stored as scalars of
     *  `scalarSize` bytes (2 half, 4 float, 8 double). */
    virtual void beginFactor(const FactoredBtf& described, int factor, int components,
                             int scalarSize) = 0;
    /** Rows [first, first + count) of the factor in file order (FactoredBtf::factorRow): row r's
     *  `components` scalars at bytes + r * rowBytes, little-endian. Throws Error to stop the
     *  read. */
    virtual void texelRows(int factor, int components, std::uint64_t first, std::uint64_t count,
                           const unsigned char* bytes, std::uint64_t rowBytes, int scalarSize) = 0;
};

}  // namespace osgBTF
