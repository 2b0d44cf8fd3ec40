// Writing factorisations as UBO2014 .btf files (`btf fit -m fmf -o out.btf`),
// checked with a byte-level parser written here from docs/formats.md section 2, not
// with osgBTF's reader: the file must be what the format's reference readers expect.
#include <unistd.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <memory>
#include <stdexcept>
#include <string>
#include <vector>

#include <Imath/half.h>
#include <gtest/gtest.h>

#include "core/FactoredBtf.h"
#include "harness/sample/SampleBtf.h"
#include "loaders/Ubo2014.h"
#include "materials/MethodOptions.h"
#include "materials/fmf/Fmf.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::readTextFile;
using osgBTF::test::TempDir;

namespace {

constexpr double kPi = 3.14159265358979323846;

/** A UBO2014 FMF or DFMF file as formats.md 2.1-2.6 lay it out. Throws std::runtime_error on any
 *  violation of the format (wrong Size, short file, trailing bytes, differing light lists). */
struct ParsedBtf {
    std::string signature;
    std::uint32_t metaSize = 0, metaVersion = 0;
    std::string setup, sensor, lamp;
    float ppmm = 0, rgbScale[3] = {0, 0, 0};
    std::uint32_t cosine = 0;
    std::string xml;
    std::vector<std::string> channels;
    std::vector<std::array<float, 2>> views, lights;  ///< radians as stored
    std::uint32_t width = 0, height = 0;
    // FMF
    int headerVersion = -1;
    std::uint32_t drr = 0;
    // DFMF
    std::int32_t colorModel = -1;
    struct Factor {
        int scalarSize = 0;
        std::uint32_t k = 0, stride = 0, rows = 0, cols = 0;
        std::vector<double> s, u, sxv;  ///< u: rows x stride, sxv: cols x stride
    };
    std::vector<Factor> factors;

    explicit ParsedBtf(const std::string& bytes) : _b(bytes) {
        const bool fmf = bytes.compare(0, 9, "!FMF12FCE") == 0;
        const bool dfmf = bytes.compare(0, 9, "!DFMF08FC") == 0;
        if (!fmf && !dfmf) throw std::runtime_error("signature " + bytes.substr(0, 10));
        signature = bytes.substr(0, 9);
        _pos = 9;
        if (_pos < _b.size() && _b[_pos] == 'R') throw std::runtime_error("rotations flag set");
        // 2.2 meta block.
        const std::size_t metaStart = _pos;
        metaSize = get<std::uint32_t>();
        metaVersion = get<std::uint32_t>();
        setup = chars(80);
        sensor = chars(80);
        lamp = chars(80);
        ppmm = get<float>();
        for (float& s : rgbScale) s = get<float>();
        if (metaVersion > 1) cosine = get<std::uint32_t>();
        if (metaVersion > 2) xml = raw(get<std::uint32_t>());
        if (metaVersion > 3) {
            const std::uint32_t n = get<std::uint32_t>();
            for (std::uint32_t c = 0; c < n; ++c) channels.push_back(raw(get<std::uint32_t>()));
        }
        if (_pos - metaStart != metaSize) throw std::runtime_error("meta Size mismatch");
        // 2.3 directions: the light list after every view, identical each time.
        const std::uint32_t nV = get<std::uint32_t>();
        for (std::uint32_t v = 0; v < nV; ++v) {
            const float theta = get<float>(), phi = get<float>();
            views.push_back({theta, phi});
            const std::uint32_t nL = get<std::uint32_t>();
            std::vector<std::array<float, 2>> list;
            for (std::uint32_t l = 0; l < nL; ++l) {
                const float lt = get<float>(), lp = get<float>();
                list.push_back({lt, lp});
            }
            if (v == 0)
                lights = list;
            else if (list != lights)
                throw std::runtime_error("view " + std::to_string(v) + " lists other lights");
        }
        width = get<std::uint32_t>();
        height = get<std::uint32_t>();
        const std::uint64_t images = std::uint64_t(nV) * lights.size(),
                            texels = std::uint64_t(width) * height;
        if (fmf) {
            // 2.5: header version, DRR; K_a, scalar size, K_b, rows, cols, S, U, SxV.
            headerVersion = get<std::uint8_t>();
            if (headerVersion >= 1) drr = get<std::uint32_t>();
            if (headerVersion >= 2) throw std::runtime_error("height map present");
            Factor f;
            f.k = get<std::uint32_t>();
            f.scalarSize = get<std::uint8_t>();
            f.stride = get<std::uint32_t>();
            f.rows = get<std::uint32_t>();
            f.cols = get<std::uint32_t>();
            if (f.rows != images * 3 || f.cols != texels)
                throw std::runtime_error("FMF matrix sizes");
            readFactor(f);
            factors.push_back(f);
        } else {
            // 2.4: max components, colour model, mean, matrix; per channel the factor.
            get<std::uint32_t>();
            colorModel = get<std::int32_t>();
            for (int i = 0; i < 12; ++i) get<float>();
            for (int c = 0; c < 3; ++c) {
                Factor f;
                f.scalarSize = get<std::uint8_t>();
                f.k = f.stride = get<std::uint32_t>();
                f.rows = get<std::uint32_t>();
                f.cols = get<std::uint32_t>();
                if (f.rows != images || f.cols != texels)
                    throw std::runtime_error("DFMF matrix sizes");
                readFactor(f);
                factors.push_back(f);
            }
        }
        if (_pos != _b.size())
            throw std::runtime_error(std::to_string(_b.size() - _pos) + " trailing bytes");
    }

private:
    template <typename T>
    T get() {
        if (_pos + sizeof(T) > _b.size()) throw std::runtime_error("short file");
        T v;
        std::memcpy(&v, _b.data() + _pos, sizeof v);
        _pos += sizeof v;
        return v;
    }
    std::string raw(std::size_t n) {
        if (_pos + n > _b.size()) throw std::runtime_error("short file");
        std::string s = _b.substr(_pos, n);
        _pos += n;
        return s;
    }
    std::string chars(std::size_t n) {
        const std::string s = raw(n);
        return s.substr(0, s.find('\0'));
    }
    double scalar(int size) {
        if (size == 2) {
            Imath::half h;
            h.setBits(get<std::uint16_t>());
            return double(float(h));
        }
        if (size == 4) return double(get<float>());
        if (size == 8) return get<double>();
        throw std::runtime_error("scalar size " + std::to_string(size));
    }
    void readFactor(Factor& f) {
        for (std::uint32_t i = 0; i < f.stride; ++i) f.s.push_back(scalar(f.scalarSize));
        for (std::uint64_t i = 0; i < std::uint64_t(f.rows) * f.stride; ++i)
            f.u.push_back(scalar(f.scalarSize));
        for (std::uint64_t i = 0; i < std::uint64_t(f.cols) * f.stride; ++i)
            f.sxv.push_back(scalar(f.scalarSize));
    }

