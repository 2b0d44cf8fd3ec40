#include "core/FactoredBtf.h"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <sstream>

#include <Imath/half.h>
#include <tbb/blocked_range.h>
#include <tbb/enumerable_thread_specific.h>
#include <tbb/parallel_for.h>
#include <tbb/partitioner.h>

#include "core/Error.h"
#include "core/Progress.h"

namespace osgBTF {

void scalarsToFloats(const unsigned char* src, std::uint64_t count, int scalarSize, float* out) {
    if (scalarSize == 2) {
        for (std::uint64_t k = 0; k < count; ++k) {
            std::uint16_t bits;
            std::memcpy(&bits, src + 2 * k, 2);
            out[k] = imath_half_to_float(bits);
        }
    } else if (scalarSize == 4) {
        std::memcpy(out, src, count * 4);
    } else {
        for (std::uint64_t k = 0; k < count; ++k) {
            double d;
            std::memcpy(&d, src + 8 * k, 8);
            out[k] = float(d);
        }
    }
}

int FactoredBtf::components(int channel) const {
    if (factors.empty()) return 0;
    const BtfFactor& f = model == FactorModel::Fmf ? factors[0] : factors[std::size_t(channel)];
    return int(f.U.cols());
}

void FactoredBtf::checkColorModel(const std::string& source, int model) {
    switch (model) {
        case 0:
        case 1:
        case 3:
        case 4:
        case 11:
            return;
        default:
            fail(source, "DFMF colour model " + std::to_string(model) +
                             " is not supported (supported: 0 RGB, 1 YUV, 3 PCA, 4 YCoCg, "
                             "11 exp-YUV)");
    }
}

void FactoredBtf::validate(bool texelFactorsElsewhere) const {
    const bool fmf = model == FactorModel::Fmf;
    const std::size_t images = imageCount(), texels = texelCount();
    if (factors.size() != (fmf ? 1u : 3u) || images == 0 || texels == 0)
        fail(source, "inconsistent factors: " + std::to_string(factors.size()) + " factor sets (" +
                         (fmf ? "FMF needs 1" : "DFMF needs 3") + ") for " +
                         std::to_string(images) + " images of " + std::to_string(texels) +
                         " texels");
    for (const BtfFactor& factor : factors)
        if (std::size_t(factor.U.rows()) != images * (fmf ? 3 : 1) ||
            std::size_t(factor.SxV.rows()) != (texelFactorsElsewhere ? 0 : texels) ||
            factor.U.cols() != factor.SxV.cols())
            fail(source,
                 "inconsistent factor matrix sizes: U is " + std::to_string(factor.U.rows()) + "x" +
                     std::to_string(factor.U.cols()) + ", SxV " +
                     std::to_string(factor.SxV.rows()) + "x" + std::to_string(factor.SxV.cols()));
    if (!fmf) checkColorModel(source, colorModel);
}

void FactoredBtf::decodeColor(const float v[3], float rgb[3]) const {
    if (model == FactorModel::Fmf) {
        for (int c = 0; c < 3; ++c) rgb[c] = drr() ? std::exp(v[c]) - eps : v[c];
        return;
    }
    auto yuv = [&](float y, float u, float w) {
        rgb[0] = y + 1.13983f * w;
        rgb[1] = y - 0.39465f * u - 0.5806f * w;
        rgb[2] = y + 2.03211f * u;
    };
    switch (colorModel) {
        case 1:
            yuv(v[0], v[1], v[2]);
            break;
        case 3:
            for (int j = 0; j < 3; ++j)
                rgb[j] = v[0] * colorMatrix[0 * 3 + j] + v[1] * colorMatrix[1 * 3 + j] +
                         v[2] * colorMatrix[2 * 3 + j] + colorMean[j];
            break;
        case 4:
            rgb[0] = v[0] + v[1] - v[2];
            rgb[1] = v[0] + v[2];
            rgb[2] = v[0] - v[1] - v[2];
            break;
        case 11: {
            // exp-YUV: Y is stored as log(Y + eps), U and V as chroma divided by (Y + eps).
            const float y = std::exp(v[0]) - eps;
            yuv(y, v[1] * (y + eps), v[2] * (y + eps));
            break;
        }
        default:
            rgb[0] = v[0];
            rgb[1] = v[1];
            rgb[2] = v[2];
    }
}

glm::vec3 FactoredBtf::value(std::size_t view, std::size_t light, int x, int y) const {
    const std::size_t image = view * lights.size() + light, row = factorRow(x, y);
    float sums[3];
    for (int c = 0; c < 3; ++c) {
        const BtfFactor& f = model == FactorModel::Fmf ? factors[0] : factors[std::size_t(c)];
        const std::size_t uRow = model == FactorModel::Fmf ? image * 3 + std::size_t(c) : image;
        sums[c] = f.U.row(Eigen::Index(uRow)).dot(f.SxV.row(Eigen::Index(row)));
    }
    float rgb[3];
    decodeColor(sums, rgb);
    const float scale = cosineScale(lights.vector(light).z);
    return glm::vec3(rgb[0], rgb[1], rgb[2]) * scale;
}

void FactoredBtf::decodeImages(std::size_t first, std::size_t count, float* out) const {
    const std::size_t texels = texelCount(), nL = lights.size();
    const bool fmf = model == FactorModel::Fmf;
    Eigen::MatrixXf products[3];
    const Eigen::Index f0 = Eigen::Index(first), n = Eigen::Index(count);
    // products[c](texel, j) = channel c of image first + j, texel in file order.
    if (fmf) {
        products[0].noalias() = factors[0].SxV * factors[0].U.middleRows(f0 * 3, n * 3).transpose();
    } else {
        for (int c = 0; c < 3; ++c)
            products[c].noalias() = factors[std::size_t(c)].SxV *
                                    factors[std::size_t(c)].U.middleRows(f0, n).transpose();
    }
    const int W = width, H = height;
    for (Eigen::Index j = 0; j < n; ++j) {
        const std::size_t light = (first + std::size_t(j)) % nL;
        const float scale = cosineScale(lights.vector(light).z);
        const float* col[3];
        for (int c = 0; c < 3; ++c)
            col[c] = fmf ? products[0].col(j * 3 + c).data() : products[c].col(j).data();
        float* image = out + std::size_t(j) * texels * 3;
        for (int y = 0; y < H; ++y) {
            // File row 0 is the top image row; osgBTF rows count from the bottom.
            float* dst = image + std::size_t(H - 1 - y) * std::size_t(W) * 3;
            const std::size_t row = std::size_t(y) * std::size_t(W);
            for (int x = 0; x < W; ++x, dst += 3) {
                const float v[3] = {col[0][row + x], col[1][row + x], col[2][row + x]};
                decodeColor(v, dst);
                dst[0] *= scale;
                dst[1] *= scale;
                dst[2] *= scale;
            }
        }
    }
}

void FactoredBtf::decodeAbrdfs(const std::vector<std::size_t>& texels, float* out) const {
    decodeAbrdfs(texels.data(), texels.size(), out);
}

void FactoredBtf::decodeAbrdfs(const std::size_t* texels, std::size_t count, float* out) const {
    const std::size_t images = imageCount(), nL = lights.size();
    const bool fmf = model == FactorModel::Fmf;
    const Eigen::Index n = Eigen::Index(count);
    std::vector<float> scales(nL);
    for (std::size_t l = 0; l < nL; ++l) scales[l] = cosineScale(lights.vector(l).z);
    Eigen::MatrixXf products[3];
    for (std::size_t f = 0; f < factors.size(); ++f) {
        const BtfFactor& factor = factors[f];
        FactorMatrix rows(n, factor.SxV.cols());
        for (Eigen::Index t = 0; t < n; ++t) {
            const std::size_t texel = texels[t];
            const int x = int(texel % std::size_t(width)), y = int(texel / std::size_t(width));
            rows.row(t) = factor.SxV.row(Eigen::Index(factorRow(x, y)));
        }
        // products[f](u row, t): one column per texel, the ABRDF along the rows.
        products[f].noalias() = factor.U * rows.transpose();
    }
    for (Eigen::Index t = 0; t < n; ++t) {
        float* abrdf = out + std::size_t(t) * images * 3;
        for (std::size_t i = 0; i < images; ++i) {
            float v[3];
            for (int c = 0; c < 3; ++c)
                v[c] = fmf ? products[0](Eigen::Index(i * 3 + std::size_t(c)), t)
                           : products[c](Eigen::Index(i), t);
            float* dst = abrdf + i * 3;
            decodeColor(v, dst);
            const float scale = scales[i % nL];
            dst[0] *= scale;
            dst[1] *= scale;
            dst[2] *= scale;
        }
    }
}

MeasuredBtf FactoredBtf::decode(Storage storage, const std::string& progressLabel) const {
    validate();
    const std::size_t images = imageCount(), texels = texelCount();
    std::ostringstream what;
    what << source << ": BTF of " << width << "x" << height << " texels x " << views.size()
         << " views x " << lights.size() << " lights";
    checkMemory(MeasuredBtf::bytesNeeded(width, height, views.size(), lights.size(), storage),
                what.str());
    MeasuredBtf btf(width, height, views, lights, storage);
    btf.source = source;

    // Images in blocks so each product is a matrix-matrix multiply of moderate size.
    const std::size_t block =
        std::clamp<std::size_t>((std::size_t(8) << 20) / (texels * 3 * sizeof(float) + 1), 1, 64);
    tbb::enumerable_thread_specific<std::vector<float>> scratches;
    Progress progress(progressLabel.empty() ? "decoding " + source : progressLabel, images);
    const std::size_t nL = lights.size();
    tbb::parallel_for(
        tbb::blocked_range<std::size_t>(0, images, block),
        [&](const tbb::blocked_range<std::size_t>& range) {
            std::vector<float>& decoded = scratches.local();
            decoded.resize(range.size() * texels * 3);
            decodeImages(range.begin(), range.size(), decoded.data());
            for (std::size_t j = 0; j < range.size(); ++j) {
                const std::size_t image = range.begin() + j;
                btf.setImage(image / nL, image % nL, decoded.data() + j * texels * 3);
            }
            progress.advance(range.size());
        },
        // The default partitioner hands out ranges far above the grain, and the
        // scratch above grows with the range: keep each block at `block` images.
        tbb::simple_partitioner());
    progress.finish();
    return btf;
}

std::uint64_t FactoredBtf::factorBytes() const {
    std::uint64_t values = 0;
    for (const BtfFactor& f : factors)
        values +=
            std::uint64_t(f.U.size()) + std::uint64_t(f.SxV.size()) + std::uint64_t(f.S.size());
    return values * sizeof(float);
}

std::uint64_t FactoredBtf::decodedBytes() const {
    return std::uint64_t(texelCount()) * imageCount() * 3 * sizeof(float);
}

FactoredBtfSource::FactoredBtfSource(const FactoredBtf& factors)
    : BtfSource(factors.width, factors.height, factors.views, factors.lights), _factors(factors) {
    source = factors.source;
    factors.validate();
}

FactoredBtfSource::FactoredBtfSource(std::shared_ptr<const FactoredBtf> factors)
    : FactoredBtfSource(*factors) {
    _owned = std::move(factors);
}

void FactoredBtfSource::readImages(std::size_t first, std::size_t count, float* out) const {
    _factors.decodeImages(first, count, out);
}

void FactoredBtfSource::readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const {
    _factors.decodeAbrdfs(texels, count, out);
}

// Blocks sized so that one decoded block (the GEMM's product) stays near 16 MiB: large enough
// for the GEMM to run at full speed, small enough for one block per worker thread.
std::size_t FactoredBtfSource::abrdfBlockTexels() const {
    const std::size_t perTexel = imageCount() * 3 * sizeof(float);
    return std::clamp<std::size_t>((std::size_t(16) << 20) / std::max<std::size_t>(perTexel, 1), 8,
                                   1024);
}

std::size_t FactoredBtfSource::imageBlock() const {
    const std::size_t perImage = texelCount() * 3 * sizeof(float);
    return std::clamp<std::size_t>((std::size_t(16) << 20) / std::max<std::size_t>(perImage, 1), 1,
                                   256);
}

}  // namespace osgBTF
