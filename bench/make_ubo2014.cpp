// Benchmark input: a full-size UBO2014 DFMF file written with the project's
// writer (writeUbo2014): 400x400 texels, 151 x 151 Dome-1 directions, K = 100 components per
// channel, colour model 11 (exp-YUV), half scalars by default.
// Usage: bench_make_ubo2014 -o FILE [--size N] [--components K] [--scalar 2|4] [--cosine] [--seed
// S]
// --seed S (a database of varied materials, bench/batch.sh): other random factors, a glossy lobe
// exponent in 10..80 and a thread period in 4..12 texels instead of 40 and 8.
//
// Values, chosen so the decoded BTF looks like a real material rather than noise:
//   channel Y (stored as log(Y + eps)): component 0 = log of a smooth BRDF (diffuse + a glossy
//     lobe, times cos(theta_light): the Bonn data contain the cosine) over every (view, light),
//     with SxV 1; component 1 = log albedo of a woven texture (U 1); components 2.. = smooth
//     functions of the directions (cosines of their disc coordinates) times textured SxV
//     (sinusoids plus per-texel noise), amplitudes falling as 1/k;
//   channels U, V (stored as chroma / (Y + eps)): a per-texel hue (U 1) plus small smooth terms.
// With half scalars the file holds 54.8 M scalars = 110 MB (219 MB with floats); decoded it is
// 22801 images x 160000 texels x RGB = 10.9 G values (43.8 GB as float, 21.9 GB as half).
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <filesystem>
#include <random>
#include <string>

#include <glm/geometric.hpp>

#include "core/Directions.h"
#include "core/Error.h"
#include "loaders/Ubo2014.h"

namespace {

constexpr float kPi = 3.14159265f;

float hashNoise(std::uint32_t a, std::uint32_t b) {
    std::uint32_t h = a * 0x9E3779B1u ^ (b + 0x7F4A7C15u) * 0x85EBCA77u;
    h ^= h >> 15;
    h *= 0x2C1B3C6Du;
    h ^= h >> 12;
    return float(h & 0xFFFFu) / 65535.0f * 2.0f - 1.0f;
}

}  // namespace