    const std::string& _b;
    std::size_t _pos = 0;
};

/** The value a file with `scalarSize` scalars stores for x. */
double stored(float x, int scalarSize) {
    return scalarSize == 2 ? double(float(Imath::half(x))) : double(x);
}

/** Directions (radians as stored) equal the set's (degrees), azimuths modulo 2 pi. */
void expectDirections(const std::vector<std::array<float, 2>>& file, const DirectionSet& set) {
    ASSERT_EQ(file.size(), set.size());
    for (std::size_t i = 0; i < set.size(); ++i) {
        EXPECT_NEAR(file[i][0], set[i].theta * kPi / 180.0, 1e-6) << i;
        const double dphi = std::remainder(file[i][1] - set[i].phi * kPi / 180.0, 2 * kPi);
        EXPECT_NEAR(dphi, 0.0, 1e-6) << i;
    }
}

/** The file holds exactly `f`'s factors (FMF: one, rows (view * lights + light) * 3 + c;
 *  texel rows from the top image row, as FactoredBtf keeps them). */
void expectFactorsEqual(const ParsedBtf& p, const FactoredBtf& f, int scalarSize) {
    ASSERT_EQ(p.factors.size(), f.factors.size());
    expectDirections(p.views, f.views);
    expectDirections(p.lights, f.lights);
    EXPECT_EQ(p.width, std::uint32_t(f.width));
    EXPECT_EQ(p.height, std::uint32_t(f.height));
    EXPECT_EQ(p.cosine, f.cosine ? 1u : 0u);
    for (std::size_t i = 0; i < f.factors.size(); ++i) {
        const BtfFactor& want = f.factors[i];
        const ParsedBtf::Factor& got = p.factors[i];
        EXPECT_EQ(got.scalarSize, scalarSize);
        ASSERT_EQ(got.k, std::uint32_t(want.U.cols()));
        ASSERT_EQ(got.stride, got.k);
        ASSERT_EQ(got.rows, std::uint32_t(want.U.rows()));
        ASSERT_EQ(got.cols, std::uint32_t(want.SxV.rows()));
        const int k = int(got.k);
        for (int j = 0; j < k; ++j)
            EXPECT_EQ(got.s[std::size_t(j)], stored(want.S[j], scalarSize)) << "S " << j;
        for (int r = 0; r < int(got.rows); ++r)
            for (int j = 0; j < k; ++j)
                ASSERT_EQ(got.u[std::size_t(r * k + j)], stored(want.U(r, j), scalarSize))
                    << "factor " << i << " U row " << r << " component " << j;
        for (int r = 0; r < int(got.cols); ++r)
            for (int j = 0; j < k; ++j)
                ASSERT_EQ(got.sxv[std::size_t(r * k + j)], stored(want.SxV(r, j), scalarSize))
                    << "factor " << i << " SxV row " << r << " component " << j;
    }
}

/** An FMF factorisation made by hand: values not exact in half (so half rounding shows). */
FactoredBtf handMadeFmf() {
    FactoredBtf f;
    f.model = FactorModel::Fmf;
    f.source = "hand-made";
    f.views = DirectionSet("v", {{0, 0}, {45, 200}, {60, 90}});
    f.lights = DirectionSet("l", {{0, 0}, {30, 300}, {50, 10}, {70, 180}});
    f.width = 5;
    f.height = 2;
    BtfFactor factor;
    const int k = 4;
    factor.U.resize(Eigen::Index(f.imageCount() * 3), k);
    factor.SxV.resize(Eigen::Index(f.texelCount()), k);
    factor.S.resize(k);
    for (Eigen::Index r = 0; r < factor.U.rows(); ++r)
        for (int j = 0; j < k; ++j) factor.U(r, j) = std::sin(0.37f * float(r) + 1.3f * float(j));
    for (Eigen::Index r = 0; r < factor.SxV.rows(); ++r)
        for (int j = 0; j < k; ++j)
            factor.SxV(r, j) = std::cos(0.71f * float(r) - 0.4f * float(j)) / float(j + 1);
    for (int j = 0; j < k; ++j) factor.S[j] = 10.0f / float(j + 1) + 0.1f;
    f.factors.push_back(factor);
    return f;
}

}  // namespace

