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

#include <Imath/half.h>
#include <tbb/parallel_for.h>
#include <torch/torch.h>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
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
    checkMemory(blockTexels * texelBytes + std::uint64_t(texels) * latentSize * 4 * 4,
                "neural: a block of ABRDFs and the latents");

    // One thread: a step's products are too small to split (the sample at 32 x 32 fitted in 25.6 s
    // on one thread, 38.4 s on two), and a seed then gives the same fit whatever the core count.
    at::set_num_threads(1);
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

    std::vector<float> values(blockTexels * pairs * 3);
    std::vector<std::int64_t> texelIndex(batch), pairIndex(batch);
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
            for (int i = 0; i < batch; ++i) {
                const std::size_t t = pickTexel(random), p = pickPair(random);
                texelIndex[i] = std::int64_t(blockFirst + t);
                pairIndex[i] = std::int64_t(p);
                const float* v = values.data() + (t * pairs + p) * 3;
                std::copy(v, v + 3, targets.begin() + std::ptrdiff_t(i) * 3);
            }
            const torch::Tensor ti = torch::from_blob(texelIndex.data(), {batch}, torch::kLong);
            const torch::Tensor pi = torch::from_blob(pairIndex.data(), {batch}, torch::kLong);
            const torch::Tensor target = torch::from_blob(targets.data(), {batch, 3});
            const torch::Tensor input =
                torch::cat({latent.index_select(0, ti), features.index_select(0, pi)}, 1);
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
