// PCA's fit (libosgBTFFit): a truncated SVD per view, Eigen-Textures quantised to the storage,
// weights refitted against the basis as stored.
#include "materials/MethodOptions.h"
#include "materials/pca/Pca.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <numeric>

#include <Imath/half.h>
#include <tbb/parallel_for.h>
#include <tbb/task_arena.h>

#include "core/Error.h"
#include "core/LowRank.h"
#include "core/Progress.h"

namespace osgBTF {

namespace {

/** The storage option's value (validated: one of the option table's choices). */
MaterialTexture::PixelKind storageKind(const std::string& text) {
    if (text == "unorm8") return MaterialTexture::UNorm8;
    return text == "half" ? MaterialTexture::Half : MaterialTexture::Float;
}

/** Stores one Eigen-Texture column (3 * texels values, max |value| = 1) at the storage's precision.
 *  `stored` receives what the file and the GPU hold, `basis` what that means (E = offset + range
 *  * stored per channel), `offset`/`range` the per-channel mapping (0/1 unless unorm8). */
void quantise(const float* e, std::size_t rows, MaterialTexture::PixelKind kind, float* stored,
              float* basis, float offset[3], float range[3]) {
    for (int ch = 0; ch < 3; ++ch) offset[ch] = 0.0f, range[ch] = 1.0f;
    if (kind == MaterialTexture::Float) {
        std::copy(e, e + rows, stored);
        std::copy(e, e + rows, basis);
        return;
    }
    if (kind == MaterialTexture::Half) {
        for (std::size_t i = 0; i < rows; ++i) basis[i] = stored[i] = float(Imath::half(e[i]));
        return;
    }
    for (int ch = 0; ch < 3; ++ch) {
        float lo = 0.0f, hi = 0.0f;
        if (rows >= 3) lo = hi = e[ch];
        for (std::size_t i = std::size_t(ch); i < rows; i += 3) {
            lo = std::min(lo, e[i]);
            hi = std::max(hi, e[i]);
        }
        offset[ch] = lo;
        range[ch] = hi - lo;
    }
    for (std::size_t i = 0; i < rows; ++i) {
        const int ch = int(i % 3);
        // n / 255.0f is exactly what the file loader produces, so save/load stays bit-exact.
        const float n =
            range[ch] > 0.0f
                ? std::clamp(std::round((e[i] - offset[ch]) / range[ch] * 255.0f), 0.0f, 255.0f)
                : 0.0f;
        stored[i] = n / 255.0f;
        basis[i] = offset[ch] + range[ch] * stored[i];
    }
}

}  // namespace

osg::ref_ptr<PcaMaterial> PcaMaterial::fit(const BtfSource& btf, const FitOptions& options) {
    const auto start = std::chrono::steady_clock::now();
    const OptionValues o = validateOptions(kMethod, options);
    if (btf.empty()) throw Error("pca: the BTF is empty");
    const int components = o.integer("components");
    const MaterialTexture::PixelKind storage = storageKind(o.choice("storage"));
    const std::size_t texels = btf.texelCount(), rows = texels * 3, lights = btf.lightCount();
    const std::size_t maxComponents = std::min(lights, rows);
    // The rank of a view's matrix bounds it; that depends on the data, not on the table.
    if (std::size_t(components) > maxComponents)
        throw Error("pca: option components must be at most " + std::to_string(maxComponents) +
                    " for this BTF (its lights, or 3 x texels if fewer), got " +
                    std::to_string(components));

    osg::ref_ptr<PcaMaterial> m = new PcaMaterial;
    m->setShape(btf.width(), btf.height(), btf.views(), btf.lights(), components, storage);
    m->prepareLookups();
    // The model itself can be gigabytes (151 views x 16 components x 160000 texels x RGB for a
    // full-size UBO2014 file): refused before allocating when it cannot fit.
    // 8-bit Eigen-Textures are held as bytes: a quarter of the memory of floats (1.2 GB instead
    // of 4.6 for a full-size UBO2014 file at 16 components).
    const bool bytes = storage == MaterialTexture::UNorm8;
    // Beside it, each worker holds one view's images as floats (rows x lights) and their SVD.
    const std::uint64_t workers = std::min<std::uint64_t>(
        btf.viewCount(), std::uint64_t(std::max(1, tbb::this_task_arena::max_concurrency())));
    checkMemoryBeside(btf,
                      std::uint64_t(m->eigenTextures.valueCount()) * (bytes ? 1 : sizeof(float)) +
                          std::uint64_t(m->weights.valueCount()) * sizeof(float) +
                          workers * std::uint64_t(rows) * lights * sizeof(float),
                      "pca: " + std::to_string(components) + " Eigen-Textures for each of " +
                          std::to_string(btf.viewCount()) + " views");
    if (bytes)
        m->eigenTextures.bytes.assign(m->eigenTextures.valueCount(), 0);
    else
        m->eigenTextures.data.assign(m->eigenTextures.valueCount(), 0.0f);
    m->weights.data.assign(m->weights.valueCount(), 0.0f);

    std::vector<double> totalSquares(btf.viewCount(), 0.0), residualSquares(btf.viewCount(), 0.0);
    Progress progress("pca: fitting " + std::to_string(btf.viewCount()) + " views",
                      btf.viewCount());
    // One view per task: each is an independent (3 * texels) x lights problem, and Eigen's
    // single-threaded kernels inside keep both cores busy without oversubscription.
    tbb::parallel_for(std::size_t(0), btf.viewCount(), [&](std::size_t v) {
        std::vector<float> images(rows * lights);  // column l = image (v, l), texel-major RGB
        btf.readImages(v * lights, lights, images.data());
        const TruncatedSvd svd = truncatedSvd(images.data(), rows, lights, components);
        double sumSquares = 0;
        for (double s : svd.singularValues) sumSquares += s * s;
        totalSquares[v] = sumSquares;
        residualSquares[v] = svd.residualSquared();

        std::vector<float> e(rows), stored(rows), basis(rows * std::size_t(components));
        std::vector<float> offsets(std::size_t(components) * 3), ranges(offsets.size());
        for (int k = 0; k < components; ++k) {
            const float* u = svd.u.data() + std::size_t(k) * rows;
            float maxAbs = 0.0f;
            for (std::size_t i = 0; i < rows; ++i) maxAbs = std::max(maxAbs, std::abs(u[i]));
            // Any scale works (the weights absorb it); max |E| = 1 puts half's and unorm8's
            // precision where the values are.
            const float scale = maxAbs > 0.0f ? 1.0f / maxAbs : 0.0f;
            for (std::size_t i = 0; i < rows; ++i) e[i] = u[i] * scale;
            quantise(e.data(), rows, storage, stored.data(), basis.data() + std::size_t(k) * rows,
                     offsets.data() + k * 3, ranges.data() + k * 3);
            for (std::size_t t = 0; t < texels; ++t) {
                const std::size_t at =
                    m->eigenIndex(v, k, int(t % btf.width()), int(t / btf.width()));
                for (std::size_t ch = 0; ch < 3; ++ch) {
                    const float q = stored[t * 3 + ch];
                    if (bytes)
                        m->eigenTextures.bytes[at + ch] = std::uint8_t(std::lround(q * 255.0f));
                    else
                        m->eigenTextures.data[at + ch] = q;
                }
            }
        }
        // Weights refitted against the basis as stored: for float storage this is the projection
        // onto the top singular vectors (the Eckart-Young optimum); for half and unorm8 it is the
        // best the quantised basis can do.
        const std::vector<float> alpha =
            leastSquares(basis.data(), rows, components, images.data(), int(lights));
        for (std::size_t l = 0; l < lights; ++l) {
            float* out = m->weights.data.data() + m->weightIndex(v, l, 0);
            float* bias = m->weights.data.data() + m->weightIndex(v, l, components);
            for (int k = 0; k < components; ++k) {
                const float a = alpha[l * std::size_t(components) + k];
                for (int ch = 0; ch < 3; ++ch) {
                    out[k * 3 + ch] = a * ranges[k * 3 + ch];
                    bias[ch] += a * offsets[k * 3 + ch];
                }
            }
        }
        progress.advance();
    });
    progress.finish();

    const double total = std::accumulate(totalSquares.begin(), totalSquares.end(), 0.0);
    const double residual = std::accumulate(residualSquares.begin(), residualSquares.end(), 0.0);
    m->fitInfo["seconds"] = std::to_string(
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count());
    m->fitInfo["components"] = std::to_string(components);
    m->fitInfo["storage"] = o.choice("storage");
    // Share of the data's squared norm the rank-c subspaces capture (before quantisation).
    m->fitInfo["energy"] = std::to_string(total > 0 ? 1.0 - residual / total : 1.0);
    return m;
}

namespace {
// The fit hook of the method registered in Pca.cpp (libosgBTF).
const bool pcaFitterRegistered = registerFitterClass<PcaMaterial>();
}  // namespace

}  // namespace osgBTF