TEST(Ubo2014Write, FactorsAsFmfReadByAnIndependentParser) {
    TempDir dir;
    const FactoredBtf f = handMadeFmf();
    Ubo2014Factors meta;
    meta.measurementSetup = "dome";
    meta.imageSensor = "sensor";
    meta.lightSource = "led";
    meta.ppmm = 7.5f;
    meta.rgbScale = {1.5f, 1.0f, 0.5f};
    meta.xml = "<x/>";
    for (int scalarSize : {2, 4}) {
        SCOPED_TRACE("scalar size " + std::to_string(scalarSize));
        const std::string path = dir.file("out" + std::to_string(scalarSize) + ".btf");
        writeFactorsAsUbo2014(f, path, scalarSize, &meta);
        const std::string bytes = readTextFile(path);
        std::unique_ptr<ParsedBtf> p;
        try {
            p = std::make_unique<ParsedBtf>(bytes);
        } catch (const std::exception& e) {
            FAIL() << e.what();
        }
        EXPECT_EQ(p->signature, "!FMF12FCE");
        EXPECT_EQ(p->metaVersion, 4u);
        EXPECT_EQ(p->metaSize, 291u + 4u);  // formats.md 2.2: 291 + XML length
        EXPECT_EQ(p->setup, "dome");
        EXPECT_EQ(p->sensor, "sensor");
        EXPECT_EQ(p->lamp, "led");
        EXPECT_EQ(p->ppmm, 7.5f);
        EXPECT_EQ(p->rgbScale[0], 1.5f);
        EXPECT_EQ(p->xml, "<x/>");
        EXPECT_EQ(p->channels, (std::vector<std::string>{"R", "G", "B"}));
        EXPECT_EQ(p->headerVersion, 1);
        EXPECT_EQ(p->drr, 0u);
        expectFactorsEqual(*p, f, scalarSize);
    }
    // Without meta data the text fields are empty, the file still complete.
    const std::string bare = dir.file("bare.btf");
    writeFactorsAsUbo2014(f, bare, 4);
    const ParsedBtf p(readTextFile(bare));
    EXPECT_EQ(p.setup, "");
    EXPECT_EQ(p.metaSize, 291u);
}

TEST(Ubo2014Write, RefusesWhatItCannotWrite) {
    TempDir dir;
    const std::string path = dir.file("x.btf");
    EXPECT_EQ(test::errorOf([&] { writeFactorsAsUbo2014(handMadeFmf(), path, 8); }),
              path + ": cannot write scalar size 8 (2 half or 4 float)");
    FactoredBtf broken = handMadeFmf();
    broken.factors[0].SxV.conservativeResize(3, Eigen::NoChange);
    EXPECT_EQ(test::errorOf([&] { writeFactorsAsUbo2014(broken, path, 4); }),
              "hand-made: inconsistent factor matrix sizes: U is 36x4, SxV 3x4");
    EXPECT_FALSE(std::filesystem::exists(path));
    EXPECT_FALSE(std::filesystem::exists(path + ".tmp" + std::to_string(getpid())));
}