int main(int argc, char** argv) {
    std::string output;
    int size = 400, components = 100, scalarSize = 2;
    bool cosine = false;
    unsigned seed = 0;  // 0: the one file every other benchmark uses
    for (int i = 1; i < argc; ++i) {
        const std::string arg = argv[i];
        if ((arg == "-o" || arg == "--out") && i + 1 < argc)
            output = argv[++i];
        else if (arg == "--size" && i + 1 < argc)
            size = std::atoi(argv[++i]);
        else if (arg == "--components" && i + 1 < argc)
            components = std::atoi(argv[++i]);
        else if (arg == "--scalar" && i + 1 < argc)
            scalarSize = std::atoi(argv[++i]);
        else if (arg == "--cosine")
            cosine = true;
        else if (arg == "--seed" && i + 1 < argc)
            seed = unsigned(std::strtoul(argv[++i], nullptr, 10));
        else
            output.clear(), i = argc;
    }
    if (output.empty() || size < 1 || components < 2 || (scalarSize != 2 && scalarSize != 4)) {
        std::fprintf(stderr,
                     "usage: %s -o FILE [--size N] [--components K>=2] [--scalar 2|4] [--cosine] "
                     "[--seed S]\n",
                     argv[0]);
        return 2;
    }
    try {
        using clock = std::chrono::steady_clock;
        const auto start = clock::now();
        osgBTF::Ubo2014Factors f;
        f.model = osgBTF::FactorModel::Dfmf;
        f.source = output;
        f.views = f.lights = osgBTF::DirectionSet::ubo2014();
        f.width = f.height = size;
        f.colorModel = 11;
        f.colorMatrix = {1, 0, 0, 0, 1, 0, 0, 0, 1};
        f.cosine = cosine;
        f.scalarSize = scalarSize;
        f.maxComponents = std::uint32_t(components);
        f.measurementSetup = "osgBTF bench_make_ubo2014 (synthetic)";
        f.ppmm = 10.0f;
        f.hasRotations = true;  // "!DFMF08FCR" as the Bonn files, with no rotations listed

        const std::size_t nV = f.views.size(), nL = f.lights.size(), rows = nV * nL;
        const std::size_t texels = std::size_t(size) * std::size_t(size);
        const int K = components;
        std::mt19937 random(seed ? seed : 2014);
        std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
        const float shininess = seed ? 10.0f + 70.0f * uniform(random) : 40.0f;
        const float period = seed ? 4.0f + 8.0f * uniform(random) : 8.0f;
        for (int c = 0; c < 3; ++c) {
            osgBTF::BtfFactor factor;
            factor.U.resize(Eigen::Index(rows), K);
            factor.SxV.resize(Eigen::Index(texels), K);
            factor.S.resize(K);
            // Smooth direction functions: cosines of the parabolic disc coordinates of view and
            // light with random low frequencies.
            std::vector<std::array<float, 5>> basis(static_cast<std::size_t>(K));
            for (auto& b : basis)
                for (float& x : b) x = uniform(random);
            for (std::size_t v = 0; v < nV; ++v) {
                const glm::vec3 wv = f.views.vector(v);
                const float pvx = wv.x / (1 + wv.z), pvy = wv.y / (1 + wv.z);
                for (std::size_t l = 0; l < nL; ++l) {
                    const glm::vec3 wl = f.lights.vector(l);
                    const float plx = wl.x / (1 + wl.z), ply = wl.y / (1 + wl.z);
                    const Eigen::Index row = Eigen::Index(v * nL + l);
                    for (int k = 0; k < K; ++k) {
                        const auto& b = basis[std::size_t(k)];
                        const float smooth =
                            std::cos(3.0f * (b[0] * pvx + b[1] * pvy) +
                                     3.0f * (b[2] * plx + b[3] * ply) + 2.0f * kPi * b[4]);
                        factor.U(row, k) = smooth * (c == 0 ? 0.3f : 0.02f) / float(k);
                    }
                    if (c == 0) {
                        const glm::vec3 h = glm::normalize(wv + wl);
                        const float cosL = std::max(wl.z, 0.02f);
                        const float lobe = std::pow(std::max(h.z, 0.0f), shininess);
                        factor.U(row, 0) = std::log(cosL * (0.35f + 2.5f * lobe));
                        factor.U(row, 1) = 1.0f;
                    } else {
                        factor.U(row, 0) = 1.0f;
                        factor.U(row, 1) = 0.05f * std::cos(3.0f * (plx - pvx));
                    }
                }
            }
            std::vector<std::array<float, 3>> waves(static_cast<std::size_t>(K));
            for (auto& w : waves)
                for (float& x : w) x = uniform(random);
            for (int y = 0; y < size; ++y)
                for (int x = 0; x < size; ++x) {
                    const Eigen::Index row = Eigen::Index(std::size_t(y) * size + x);
                    // A woven pattern: threads every `period` texels, alternating direction.
                    const float u = float(x) / period, w = float(y) / period;
                    const bool over = (int(std::floor(u)) + int(std::floor(w))) % 2 == 0;
                    const float thread = 0.5f + 0.5f * std::sin(kPi * (over ? u : w));
                    for (int k = 0; k < K; ++k) {
                        const auto& wave = waves[std::size_t(k)];
                        factor.SxV(row, k) =
                            0.7f * std::sin(2 * kPi *
                                            ((wave[0] * x + wave[1] * y) / 16.0f + wave[2])) +
                            0.3f * hashNoise(std::uint32_t(row), std::uint32_t(k * 3 + c));
                    }
                    if (c == 0) {
                        factor.SxV(row, 0) = 1.0f;
                        factor.SxV(row, 1) = std::log(0.15f + 0.6f * thread +
                                                      0.05f * hashNoise(std::uint32_t(row), 7));
                    } else {
                        factor.SxV(row, 0) = (c == 1 ? -0.08f : 0.12f) * (0.5f + thread);
                        factor.SxV(row, 1) = 1.0f;
                    }
                }
            for (int k = 0; k < K; ++k) factor.S[k] = factor.SxV.col(k).norm();
            f.factors.push_back(std::move(factor));
        }
        f.validate();
        const auto made = clock::now();
        osgBTF::writeUbo2014(f, output);
        const auto written = clock::now();
        std::printf(
            "wrote %s: %dx%d texels, %zu x %zu directions (Dome 1), DFMF colour model 11, "
            "K = %d per channel, %s scalars, %.1f MB (decoded: %.1f GB as float)\n"
            "time: generate %.2f s, write %.2f s\n",
            output.c_str(), size, size, nV, nL, K, scalarSize == 2 ? "half" : "float",
            double(std::filesystem::file_size(output)) / 1e6, double(f.decodedBytes()) / 1e9,
            std::chrono::duration<double>(made - start).count(),
            std::chrono::duration<double>(written - made).count());
    } catch (const osgBTF::Error& e) {
        std::fprintf(stderr, "bench_make_ubo2014: %s\n", e.what());
        return 1;
    }
    return 0;
}
