// Tiny UBO2014 .btf files written byte by byte from docs/formats.md section 2, not
// through osgBTF's writer, with the values they encode computed here from the format's formulas
// (2.6, 2.7) in double precision. Shared by the loader tests and the GPU tests of the native
// material, so both read files that another implementation of the format could have written.
#pragma once

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include <Imath/half.h>

namespace osgBTF::test {

struct HandWrittenBtf {
    std::string bytes;  ///< the whole file
    std::string signature;
    bool fmf = false;
    int width = 0, height = 0;
    /** Degrees, in the file's order; phi in [0, 360) although the file stores some as negative
     *  radians (as btflib writes azimuths). */
    std::vector<std::array<double, 2>> views, lights;
    int colorModel = 0;  ///< DFMF
    bool drr = false;    ///< FMF
    bool cosine = false;
    int scalarSize = 4;
    /** Per factor (DFMF: one per channel, FMF: one): rank K, U (rows x K) and SxV (texels x K),
     *  row-major, exactly as stored (every value is exact in half, float and double). */
    std::vector<int> ranks;
    std::vector<std::vector<double>> u, sxv;
    /** Byte offsets for corrupting the file in tests: DFMF's colour model (i32; -1 for FMF) and
     *  the first factor header (DFMF channel 0's scalar-size byte, FMF's K_a). */
    long colorModelOffset = -1;
    long factorHeaderOffset = 0;

    /** Expected RGB of the file's texel (x, yFile), yFile counted from the file's first row (the
     *  top of the image, formats.md 2.8), at view v and light l: 2.6's factor sums, then 2.7's
     *  colour model (DFMF) or exp (FMF with DRR), then the cosine division. */
    std::array<double, 3> value(int v, int l, int x, int yFile) const {
        const int nL = int(lights.size()), lv = v * nL + l, texel = yFile * width + x;
        double sums[3];
        for (int c = 0; c < 3; ++c) {
            const int f = fmf ? 0 : c, k = ranks[std::size_t(f)];
            const int row = fmf ? lv * 3 + c : lv;
            double sum = 0;
            for (int i = 0; i < k; ++i)
                sum += u[std::size_t(f)][std::size_t(row * k + i)] *
                       sxv[std::size_t(f)][std::size_t(texel * k + i)];
            sums[c] = sum;
        }
        const double eps = 1e-5;
        std::array<double, 3> rgb{};
        if (fmf) {
            for (int c = 0; c < 3; ++c)
                rgb[std::size_t(c)] = drr ? std::exp(sums[c]) - eps : sums[c];
        } else if (colorModel == 11) {
            // Y = exp(v0) - eps, U = v1 (Y + eps), V = v2 (Y + eps), then YUV -> RGB.
            const double y = std::exp(sums[0]) - eps, cu = sums[1] * (y + eps),
                         cv = sums[2] * (y + eps);
            rgb = {y + 1.13983 * cv, y - 0.39465 * cu - 0.5806 * cv, y + 2.03211 * cu};
        } else {
            rgb = {sums[0], sums[1], sums[2]};
        }
        if (cosine) {
            const double z = std::cos(lights[std::size_t(l)][0] * kPi / 180.0);
            for (double& c : rgb) c /= z;
        }
        return rgb;
    }

