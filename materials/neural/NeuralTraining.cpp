// The neural method's training with libtorch, in a module of its own (libosgBTFNeuralTraining.so,
// next to libosgBTFFit) that NeuralFit.cpp loads on the first neural fit: libtorch's libraries
// take 0.4 s to load (0.9 s under AddressSanitizer), which every program linking libosgBTFFit,
// the btf tool's every start included, would otherwise pay. Latents and decoder are trained
// together (Adam), reading the measured values block by block, so memory stays bounded whatever
// the BTF's size.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <thread>

#include <Imath/half.h>
#include <tbb/parallel_for.h>
#include <torch/torch.h>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "core/MipPyramid.h"
#include "core/Progress.h"
#include "materials/neural/Neural.h"

namespace osgBTF {

namespace {

/** Measured values held at once, one block of texels' ABRDFs: at most this, and an eighth of the
 *  memory limit. */
constexpr std::uint64_t kBlockBytes = 256ull << 20;
/** Adam steps on one block before the next is read, when the BTF needs several blocks; fewer when
 *  the steps would not reach every block that way (a full-size UBO2014 file has 164 blocks). */
constexpr int kStepsPerBlock = 25;
/** Learning rates: latents move faster than the shared decoder, which every sample pulls on. */
constexpr double kLatentRate = 0.02, kDecoderRate = 0.005;

struct Decoder {
    std::vector<torch::nn::Linear> layers;
    std::vector<torch::Tensor> parameters() const {
        std::vector<torch::Tensor> p;
        for (const auto& layer : layers) {
            p.push_back(layer->weight);
            p.push_back(layer->bias);
        }
        return p;
    }
    torch::Tensor forward(torch::Tensor x) {
        for (std::size_t k = 0; k + 1 < layers.size(); ++k) x = torch::relu(layers[k]->forward(x));
        return layers.back()->forward(x);
    }
};

/** Taps per training sample: one texel, or the blends of filteredTaps. */
constexpr int kTaps = 4;

/** The taps of a filtered sample around atlas texel `texel` (of level levelOf[texel]), with random
 *  fractions a, b in [0, 1): half of them (a < 0.5, as a coin) GL_LINEAR's four texels of the
 *  level at fraction (2a, b) past the texel's centre, wrapping inside the level; the others the
 *  texel and the coarser level's texel over it, the coarser one weighted b (between two mip
 *  levels), or the four texels where the level is the last. */
void filteredTaps(const std::vector<MipLevel>& levels, const std::vector<std::int8_t>& levelOf,
                  std::size_t width, std::size_t texel, float a, float b, std::size_t* tap,
                  float* weight) {
    const std::size_t l = std::size_t(levelOf[texel]);
    const MipLevel& r = levels[l];
    const int x = int(texel % width) - r.x, y = int(texel / width) - r.y;
    const auto at = [&](const MipLevel& level, int tx, int ty) {
        return std::size_t(level.y + ty) * width + std::size_t(level.x + tx);
    };
    if (a >= 0.5f && l + 1 < levels.size()) {
        const MipLevel& c = levels[l + 1];
        tap[1] = at(c, std::min(x / 2, c.width - 1), std::min(y / 2, c.height - 1));
        weight[0] = 1.0f - b;
        weight[1] = b;
        return;
    }
    const float s = a < 0.5f ? 2.0f * a : 2.0f * a - 1.0f, t = b;
    const int x1 = (x + 1) % r.width, y1 = (y + 1) % r.height;
    tap[1] = at(r, x1, y);
    tap[2] = at(r, x, y1);
    tap[3] = at(r, x1, y1);
    weight[0] = (1.0f - s) * (1.0f - t);
    weight[1] = s * (1.0f - t);
    weight[2] = (1.0f - s) * t;
    weight[3] = s * t;
}

/** A cosine decay from `rate` to a tenth of it over the steps. */
double decayed(double rate, int step, int steps) {
    const double t = double(step) / std::max(1, steps - 1);
    return rate * (0.1 + 0.45 * (1.0 + std::cos(3.14159265358979 * t)));
}

void setRate(torch::optim::Adam& optimizer, double rate) {
    for (auto& group : optimizer.param_groups())
        static_cast<torch::optim::AdamOptions&>(group.options()).lr(rate);
}

void train(const BtfSource& btf, const OptionValues& o, NeuralMaterial& m) {
    const int latentSize = m.latentSize(), steps = o.integer("steps"), batch = o.integer("batch");
    const std::uint64_t seed = std::uint64_t(o.integer("seed"));
    const std::size_t texels = btf.texelCount(), pairs = btf.imageCount(), views = btf.viewCount(),
                      lights = btf.lightCount();
    const std::uint64_t texelBytes = std::uint64_t(pairs) * 3 * sizeof(float);
    const std::size_t blockTexels = std::size_t(std::clamp<std::uint64_t>(
        std::min(kBlockBytes, memoryLimit() / 8) / texelBytes, 1, texels));
    const std::size_t blocks = (texels + blockTexels - 1) / blockTexels;
    const int stepsPerBlock = int(
        std::clamp<std::int64_t>(std::int64_t(steps) / std::int64_t(blocks), 1, kStepsPerBlock));
    checkMemoryBeside(btf, blockTexels * texelBytes + std::uint64_t(texels) * latentSize * 4 * 4,
                      "neural: a block of ABRDFs and the latents");

    // Intra-op threads: the option's count, 0 every core. The batch is drawn on this thread; the
    // same seed gave the same material at 1 and 2 threads (README). One by default: a step's
    // products are small, and on a machine whose other core is busy, a second thread waits at every
    // product's barrier (README: 5-8x slower under load with OpenMP's active waiting, about even
    // with OMP_WAIT_POLICY=passive).
    const int threads = o.integer("threads") > 0
                            ? o.integer("threads")
                            : int(std::max(1u, std::thread::hardware_concurrency()));
    at::set_num_threads(threads);
    torch::manual_seed(seed);
    std::mt19937_64 random(seed);
    // Features and cosines of every measured (view, light) pair, in the ABRDF's order.
    torch::Tensor features =
        torch::empty({std::int64_t(pairs), NeuralMaterial::kDirectionFeatures});
    torch::Tensor cosines = torch::empty({std::int64_t(pairs), 1});
    {
        float* f = features.data_ptr<float>();
        float* c = cosines.data_ptr<float>();
        for (std::size_t v = 0, p = 0; v < views; ++v)
            for (std::size_t l = 0; l < lights; ++l, ++p) {
                NeuralMaterial::directionFeatures(btf.views().vector(v), btf.lights().vector(l),
                                                  f + p * NeuralMaterial::kDirectionFeatures);
                c[p] = btf.lights().vector(l).z;
            }
    }
    torch::Tensor latent =
        (torch::randn({std::int64_t(texels), latentSize}) * 0.1).requires_grad_();
    Decoder decoder;
    for (int k = 0; k <= m.hiddenLayers(); ++k)
        decoder.layers.push_back(torch::nn::Linear(m.layerInputs(k), m.layerOutputs(k)));
    torch::optim::Adam latentOptimizer({latent}, torch::optim::AdamOptions(kLatentRate));
    torch::optim::Adam decoderOptimizer(decoder.parameters(),
                                        torch::optim::AdamOptions(kDecoderRate));

    // Filtered samples (option `filtered`, percent of each batch): the shader decodes the latents
    // blended over the texels a lookup filters (TexelFilter::Inputs), so the decoder and the
    // latents also train on blends: the four texels around a random point of a level (GL_LINEAR
    // between texel centres, wrapping inside the level) or a texel and the coarser level's texel
    // over it (between two mip levels), against the same blend of their measured values, which
    // is what the methods that blend values show there. The levels: a mip atlas's (each level
    // fitted to its own box-filtered data, fit/MipMapping.h), else the whole texture.
    std::vector<MipLevel> levels;
    if (const auto* atlas = dynamic_cast<const MipAtlasSource*>(&btf))
        levels = atlas->layout().levels();
    if (levels.empty()) levels.push_back(MipLevel{0, 0, btf.width(), btf.height()});
    std::vector<std::int8_t> levelOf(texels, -1);  // -1: the atlas's unused corner
    for (std::size_t l = 0; l < levels.size(); ++l)
        for (int y = 0; y < levels[l].height; ++y)
            for (int x = 0; x < levels[l].width; ++x)
                levelOf[std::size_t(levels[l].y + y) * std::size_t(btf.width()) +
                        std::size_t(levels[l].x + x)] = std::int8_t(l);
    const int filteredSamples = int(std::int64_t(batch) * o.integer("filtered") / 100);

    std::vector<float> values(blockTexels * pairs * 3);
    std::vector<std::int64_t> texelIndex(std::size_t(batch) * kTaps), pairIndex(batch);
    std::vector<float> tapWeight(std::size_t(batch) * kTaps);
    std::vector<float> targets(std::size_t(batch) * 3);
    std::vector<std::size_t> order(blocks);
    for (std::size_t b = 0; b < blocks; ++b) order[b] = b;
    std::size_t loaded = blocks, visit = 0, blockFirst = 0, blockCount = 0;
    const auto loadBlock = [&](std::size_t b) {
        if (b == loaded) return;
        blockFirst = b * blockTexels;
        blockCount = std::min(blockTexels, texels - blockFirst);
        const std::size_t sub = std::max<std::size_t>(1, btf.abrdfBlockTexels());
        tbb::parallel_for(std::size_t(0), (blockCount + sub - 1) / sub, [&](std::size_t s) {
            const std::size_t first = s * sub, count = std::min(sub, blockCount - first);
            btf.readAbrdfRange(blockFirst + first, count, values.data() + first * pairs * 3);
        });
        loaded = b;
    };

    // The last tenth: latents rounded to half, as stored, and only the decoder trains, so that it
    // fits the latents the file and the GPU hold.
    const int frozenFrom = steps - std::max(1, steps / 10);
    const int segments = std::min(10, steps);
    double runningLoss = 0;
    int runningCount = 0;
    char label[96];
    for (int segment = 0, step = 0; segment < segments; ++segment) {
        const int segmentEnd = int(std::int64_t(steps) * (segment + 1) / segments);
        if (segment == 0)
            std::snprintf(label, sizeof label, "neural fit");
        else
            std::snprintf(label, sizeof label, "neural fit (loss %.3g)", runningLoss);
        Progress progress(label, std::size_t(segmentEnd - step));
        double segmentLoss = 0;
        int segmentCount = 0;
        for (; step < segmentEnd; ++step) {
            if (step % stepsPerBlock == 0 || blockCount == 0) {
                if (visit % blocks == 0) std::shuffle(order.begin(), order.end(), random);
                loadBlock(order[visit++ % blocks]);
            }
            if (step == frozenFrom) {
                torch::NoGradGuard noGrad;
                float* z = latent.data_ptr<float>();
                for (std::int64_t i = 0; i < latent.numel(); ++i) z[i] = float(Imath::half(z[i]));
                latent.requires_grad_(false);
            }
            std::uniform_int_distribution<std::size_t> pickTexel(0, blockCount - 1),
                pickPair(0, pairs - 1);
            std::uniform_real_distribution<float> fraction(0.0f, 1.0f);
            for (int i = 0; i < batch; ++i) {
                const std::size_t t = pickTexel(random), p = pickPair(random);
                std::size_t tap[kTaps];
                float weight[kTaps] = {1.0f, 0.0f, 0.0f, 0.0f};
                for (std::size_t& k : tap) k = blockFirst + t;
                if (i < filteredSamples && levelOf[blockFirst + t] >= 0)
                    filteredTaps(levels, levelOf, std::size_t(btf.width()), blockFirst + t,
                                 fraction(random), fraction(random), tap, weight);
                pairIndex[i] = std::int64_t(p);
                float* target = targets.data() + std::ptrdiff_t(i) * 3;
                std::fill(target, target + 3, 0.0f);
                for (int k = 0; k < kTaps; ++k) {
                    // A neighbour outside the block in memory: the texel itself instead.
                    if (tap[k] < blockFirst || tap[k] >= blockFirst + blockCount)
                        tap[k] = blockFirst + t;
                    texelIndex[std::size_t(i) * kTaps + k] = std::int64_t(tap[k]);
                    tapWeight[std::size_t(i) * kTaps + k] = weight[k];
                    const float* v = values.data() + ((tap[k] - blockFirst) * pairs + p) * 3;
                    for (int c = 0; c < 3; ++c) target[c] += weight[k] * v[c];
                }
            }
            const torch::Tensor ti =
                torch::from_blob(texelIndex.data(), {batch * kTaps}, torch::kLong);
            const torch::Tensor wi = torch::from_blob(tapWeight.data(), {batch, kTaps, 1});
            const torch::Tensor pi = torch::from_blob(pairIndex.data(), {batch}, torch::kLong);
            const torch::Tensor target = torch::from_blob(targets.data(), {batch, 3});
            const torch::Tensor blended =
                (latent.index_select(0, ti).view({batch, kTaps, latentSize}) * wi).sum(1);
            const torch::Tensor input = torch::cat({blended, features.index_select(0, pi)}, 1);
            const torch::Tensor prediction = decoder.forward(input) * cosines.index_select(0, pi);
            const torch::Tensor loss = torch::mse_loss(prediction, target);
            if (!std::isfinite(loss.item<float>()))
                throw Error("neural: the training diverged at step " + std::to_string(step) +
                            " (loss not finite)");
            decoderOptimizer.zero_grad();
            if (latent.requires_grad()) latentOptimizer.zero_grad();
            loss.backward();
            setRate(decoderOptimizer, decayed(kDecoderRate, step, steps));
            decoderOptimizer.step();
            if (step < frozenFrom) {
                setRate(latentOptimizer, decayed(kLatentRate, step, frozenFrom));
                latentOptimizer.step();
            }
            segmentLoss += loss.item<float>();
            ++segmentCount;
            progress.advance();
        }
        runningLoss = segmentLoss / std::max(1, segmentCount);
        runningCount = segmentCount;
    }
    (void)runningCount;

    // The model as stored: latents as the halves they are now, the decoder's float weights.
    const float* z = latent.data_ptr<float>();
    for (int y = 0; y < m.height(); ++y)
        for (int x = 0; x < m.width(); ++x) {
            const std::size_t t = std::size_t(y) * m.width() + x;
            for (int i = 0; i < latentSize; ++i)
                m.latent.set(m.latentIndex(x, y, i), z[t * latentSize + i]);
        }
    for (int k = 0; k <= m.hiddenLayers(); ++k) {
        const torch::Tensor w = decoder.layers[k]->weight.detach().contiguous();
        const torch::Tensor b = decoder.layers[k]->bias.detach().contiguous();
        const int inputs = m.layerInputs(k);
        for (int j = 0; j < m.layerOutputs(k); ++j) {
            float* row = &m.decoder.data[std::size_t(m.decoderRow(k, j)) * m.decoder.width * 4];
            row[0] = b.data_ptr<float>()[j];
            std::copy(w.data_ptr<float>() + std::size_t(j) * inputs,
                      w.data_ptr<float>() + std::size_t(j + 1) * inputs, row + 4);
        }
    }
    char loss[32];
    std::snprintf(loss, sizeof loss, "%.6g", runningLoss);
    m.fitInfo["loss"] = loss;  // mean squared error of the last tenth's batches
    m.fitInfo["blocks"] = std::to_string(blocks);
    // Fewer steps than blocks leave some blocks' texels at their initial latents.
    m.fitInfo["blocksRead"] = std::to_string(std::min<std::size_t>(visit, blocks));
}

}  // namespace

}  // namespace osgBTF

/** The module's entry point, found by name (dlsym) by NeuralFit.cpp. */
extern "C" __attribute__((visibility("default"))) void osgbtfTrainNeural(
    const osgBTF::BtfSource& btf, const osgBTF::OptionValues& options,
    osgBTF::NeuralMaterial& material) {
    osgBTF::train(btf, options, material);
}
