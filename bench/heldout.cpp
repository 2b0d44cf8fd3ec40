// Benchmark: methods fitted with a tenth of the measured (view, light) pairs left out, scored on
// the pairs they saw and on the ones they did not: how well each model interpolates between
// measured directions (the claim of Rainer et al. 2019 for neural BTFs), next to its bytes.
// Left out: every tenth light (lights 5, 15, ..., 75 of the 81), under every view, 9.9 % of the
// pairs; a method then meets those lights only between its measured ones (pca, lpca, fmf, ... blend
// their neighbours; neural and the analytic models evaluate their functions there).
//
// Usage: bench_heldout [--size N] [--variation V] [--methods "m[:opts];m[:opts];..."]
//   The built-in sample at N x N texels (64), with --variation V (btf sample --variation).
//   Default methods: lambert; pca 8 and 16 components; fmf 8 and 32; neural at its default and
//   at latent=32 units=64.
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <sstream>
#include <string>
#include <vector>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MethodRegistry.h"

using namespace osgBTF;

namespace {

struct Row {
    std::string method, options;
};

std::vector<Row> parseMethods(const std::string& text) {
    std::vector<Row> rows;
    std::stringstream in(text);
    std::string item;
    while (std::getline(in, item, ';')) {
        if (item.empty()) continue;
        const auto colon = item.find(':');
        rows.push_back(
            {item.substr(0, colon), colon == std::string::npos ? "" : item.substr(colon + 1)});
    }
    return rows;
}

ErrorSummary score(const MeasuredBtf& full, const Material& m,
                   const std::vector<std::size_t>& pairs) {
    const std::size_t lights = full.lightCount();
    return computeError(
        full,
        [&](std::size_t texel, float* out) {
            const int x = int(texel % std::size_t(full.width())),
                      y = int(texel / std::size_t(full.width()));
            for (std::size_t p : pairs) {
                const glm::vec3 v = m.evaluate(x, y, full.views().vector(p / lights),
                                               full.lights().vector(p % lights));
                for (int c = 0; c < 3; ++c) out[p * 3 + c] = v[c];
            }
        },
        nullptr, &pairs);
}

}  // namespace

int main(int argc, char** argv) {
    int size = 64;
    double variation = 0;
    std::string methods =
        "lambert;pca:components=8;pca:components=16;fmf:components=8;fmf:components=32;"
        "neural;neural:latent=32 units=64";
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--size" && i + 1 < argc)
            size = std::atoi(argv[++i]);
        else if (arg == "--variation" && i + 1 < argc)
            variation = std::atof(argv[++i]);
        else if (arg == "--methods" && i + 1 < argc)
            methods = argv[++i];
        else {
            std::fprintf(stderr,
                         "usage: %s [--size N] [--variation V] [--methods \"m[:opts];...\"]\n",
                         argv[0]);
            return 2;
        }
    }
    try {
        SampleOptions options;
        options.width = options.height = size;
        options.variation = float(variation);
        const MeasuredBtf full = makeSampleBtf(options);
        std::vector<Direction> kept;
        std::vector<std::size_t> keptIndex, seenPairs, heldOutPairs;
        for (std::size_t l = 0; l < full.lightCount(); ++l)
            if (l % 10 != 5) {
                kept.push_back(full.lights()[l]);
                keptIndex.push_back(l);
            }
        for (std::size_t v = 0; v < full.viewCount(); ++v)
            for (std::size_t l = 0; l < full.lightCount(); ++l)
                (l % 10 == 5 ? heldOutPairs : seenPairs).push_back(v * full.lightCount() + l);
        MeasuredBtf training(size, size, full.views(), DirectionSet("kept lights", kept));
        for (std::size_t v = 0; v < full.viewCount(); ++v)
            for (std::size_t k = 0; k < keptIndex.size(); ++k)
                training.setImage(v, k, full.image(v, keptIndex[k]).data());
        std::printf(
            "sample %dx%d, variation %g: %zu of %zu pairs left out (%.1f %%)\n\n", size, size,
            variation, heldOutPairs.size(), seenPairs.size() + heldOutPairs.size(),
            100.0 * double(heldOutPairs.size()) / double(seenPairs.size() + heldOutPairs.size()));
        std::printf(
            "| method | options | bytes/texel | fit s | seen: avg | RMSE | PSNR dB | "
            "held out: avg | RMSE | PSNR dB |\n|---|---|---|---|---|---|---|---|---|---|\n");
        for (const Row& row : parseMethods(methods)) {
            const auto start = std::chrono::steady_clock::now();
            const osg::ref_ptr<Material> m =
                findMethod(row.method).fit(training, FitOptions::parse(row.options));
            const double seconds =
                std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
            const ErrorSummary seen = score(full, *m, seenPairs);
            const ErrorSummary heldOut = score(full, *m, heldOutPairs);
            std::printf("| %s | %s | %.1f | %.1f | %.4f | %.4f | %.2f | %.4f | %.4f | %.2f |\n",
                        row.method.c_str(), row.options.c_str(), m->memory().bytesPerTexel, seconds,
                        seen.average, seen.rmse, seen.psnr, heldOut.average, heldOut.rmse,
                        heldOut.psnr);
            std::fflush(stdout);
        }
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_heldout: %s\n", e.what());
        return 1;
    }
    return 0;
}
