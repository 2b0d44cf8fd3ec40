// osgBTF: reader for UBO2014 ".btf" files (DFMF and FMF factorised BTFs, formats.md section 2).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include <Eigen/Core>

#include "core/MeasuredBtf.h"
#include "loaders/LoadOptions.h"

namespace osgBTF {

enum class Ubo2014Format {
    Dfmf,  ///< "!DFMF08FC[R]": one factorisation per (decorrelated) colour channel
    Fmf,   ///< "!FMF12FCE[R]" / "!FMF06FC[R]": one factorisation, colour interleaved in U's rows
};

/** Row-major so factor rows load straight from the file's row-major storage. */
using FactorMatrix = Eigen::Matrix<float, Eigen::Dynamic, Eigen::Dynamic, Eigen::RowMajor>;

/** One factorisation B = U * SxV^T with the singular values S already folded into SxV. */
struct Ubo2014Factor {
    Eigen::VectorXf S;  ///< singular values as stored (not needed for decoding)
    FactorMatrix U;     ///< DFMF: nL*nV rows; FMF: nL*nV*3 rows (row (view*nL+light)*3 + c)
    FactorMatrix SxV;   ///< width*height rows, texel y*width+x, file row 0 = top image row
};

/** Everything a UBO2014 file holds, kept factorised (an FMF renderer can use it directly). */
struct Ubo2014Factors {
    Ubo2014Format format = Ubo2014Format::Dfmf;
    std::string signature;      ///< as read, e.g. "!DFMF08FCR"; the writer derives its own
    bool hasRotations = false;  ///< the trailing 'R' of the signature
    std::string source;         ///< file name, used in messages of decodeUbo2014

    std::uint32_t metaVersion = 4;  ///< 1..4; decides which optional meta fields exist
    std::string measurementSetup, imageSensor, lightSource;
    float ppmm = 0.0f;
    std::array<float, 3> rgbScale{1.0f, 1.0f, 1.0f};  ///< stored, never applied (as btflib)
    bool cosine = false;  ///< data include cos(theta_light); decoding divides it out
    std::string xml;
    std::vector<std::string> channelNames{"R", "G", "B"};

    DirectionSet views, lights;  ///< degrees, phi in [0, 360), the file's order
    int width = 0, height = 0;
    std::vector<std::array<float, 9>> rotations;  ///< only with hasRotations; unused for decoding

    int scalarSize = 4;  ///< bytes per stored scalar (2 = half, 4 = float, 8 = double)

    // DFMF only.
    std::uint32_t maxComponents = 0;
    int colorModel = 0;  ///< btflib numbering: 0 RGB, 1 YUV, 3 PCA, 4 YCoCg, 11 exp-YUV
    std::array<float, 3> colorMean{};
    std::array<float, 9>
        colorMatrix{};  ///< row-major 3x3 (PCA: rgb_j = sum_i v_i M[i][j] + mean_j)

    // FMF only.
    bool extendedHeader = true;  ///< "!FMF12FCE" (header version byte present) vs "!FMF06FC"
    int headerVersion = 0;       ///< 0..2
    std::uint32_t dynamicRangeReduction = 0;  ///< non-zero: stored values are log(rgb + eps)
    float eps = 1e-5f;                        ///< not in the file (formats.md 2.7)
    int heightMapWidth = 0, heightMapHeight = 0;
    std::vector<float> heightMap;  ///< rows of heightMapWidth values, file order

    /** DFMF: one factor per channel (3); FMF: exactly one. */
    std::vector<Ubo2014Factor> factors;

    bool drr() const { return format == Ubo2014Format::Fmf && dynamicRangeReduction != 0; }
};

/** Reads and validates a .btf file completely (every byte accounted for). Refuses PVF, BDI,
 *  unknown signatures, unsupported colour models and channel counts other than 3, and checks
 *  memoryLimit() and the file size before every large allocation. */
Ubo2014Factors readUbo2014(const std::string& path, const LoadOptions& options = {});

/** Reconstructs every value (colour model, then dynamic-range reduction, then cosine division,
 *  as btflib) into a MeasuredBtf with bottom-up rows. */
MeasuredBtf decodeUbo2014(const Ubo2014Factors& factors, const LoadOptions& options = {});

/** readUbo2014 + decodeUbo2014. */
MeasuredBtf loadUbo2014(const std::string& path, const LoadOptions& options = {});

/** Writes factors as a .btf file (meta version factors.metaVersion, scalars of
 *  factors.scalarSize). Meant for synthetic files in tests and benchmarks; the file appears
 *  atomically (path + ".tmp", then renamed). */
void writeUbo2014(const Ubo2014Factors& factors, const std::string& path);

}  // namespace osgBTF