    static constexpr double kPi = 3.14159265358979323846;
};

namespace handwritten {

/** Little-endian appends (every platform osgBTF builds on is little-endian). */
struct Bytes {
    std::string data;
    template <typename T>
    void put(T value) {
        data.append(reinterpret_cast<const char*>(&value), sizeof value);
    }
    void u8(unsigned v) { put(std::uint8_t(v)); }
    void u32(std::uint32_t v) { put(v); }
    void i32(std::int32_t v) { put(v); }
    void f32(float v) { put(v); }
    void text(const std::string& s) { data += s; }
    void padded(const std::string& s, std::size_t width) {
        std::string field = s;
        field.resize(width, '\0');
        data += field;
    }
    void scalar(double v, int size) {
        if (size == 2)
            put(Imath::half(float(v)).bits());
        else if (size == 4)
            put(float(v));
        else
            put(v);
    }
};

/** Multiples of 1/64 in [-0.75, 0.75]: exact in half, so half storage reproduces them. */
inline double patternValue(int i, int seed) {
    return double((i * 37 + seed * 11 + 5) % 97 - 48) / 64.0;
}

/** The meta block of 2.2, version 4, names R, G, B. */
inline void putMeta(Bytes& b, bool cosine, const std::string& xml) {
    b.u32(std::uint32_t(291 + xml.size()));  // Size: 264 fixed + cosine + XML + channels
    b.u32(4);
    b.padded("hand-written test dome", 80);
    b.padded("no sensor", 80);
    b.padded("no lamp", 80);
    b.f32(12.5f);  // ppmm
    b.f32(1.0f);
    b.f32(1.0f);
    b.f32(1.0f);  // rgb scale, never applied
    b.u32(cosine ? 1 : 0);
    b.u32(std::uint32_t(xml.size()));
    b.text(xml);
    b.u32(3);
    for (const char* name : {"R", "G", "B"}) {
        b.u32(1);
        b.text(name);
    }
}

/** 2.3: the view list, each view followed by the whole light list (radians, phi in (-pi, pi]),
 *  then width and height. */
inline void putDirections(Bytes& b, const HandWrittenBtf& f) {
    auto angle = [&](const std::array<double, 2>& d) {
        const double phi = d[1] > 180.0 ? d[1] - 360.0 : d[1];
        b.f32(float(d[0] * HandWrittenBtf::kPi / 180.0));
        b.f32(float(phi * HandWrittenBtf::kPi / 180.0));
    };
    b.u32(std::uint32_t(f.views.size()));
    for (const auto& v : f.views) {
        angle(v);
        b.u32(std::uint32_t(f.lights.size()));
        for (const auto& l : f.lights) angle(l);
    }
    b.u32(std::uint32_t(f.width));
    b.u32(std::uint32_t(f.height));
}

/** S (K scalars), U, SxV row-major. */
inline void putFactor(Bytes& b, const HandWrittenBtf& f, std::size_t i) {
    const int k = f.ranks[i];
    for (int s = 0; s < k; ++s) b.scalar(double(k - s), f.scalarSize);  // S: unused for decoding
    for (double v : f.u[i]) b.scalar(v, f.scalarSize);
    for (double v : f.sxv[i]) b.scalar(v, f.scalarSize);
}

inline void fillFactor(HandWrittenBtf& f, int rows, int k, int seed) {
    const int texels = f.width * f.height;
    std::vector<double> u(std::size_t(rows * k)), sxv(std::size_t(texels * k));
    for (std::size_t i = 0; i < u.size(); ++i) u[i] = patternValue(int(i), seed);
    for (std::size_t i = 0; i < sxv.size(); ++i) sxv[i] = patternValue(int(i), seed + 3);
    f.ranks.push_back(k);
    f.u.push_back(u);
    f.sxv.push_back(sxv);
}

inline void directionsOf(HandWrittenBtf& f) {
    // Views and lights differ (catches swaps); a ring at theta 75 so unmeasured directions lie
    // inside the triangulation too; phi > 180 is stored negative.
    f.views = {{0, 0}, {40, 0}, {40, 120}, {40, 240}, {75, 60}, {75, 180}, {75, 300}};
    f.lights = {{0, 0},    {30, 90},  {30, 210}, {30, 330}, {60, 30},
                {60, 150}, {60, 270}, {75, 0},   {75, 120}, {75, 240}};
}

}  // namespace handwritten

/** DFMF ("!DFMF08FCR", two rotations), colour model 11, ranks 2, 3, 1 for Y, U, V, float
 *  scalars, 4 x 3 texels, no cosine in the data. */
inline HandWrittenBtf handWrittenDfmf11() {
    using namespace handwritten;
    HandWrittenBtf f;
    f.signature = "!DFMF08FCR";
    f.width = 4;
    f.height = 3;
    f.colorModel = 11;
    f.scalarSize = 4;
    directionsOf(f);
    const int rows = int(f.views.size() * f.lights.size());
    fillFactor(f, rows, 2, 1);
    fillFactor(f, rows, 3, 2);
    fillFactor(f, rows, 1, 3);
    // Chroma ratios of a few percent, as in real data: scale U and V down (still exact).
    for (int c = 1; c < 3; ++c)
        for (double& v : f.u[std::size_t(c)]) v /= 8;

    Bytes b;
    b.text(f.signature);
    putMeta(b, false, "<btf/>");
    putDirections(b, f);
    b.u32(2);  // rotations: two 3x3 frames, read and ignored
    for (int r = 0; r < 2; ++r)
        for (int i = 0; i < 9; ++i) b.f32(i % 4 == 0 ? 1.0f : 0.0f);
    b.u32(3);  // maximum component count (unused)
    f.colorModelOffset = long(b.data.size());
    b.i32(11);
    for (int i = 0; i < 3; ++i) b.f32(0.0f);  // mean, matrix: unused by model 11
    for (int i = 0; i < 9; ++i) b.f32(i % 4 == 0 ? 1.0f : 0.0f);
    f.factorHeaderOffset = long(b.data.size());
    for (std::size_t c = 0; c < 3; ++c) {
        b.u8(unsigned(f.scalarSize));
        b.u32(std::uint32_t(f.ranks[c]));
        b.u32(std::uint32_t(rows));
        b.u32(std::uint32_t(f.width * f.height));
        putFactor(b, f, c);
    }
    f.bytes = b.data;
    return f;
}

/** FMF with the extended header ("!FMF12FCE", header version 1): dynamic-range reduction on, the
 *  cosine flag set, half scalars, rank 3, 3 x 5 texels. */
inline HandWrittenBtf handWrittenFmfDrrCosine() {
    using namespace handwritten;
    HandWrittenBtf f;
    f.signature = "!FMF12FCE";
    f.fmf = true;
    f.width = 3;
    f.height = 5;
    f.drr = true;
    f.cosine = true;
    f.scalarSize = 2;
    directionsOf(f);
    const int rows = int(f.views.size() * f.lights.size() * 3);
    fillFactor(f, rows, 3, 4);

    Bytes b;
    b.text(f.signature);
    putMeta(b, true, "");
    putDirections(b, f);
    b.u8(1);   // header version 1: the DRR field, no height map
    b.u32(1);  // dynamic-range reduction on
    f.factorHeaderOffset = long(b.data.size());
    b.u32(3);  // K_a
    b.u8(unsigned(f.scalarSize));
    b.u32(3);  // K_b (stride)
    b.u32(std::uint32_t(rows));
    b.u32(std::uint32_t(f.width * f.height));
    putFactor(b, f, 0);
    f.bytes = b.data;
    return f;
}

}  // namespace osgBTF::test
