// Benchmark: BSVTF (Schwartz et al. 2013 Tables 1-2 and Fig. 5) on synthetic fmf materials.
// Usage: bench_bsvtf [--size 512] [--components 32] [--counts 1,5,25,100] [--width 640]
//                    [--height 360] [--frames 3] [--cache 4032] [--quality 98]
//                    [--requests-per-frame 8] [--work DIR]
//   Materials: size^2 texels, C components on the Bonn 81 x 81 directions, Eigen-Textures of
//   falling energy and rising frequency (component k: amplitude 1 / (k + 1), a few sinusoids of
//   about k / 2 + 1 periods plus 5 % noise), U random: what a measured FMF looks like to the
//   tile pyramid and the codec (the rendered colours mean nothing).
//   1. Preprocessing (Schwartz et al. 2013 Table 1): buildTileSet of one material: time, tiles,
//   bytes.
//   2. GPU memory and frame time (Schwartz et al. 2013 Table 2) for each count N: N materials on a
//   grid of
//      quads filling a W x H view, as plain fmf (N texture sets: U + SxV in half) and as BSVTF
//      (one cache, U and a LUT per material, converged for the static camera first). Memory is
//      what the textures take; frame time is the median of `frames` timed frames (glFinish, the
//      BSVTF frame includes its feedback pass and update).
//   3. Progressive streaming (Schwartz et al. 2013 Fig. 5): 25 materials (or the largest count
//   below)
//      streamed from their folder from scratch, one frame at a time, at most N new files requested
//      per frame (a paced link: on localhost everything would arrive at once and the order
//      would not show): bytes received and the SSIM of each frame against the converged frame.
// Prints Markdown tables; timings depend on the GL renderer (printed): llvmpipe here, the GPU
// through bench/gpu.sh.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <random>
#include <sstream>
#include <string>

#include <osg/Group>
#include <osg/MatrixTransform>

#include "core/Error.h"
#include "core/ImageSimilarity.h"
#include "harness/MaterialImage.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/ShaderInterface.h"
#include "materials/fmf/Fmf.h"
#include "streaming/StreamingGroup.h"
#include "streaming/TileBuilder.h"

using namespace osgBTF;
namespace fs = std::filesystem;

namespace {

double since(std::chrono::steady_clock::time_point start) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
}

osg::ref_ptr<FmfMaterial> syntheticFmf(int size, int components) {
    FactoredBtf f;
    f.model = FactorModel::Fmf;
    f.source = "synthetic";
    f.views = f.lights = DirectionSet::bonn81();
    f.width = f.height = size;
    BtfFactor factor;
    std::mt19937 random(3);
    std::uniform_real_distribution<float> uniform(-1.0f, 1.0f);
    const Eigen::Index rows = Eigen::Index(f.imageCount() * 3);
    factor.U.resize(rows, components);
    for (Eigen::Index i = 0; i < factor.U.size(); ++i)
        factor.U.data()[i] = uniform(random) / std::sqrt(float(rows));
    factor.S = Eigen::VectorXf::Ones(components);
    factor.SxV.resize(Eigen::Index(size) * size, components);
    for (int k = 0; k < components; ++k) {
        const float amplitude = 1.0f / float(k + 1), periods = 0.5f * float(k) + 1.0f;
        float phase[6];
        for (float& p : phase) p = uniform(random) * 3.14159f;
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const float u = 6.2831853f * float(x) / float(size),
                            v = 6.2831853f * float(y) / float(size);
                const float value =
                    std::sin(periods * u + phase[0]) * std::cos(periods * v + phase[1]) +
                    0.5f * std::sin(2 * periods * (u + v) + phase[2]) + 0.05f * uniform(random);
                factor.SxV(Eigen::Index(f.factorRow(x, y)), k) = amplitude * value;
            }
    }
    f.factors.push_back(factor);
    return FmfMaterial::fromFactors(f);
}

