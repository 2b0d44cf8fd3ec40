// Revised LPCA's fit (libosgBTFFit): an LPCA fit, its Eigen-BRDFs resampled onto the
// elevated concentric grid.
#include "materials/MethodOptions.h"
#include "materials/lpca-revised/LpcaRevised.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <sstream>

#include <Imath/half.h>
#include <tbb/parallel_for.h>

#include "core/Error.h"
#include "core/Progress.h"
#include "materials/lpca-revised/ConcentricMap.h"

namespace osgBTF {

namespace {
/** GL_MAX_3D_TEXTURE_SIZE guaranteed by GL 3.3 is 256; llvmpipe and desktop GPUs give 2048. */
constexpr int kMax3DTextureSize = 2048;
}  // namespace

// ---- fit: LPCA, then resampling ----------------------------------------------------------------

osg::ref_ptr<LpcaRevisedMaterial> LpcaRevisedMaterial::fit(const BtfSource& btf,
                                                           const FitOptions& options) {
    const OptionValues o = validateOptions(kMethod, options);
    const int resolution = o.integer("resolution");
    const LpcaSettings settings = LpcaSettings::fromValues(o);
    // The 3D texture holds k x n by c x n by n^2 texels: the bound on n depends on k and c.
    const int largest = std::max(settings.clusters, settings.components);
    if (largest * resolution > kMax3DTextureSize)
        throw Error("lpca-revised: option resolution must be at most " +
                    std::to_string(kMax3DTextureSize / largest) +
                    " with clusters=" + std::to_string(settings.clusters) +
                    " components=" + std::to_string(settings.components) +
                    " (k x n and c x n <= " + std::to_string(kMax3DTextureSize) +
                    ", the 3D texture size), got " + std::to_string(resolution));
    osg::ref_ptr<LpcaMaterial> lpca = LpcaMaterial::fit(btf, settings);
    return fromLpca(*lpca, resolution, o.choice("storage") == "unorm8");
}

osg::ref_ptr<LpcaRevisedMaterial> LpcaRevisedMaterial::fromLpca(const LpcaMaterial& lpca,
                                                                int resolution, bool eightBit) {
    const auto start = std::chrono::steady_clock::now();
    osg::ref_ptr<LpcaRevisedMaterial> m = new LpcaRevisedMaterial;
    m->setGeometry(lpca.width(), lpca.height(), lpca.views(), lpca.lights());
    m->fitInfo = lpca.fitInfo;
    m->_clusters = lpca.clusters();
    m->_components = lpca.components();
    m->_resolution = resolution;
    m->_eightBit = eightBit;
    const int n = resolution, K = m->_clusters, c = m->_components;
    const int W = m->gridWidth(), H = m->gridHeight(), D = m->gridDepth();

    // Exact Delaunay weights of every grid direction (texel centres of the parameter square).
    const DirectionInterpolator viewInterpolator(lpca.views()), lightInterpolator(lpca.lights());
    std::vector<InterpolationWeights> viewWeights(std::size_t(n) * n),
        lightWeights(viewWeights.size());
    for (int jt = 0; jt < n; ++jt)
        for (int js = 0; js < n; ++js) {
            const glm::vec3 d(elevatedConcentricMap({(js + 0.5) / n, (jt + 0.5) / n}));
            viewWeights[std::size_t(jt) * n + js] = viewInterpolator.weights(d);
            lightWeights[std::size_t(jt) * n + js] = lightInterpolator.weights(d);
        }
    // Resampled in float here; the material gets the grid at its storage precision below.
    std::vector<float> grid(std::size_t(W) * H * D * 3, 0.0f);
    {
        Progress progress("lpca-revised: resampling", std::size_t(D));
        tbb::parallel_for(0, D, [&](int z) {
            const InterpolationWeights& wl = lightWeights[std::size_t(z)];  // z = t_l * n + s_l
            for (int y = 0; y < H; ++y) {
                const int i = y / n, jtv = y % n;
                for (int x = 0; x < W; ++x) {
                    const int k = x / n, jsv = x % n;
                    const InterpolationWeights& wv = viewWeights[std::size_t(jtv) * n + jsv];
                    double sum[3] = {0, 0, 0};
                    for (int a = 0; a < 3; ++a)
                        for (int b = 0; b < 3; ++b) {
                            const double w = double(wv.weight[a]) * wl.weight[b];
                            if (w == 0) continue;
                            const std::size_t rgb =
                                lpca.eigenBrdfRun(k, i, std::size_t(wv.index[a])) +
                                std::size_t(wl.index[b]) * 3;
                            for (int ch = 0; ch < 3; ++ch)
                                sum[ch] += w * lpca.eigenBrdfs[rgb + std::size_t(ch)];
                        }
                    float* out = grid.data() + ((std::size_t(z) * H + y) * W + x) * 3;
                    for (int ch = 0; ch < 3; ++ch) out[ch] = float(sum[ch]);
                }
            }
            progress.advance();
        });
    }

    // Storage precision, and the 8-bit scales folded into the weights.
    std::vector<double> scale(std::size_t(K) * c, 1.0);
    if (eightBit) {
        std::fill(scale.begin(), scale.end(), 0.0);
        for (std::size_t z = 0; z < std::size_t(D); ++z)
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x)
                    for (int ch = 0; ch < 3; ++ch) {
                        double& s = scale[std::size_t(x / n) * c + std::size_t(y / n)];
                        s = std::max(s, double(std::abs(grid[((z * H + y) * W + x) * 3 + ch])));
                    }
        for (double& s : scale)
            if (!(s > 0)) s = 1.0;
        for (std::size_t z = 0; z < std::size_t(D); ++z)
            for (int y = 0; y < H; ++y)
                for (int x = 0; x < W; ++x)
                    for (int ch = 0; ch < 3; ++ch) {
                        float& v = grid[((z * H + y) * W + x) * 3 + ch];
                        const double s = scale[std::size_t(x / n) * c + std::size_t(y / n)];
                        v = float(std::lround(std::clamp((v / s + 1.0) * 0.5, 0.0, 1.0) * 255.0)) /
                            255.0f;
                    }
    }
    m->grid = StoredValues(eightBit ? MaterialTexture::UNorm8 : MaterialTexture::Half, grid.size());
    m->grid.write(0, grid.data(), grid.size());
    const int perTexel = m->weightsPerTexel();
    m->clusterOf = lpca.clusterOf;
    const std::size_t texels = m->texelCount();
    m->weights = StoredValues(MaterialTexture::Half, lpcaWeightCount(texels, perTexel));
    for (std::size_t t = 0; t < m->texelCount(); ++t) {
        const int k = lpca.clusterOf[t];
        double offset = 0;
        for (int i = 0; i < c; ++i) {
            const double alpha = lpca.weight(t, i);
            const double s = scale[std::size_t(k) * c + i];
            m->weights.set(lpcaWeightIndex(texels, t, i), float(eightBit ? 2 * s * alpha : alpha));
            offset -= s * alpha;
        }
        if (eightBit) m->weights.set(lpcaWeightIndex(texels, t, c), float(offset));
    }
    m->finishSetup();
    std::ostringstream seconds;
    seconds << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    m->fitInfo["resample_seconds"] = seconds.str();
    return m;
}

namespace {
// The fit hook of the method registered in LpcaRevised.cpp (libosgBTF).
const bool lpcaRevisedFitterRegistered = registerFitterClass<LpcaRevisedMaterial>();
}  // namespace

}  // namespace osgBTF