TEST(Ubo2014Write, FittedFmfMaterialWritesExactlyItsFactors) {
    TempDir dir;
    SampleOptions sample;
    sample.width = 6;
    sample.height = 4;  // not square: a transposed SxV would show
    const MeasuredBtf btf = makeSampleBtf(sample);
    for (const char* storage : {"half", "float"}) {
        SCOPED_TRACE(storage);
        osg::ref_ptr<FmfMaterial> m = FmfMaterial::fit(
            btf, FitOptions::parse(std::string("components=5 storage=") + storage));
        const int scalarSize = m->storage() == MaterialTexture::Float ? 4 : 2;
        EXPECT_EQ(scalarSize, std::string(storage) == "float" ? 4 : 2);
        const std::string path = dir.file(std::string(storage) + ".btf");
        writeFactorsAsUbo2014(m->completeFactors(), path, scalarSize);
        std::unique_ptr<ParsedBtf> p;
        try {
            p = std::make_unique<ParsedBtf>(readTextFile(path));
        } catch (const std::exception& e) {
            FAIL() << e.what();
        }
        EXPECT_EQ(p->signature, "!FMF12FCE");
        EXPECT_EQ(p->headerVersion, 1);
        EXPECT_EQ(p->drr, 0u);
        EXPECT_EQ(p->cosine, 0u);  // the fitted values include the cosine, as measured
        ASSERT_EQ(p->factors.size(), 1u);
        EXPECT_EQ(p->factors[0].k, 5u);
        EXPECT_EQ(p->factors[0].rows, 81u * 81u * 3u);
        EXPECT_EQ(p->factors[0].cols, 24u);
        // Half storage: the material's factors are already rounded to half, so they are stored
        // exactly in either case.
        expectFactorsEqual(*p, m->completeFactors(), scalarSize);
        // The file's own formula (formats.md 2.6, FMF without DRR: U . SxV) at a measured pair
        // equals the material there; texel (x, y) from the bottom is file row height - 1 - y.
        const auto& f = p->factors[0];
        const std::size_t view = 40, light = 17, image = view * 81 + light;
        const int x = 4, y = 1, fileTexel = (4 - 1 - y) * 6 + x;
        const glm::vec3 want =
            m->evaluate(x, y, btf.views().vector(view), btf.lights().vector(light));
        for (int c = 0; c < 3; ++c) {
            double sum = 0;
            for (std::uint32_t k = 0; k < f.k; ++k)
                sum += f.u[(image * 3 + std::size_t(c)) * f.k + k] *
                       f.sxv[std::size_t(fileTexel) * f.k + k];
            EXPECT_NEAR(sum, want[c], 1e-5 * std::max(1.0f, std::abs(want[c]))) << c;
        }
    }
}

TEST(Ubo2014Write, BtfFitWritesAUbo2014FileOnlyForFmf) {
    TempDir dir;
    const std::string tool = test::builtTool("btf") + " --no-progress ";
    const std::string zip = dir.file("s.zip"), out = dir.file("out.btf");
    auto r = test::runCommand(tool + "sample --size 8 -o " + test::shellQuote(zip));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    r = test::runCommand(tool + "fit " + test::shellQuote(zip) + " -m lambert -o " +
                         test::shellQuote(out));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_NE(r.output.find("btf: error: " + out +
                            ": only method fmf writes a UBO2014 .btf file (its factors are the "
                            "format's); save lambert as .btfmat or .exr"),
              std::string::npos)
        << r.output;
    EXPECT_FALSE(std::filesystem::exists(out));

    r = test::runCommand(tool + "fit " + test::shellQuote(zip) + " -m fmf --components 4 -o " +
                         test::shellQuote(out));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("wrote " + out), std::string::npos) << r.output;
    try {
        const ParsedBtf p(readTextFile(out));
        EXPECT_EQ(p.signature, "!FMF12FCE");
        EXPECT_EQ(p.headerVersion, 1);
        EXPECT_EQ(p.drr, 0u);
        EXPECT_EQ(p.width, 8u);
        ASSERT_EQ(p.factors.size(), 1u);
        EXPECT_EQ(p.factors[0].k, 4u);
        EXPECT_EQ(p.factors[0].scalarSize, 2);  // fmf's default storage, half
        EXPECT_EQ(p.views.size(), 81u);
    } catch (const std::exception& e) {
        FAIL() << e.what();
    }
    // And it opens again as stored: `btf info` reads it from its header and factors.
    r = test::runCommand(tool + "info " + test::shellQuote(out));
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("factors:  FMF, rank 4"), std::string::npos) << r.output;
}

}  // namespace OSGBTF_TEST_FILE