/** N cells of a grid covering the unit square, each a patch with its own state. */
osg::ref_ptr<osg::Group> grid(const std::vector<osg::ref_ptr<osg::StateSet>>& states) {
    const int n = int(states.size()), columns = int(std::ceil(std::sqrt(double(n))));
    const int rows = (n + columns - 1) / columns;
    osg::ref_ptr<osg::Group> root = new osg::Group;
    osg::StateSet* common = root->getOrCreateStateSet();
    addRectifiedLighting(*common, glm::vec3(0.1f, -0.2f, 0.97f), glm::vec3(0.3f, 0.2f, 0.93f));
    for (int i = 0; i < n; ++i) {
        osg::ref_ptr<osg::MatrixTransform> cell = new osg::MatrixTransform(
            osg::Matrix::scale(1.0 / columns, 1.0 / rows, 1) *
            osg::Matrix::translate(double(i % columns) / columns, double(i / columns) / rows, 0));
        osg::ref_ptr<osg::Geode> patch = rectifiedPatch();
        patch->setStateSet(states[std::size_t(i)].get());
        cell->addChild(patch.get());
        root->addChild(cell.get());
    }
    return root;
}

std::vector<float> rgb(const osg::Image& image) {
    std::vector<float> out;
    const float* p = reinterpret_cast<const float*>(image.data());
    for (int i = 0; i < image.s() * image.t(); ++i)
        for (int c = 0; c < 3; ++c) out.push_back(p[4 * i + c]);
    return out;
}

}  // namespace

