// Benchmark: load time of a UBO2003-style JPEG zip (6561 images of 256x256 by default).
// Usage: bench_load_ubo2003 [--size N] [--zip FILE] [--keep] [--half]
//   Generates a synthetic Bonn-81 BTF of NxN texels (a smooth pattern plus fixed noise, so the
//   JPEGs carry realistic entropy), writes it with writeUbo2003Zip (quality 95), then times
//   loadUbo2003. --zip reuses FILE when it exists (and keeps it); --half loads into half storage.
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>
#include <vector>

#include <tbb/parallel_for.h>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "loaders/Ubo2003.h"

namespace {

osgBTF::MeasuredBtf synthetic(int size) {
    const osgBTF::DirectionSet bonn = osgBTF::DirectionSet::bonn81();
    osgBTF::MeasuredBtf btf(size, size, bonn, bonn, osgBTF::Storage::Half);
    std::vector<float> noise(std::size_t(size) * size);
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> uniform(-0.05f, 0.05f);
    for (float& n : noise) n = uniform(rng);
    tbb::parallel_for(std::size_t(0), bonn.size() * bonn.size(), [&](std::size_t i) {
        const std::size_t view = i / bonn.size(), light = i % bonn.size();
        const float lz = bonn.vector(light).z, vz = bonn.vector(view).z;
        std::vector<float> rx(size), cy(size), image(std::size_t(size) * size * 3);
        for (int t = 0; t < size; ++t) {
            rx[t] = 0.5f + 0.5f * std::sin(0.05f * t * (1 + light % 7) + 0.3f * view);
            cy[t] = 0.5f + 0.5f * std::cos(0.04f * t * (1 + view % 5) + 0.2f * light);
        }
        for (int y = 0; y < size; ++y)
            for (int x = 0; x < size; ++x) {
                const float base =
                    0.15f + 0.6f * lz * rx[x] * cy[y] + noise[std::size_t(y) * size + x];
                float* p = image.data() + (std::size_t(y) * size + x) * 3;
                p[0] = base;
                p[1] = base * (0.8f + 0.2f * vz);
                p[2] = base * 0.7f;
            }
        btf.setImage(view, light, image.data());
    });
    return btf;
}

}  // namespace

int main(int argc, char** argv) {
    int size = 256;
    std::string zip;
    bool keep = false, half = false;
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if (arg == "--size" && i + 1 < argc)
            size = std::atoi(argv[++i]);
        else if (arg == "--zip" && i + 1 < argc)
            zip = argv[++i], keep = true;
        else if (arg == "--keep")
            keep = true;
        else if (arg == "--half")
            half = true;
        else {
            std::fprintf(stderr, "usage: %s [--size N] [--zip FILE] [--keep] [--half]\n", argv[0]);
            return 2;
        }
    }
    try {
        namespace fs = std::filesystem;
        if (zip.empty())
            zip = (fs::temp_directory_path() /
                   ("osgbtf-bench-ubo2003-" + std::to_string(size) + ".zip"))
                      .string();
        using clock = std::chrono::steady_clock;
        if (!fs::exists(zip)) {
            auto t0 = clock::now();
            osgBTF::MeasuredBtf btf = synthetic(size);
            auto t1 = clock::now();
            osgBTF::writeUbo2003Zip(btf, zip, osgBTF::Ubo2003ImageFormat::Jpeg, 95);
            auto t2 = clock::now();
            std::printf("generated %dx%d x 81 x 81 in %.2f s, wrote %s (%.1f MiB) in %.2f s\n",
                        size, size, std::chrono::duration<double>(t1 - t0).count(), zip.c_str(),
                        double(fs::file_size(zip)) / (1 << 20),
                        std::chrono::duration<double>(t2 - t1).count());
        }
        osgBTF::LoadOptions options;
        options.storage = half ? osgBTF::Storage::Half : osgBTF::Storage::Float;
        auto t0 = clock::now();
        osgBTF::MeasuredBtf loaded = osgBTF::loadUbo2003(zip, options);
        const double seconds = std::chrono::duration<double>(clock::now() - t0).count();
        const std::size_t images = loaded.viewCount() * loaded.lightCount();
        std::printf("loadUbo2003: %zu images of %dx%d (%s storage) in %.2f s = %.0f images/s\n",
                    images, loaded.width(), loaded.height(), half ? "half" : "float", seconds,
                    double(images) / seconds);
        if (!keep) fs::remove(zip);
    } catch (const osgBTF::Error& e) {
        std::fprintf(stderr, "error: %s\n", e.what());
        return 1;
    }
    return 0;
}
