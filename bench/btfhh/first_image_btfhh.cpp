// The reference side of bench/first_image_cpu.sh (in its own folder: not a CMake benchmark, it
// needs a header osgBTF does not ship): the Free BTF Library's btf.hh (Z. Velinov,
// MIT, github.com/zeroeffects/btf; never shipped with osgBTF: the script compiles this file
// against a btf.hh the user names) loads a UBO2014 .btf and decodes one (light, view) image on
// the CPU, as its own btf-slice example does, then reports CPU seconds and peak resident memory.
//
//   first_image_btfhh FILE.btf LIGHT_INDEX VIEW_INDEX
//
// Prints one line: "btf.hh: WIDTHxHEIGHT, light THETA,PHI view THETA,PHI, sum R G B, load S s,
// decode S s, cpu S s, peak N KiB" (directions in degrees, as `btf eval` takes them).
#include <sys/resource.h>

#include <chrono>
#include <cstdio>
#include <cstdlib>
// btf.hh uses these without including them.
#include <cmath>
#include <cstring>
#include <fstream>

#define BTF_IMPLEMENTATION
#include "btf.hh"

namespace {
double seconds(std::chrono::steady_clock::time_point from) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - from).count();
}
}  // namespace

int main(int argc, char** argv) {
    if (argc != 4) {
        std::fprintf(stderr, "usage: %s FILE.btf LIGHT_INDEX VIEW_INDEX\n", argv[0]);
        return 2;
    }
    const auto start = std::chrono::steady_clock::now();
    BTF* btf = LoadBTF(argv[1]);
    if (!btf) {
        std::fprintf(stderr, "btf.hh: cannot load %s\n", argv[1]);
        return 1;
    }
    const double load = seconds(start);
    const uint32_t light = std::strtoul(argv[2], nullptr, 10),
                   view = std::strtoul(argv[3], nullptr, 10);
    const auto decodeStart = std::chrono::steady_clock::now();
    // The sum keeps the decode from being optimised away and lets the two sides be compared.
    double sum[3] = {0, 0, 0};
    for (uint32_t y = 0; y < btf->Height; ++y)
        for (uint32_t x = 0; x < btf->Width; ++x) {
            const Spectrum s = BTFFetchSpectrum(btf, light, view, x, y);
            sum[0] += s.x;
            sum[1] += s.y;
            sum[2] += s.z;
        }
    const double decode = seconds(decodeStart);
    // The directions as btf eval takes them (theta, phi in degrees), from the file's vectors.
    const auto degrees = [](const Vector3& d, double& theta, double& phi) {
        theta = std::acos(std::fmax(-1.0, std::fmin(1.0, double(d.z)))) * 180.0 / M_PI;
        phi = std::atan2(double(d.y), double(d.x)) * 180.0 / M_PI;
        if (phi < 0) phi += 360.0;
    };
    double lightTheta, lightPhi, viewTheta, viewPhi;
    degrees(btf->Lights[light], lightTheta, lightPhi);
    degrees(btf->Lights[view], viewTheta, viewPhi);  // one set for both (Dome 1)
    rusage usage{};
    getrusage(RUSAGE_SELF, &usage);
    std::printf(
        "btf.hh: %ux%u, light %.6f,%.6f view %.6f,%.6f, sum %.6g %.6g %.6g, load %.3f s, "
        "decode %.3f s, cpu %.3f s, peak %ld KiB\n",
        btf->Width, btf->Height, lightTheta, lightPhi, viewTheta, viewPhi, sum[0], sum[1], sum[2],
        load, decode,
        usage.ru_utime.tv_sec + usage.ru_utime.tv_usec * 1e-6 + usage.ru_stime.tv_sec +
            usage.ru_stime.tv_usec * 1e-6,
        usage.ru_maxrss);
    DestroyBTF(btf);
    return 0;
}