int main(int argc, char** argv) {
    int size = 512, components = 32, width = 640, height = 360, frames = 3, cache = 4032,
        quality = 98, requestsPerFrame = 8;
    std::vector<int> counts = {1, 5, 25, 100};
    std::string work = (fs::temp_directory_path() / "osgbtf-bench-bsvtf").string();
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string key = argv[i], value = argv[i + 1];
        if (key == "--size")
            size = std::stoi(value);
        else if (key == "--components")
            components = std::stoi(value);
        else if (key == "--width")
            width = std::stoi(value);
        else if (key == "--height")
            height = std::stoi(value);
        else if (key == "--frames")
            frames = std::stoi(value);
        else if (key == "--cache")
            cache = std::stoi(value);
        else if (key == "--quality")
            quality = std::stoi(value);
        else if (key == "--work")
            work = value;
        else if (key == "--counts") {
            counts.clear();
            std::stringstream in(value);
            for (std::string item; std::getline(in, item, ',');) counts.push_back(std::stoi(item));
        } else {
            std::fprintf(stderr,
                         "bench_bsvtf: unknown option %s (see the top of bench/bsvtf.cpp)\n",
                         key.c_str());
            return 2;
        }
    }
    try {
        fs::create_directories(work);
        const osg::ref_ptr<FmfMaterial> fmf = syntheticFmf(size, components);
        const std::string folder = (fs::path(work) / "tiles").string();
        TileBuildOptions build;
        build.quality = quality;
        auto start = std::chrono::steady_clock::now();
        const TileBuildReport r = buildTileSet(*fmf, folder, build);
        const double buildSeconds = since(start);
        std::printf(
            "## Preprocessing (Schwartz et al. 2013, Table 1: 512^2, C = 100: 1 min "
            "single-threaded)\n\n"
            "| texels | C | tiles | levels | raw tiles | coded tiles | ratio | U | "
            "seconds |\n|---|---|---|---|---|---|---|---|---|\n"
            "| %d^2 | %d | %zu | %d | %.1f MiB | %.2f MiB | %.1f:1 | %.2f MiB | %.2f |\n\n",
            size, components, r.tiles, r.levels, r.rawTileBytes / 1048576.0,
            r.storedTileBytes / 1048576.0,
            double(r.rawTileBytes) / double(std::max<std::uint64_t>(1, r.storedTileBytes)),
            r.uBytes / 1048576.0, buildSeconds);

        HeadlessRenderer renderer;
        std::printf("GL renderer: %s\n\n", renderer.glRenderer().c_str());
        const CameraSetup camera = orthoUnitSquare(width, height);
        std::printf(
            "## GPU memory and frame time (Schwartz et al. 2013, Table 2), %dx%d\n\n"
            "| materials | fmf memory | BSVTF memory | fmf ms | BSVTF ms | BSVTF frames to "
            "converge |\n|---|---|---|---|---|---|\n",
            width, height);
        for (int n : counts) {
            std::vector<osg::ref_ptr<osg::StateSet>> plain;
            for (int i = 0; i < n; ++i) plain.push_back(fmf->createStateSet());
            renderer.setScene(grid(plain).get());
            renderer.setCamera(camera);
            const PassTiming fmfTime = renderer.timePasses(frames);
            const std::uint64_t fmfBytes = std::uint64_t(n) * fmf->memory().totalBytes;
            plain.clear();

            TileStreamerOptions options;
            options.cacheSize = cache;
            osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(options));
            std::vector<osg::ref_ptr<osg::StateSet>> streamed;
            for (int i = 0; i < n; ++i)
                streamed.push_back(group->streamer()->open(folder)->createStateSet());
            group->addChild(grid(streamed).get());
            renderer.setScene(group.get());
            renderer.setCamera(camera);
            int converge = 0;
            while (!group->settled() && converge < 1000) {
                renderer.render();
                ++converge;
            }
            const PassTiming bsvtfTime = renderer.timePasses(frames);
            std::printf("| %d | %.1f MiB | %.1f MiB | %.1f | %.1f | %d |\n", n,
                        fmfBytes / 1048576.0, group->streamer()->gpuBytes() / 1048576.0,
                        fmfTime.wallMs, bsvtfTime.wallMs, converge);
            std::fflush(stdout);
        }

        // Schwartz et al. 2013 Fig. 5: bytes received against SSIM to the converged frame.
        int n = 1;
        for (int c : counts)
            if (c <= 25) n = std::max(n, c);
        TileStreamerOptions options;
        options.cacheSize = cache;
        options.requestsPerUpdate = requestsPerFrame;
        osg::ref_ptr<StreamingGroup> group = new StreamingGroup(new TileStreamer(options));
        std::vector<osg::ref_ptr<osg::StateSet>> streamed;
        for (int i = 0; i < n; ++i)
            streamed.push_back(group->streamer()->open(folder)->createStateSet());
        group->addChild(grid(streamed).get());
        renderer.setScene(group.get());
        renderer.setCamera(camera);
        std::vector<std::pair<std::uint64_t, std::vector<float>>> progress;
        while (!group->settled() && progress.size() < 1000) {
            const osg::ref_ptr<osg::Image> image = renderer.render();
            progress.emplace_back(group->streamer()->stats().bytesReceived, rgb(*image));
        }
        const std::vector<float>& converged = progress.back().second;
        const float peak = *std::max_element(converged.begin(), converged.end());
        std::printf(
            "\n## Progressive streaming, %d materials from scratch (Schwartz et al. 2013, Fig. 5: "
            "SSIM "
            "95.4 %% after 25 MB), at most %d new files per frame\n\n| frame | MiB received | SSIM "
            "to converged |\n"
            "|---|---|---|\n",
            n, requestsPerFrame);
        const std::size_t every = std::max<std::size_t>(1, progress.size() / 12);
        for (std::size_t i = 0; i < progress.size(); ++i)
            if (i % every == 0 || i + 1 == progress.size())
                std::printf(
                    "| %zu | %.2f | %.4f |\n", i + 1, progress[i].first / 1048576.0,
                    structuralSimilarity(progress[i].second, converged, width, height, 3, peak));
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "bench_bsvtf: %s\n", e.what());
        return 1;
    }
}
