// UBO2014 .btf reader (DFMF, FMF) and the loadMeasuredBtf dispatcher.
#include <gtest/gtest.h>

#include <unistd.h>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <filesystem>
#include <functional>
#include <string>
#include <vector>

#include <Imath/half.h>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "loaders/LoadBtf.h"
#include "loaders/Ubo2014.h"
#include "tests/HandWrittenUbo2014.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using osgBTF::test::readTextFile;
using osgBTF::test::TempDir;
using osgBTF::test::writeTextFile;

using osgBTF::test::errorOf;

namespace {

constexpr int kW = 5, kH = 3;  // non-square catches transposes
constexpr double kPi = 3.14159265358979323846;

/** Exactly representable in half, float and double, so every scalar size stores it exactly. */
float exactValue(int i) {
    return float((i * 7) % 17 - 8) / 16.0f;
}

FactorMatrix filled(int rows, int cols, int seed) {
    FactorMatrix m(rows, cols);
    for (int r = 0; r < rows; ++r)
        for (int c = 0; c < cols; ++c) m(r, c) = exactValue(seed + r * 5 + c * 3);
    return m;
}

/** Light phi 270 is written as -90 degrees in radians, as btflib writes azimuths. */
DirectionSet lights() {
    return DirectionSet("l", {{0, 0}, {40, 270}, {60, 30}});
}
DirectionSet views() {
    return DirectionSet("v", {{0, 0}, {45, 180}});
}

Ubo2014Factors tinyDfmf(int scalarSize, int colorModel = 0) {
    Ubo2014Factors f;
    f.model = FactorModel::Dfmf;
    f.hasRotations = true;
    f.rotations.push_back({1, 0, 0, 0, 1, 0, 0, 0, 1});
    f.views = views();
    f.lights = lights();
    f.width = kW;
    f.height = kH;
    f.scalarSize = scalarSize;
    f.colorModel = colorModel;
    f.colorMean = {0.25f, 0.5f, -0.125f};
    f.colorMatrix = {0.5f, 0.25f, 0.125f, -0.25f, 1.0f, 0.5f, 0.75f, -0.5f, 0.25f};
    f.xml = "<meta/>";
    const int ks[3] = {2, 3, 1};  // components may differ per channel
    for (int c = 0; c < 3; ++c) {
        BtfFactor factor;
        factor.U = filled(int(views().size() * lights().size()), ks[c], 11 * c);
        factor.SxV = filled(kW * kH, ks[c], 5 + 13 * c);
        factor.S = Eigen::VectorXf::Ones(ks[c]);
        f.factors.push_back(factor);
    }
    return f;
}

Ubo2014Factors tinyFmf(bool extended, int headerVersion, bool drr) {
    Ubo2014Factors f;
    f.model = FactorModel::Fmf;
    f.extendedHeader = extended;
    f.headerVersion = headerVersion;
    f.dynamicRangeReduction = drr ? 1 : 0;
    f.views = views();
    f.lights = lights();
    f.width = kW;
    f.height = kH;
    f.scalarSize = 2;
    if (headerVersion >= 2) {
        f.heightMapWidth = 4;
        f.heightMapHeight = 2;
        f.heightMap = {0.5f, 1.0f, 1.5f, 2.0f, -0.5f, -1.0f, 0.25f, 0.125f};
    }
    BtfFactor factor;
    factor.U = filled(int(views().size() * lights().size() * 3), 3, 1);
    factor.SxV = filled(kW * kH, 3, 2);
    factor.S = Eigen::VectorXf::Ones(3);
    f.factors.push_back(factor);
    return f;
}

/** The raw factor product of the test's own factors, in file layout (row 0 = top). */
double product(const FactorMatrix& u, int uRow, const FactorMatrix& sxv, int texel) {
    double sum = 0;
    for (int k = 0; k < u.cols(); ++k) sum += double(u(uRow, k)) * double(sxv(texel, k));
    return sum;
}

/** Expected RGB computed here from formats.md 2.7, independently of the library's decoder. */
void expectedRgb(const Ubo2014Factors& f, int view, int light, int x, int yFile, double rgb[3]) {
    const int nL = int(f.lights.size()), lv = view * nL + light, texel = yFile * f.width + x;
    double v[3];
    for (int c = 0; c < 3; ++c)
        v[c] = f.model == FactorModel::Fmf
                   ? product(f.factors[0].U, lv * 3 + c, f.factors[0].SxV, texel)
                   : product(f.factors[c].U, lv, f.factors[c].SxV, texel);
    const double eps = 1e-5;
    auto yuv = [&](double y, double u, double w) {
        rgb[0] = y + 1.13983 * w;
        rgb[1] = y - 0.39465 * u - 0.5806 * w;
        rgb[2] = y + 2.03211 * u;
    };
    if (f.model == FactorModel::Fmf) {
        for (int c = 0; c < 3; ++c) rgb[c] = f.dynamicRangeReduction ? std::exp(v[c]) - eps : v[c];
    } else if (f.colorModel == 1) {
        yuv(v[0], v[1], v[2]);
    } else if (f.colorModel == 3) {
        for (int j = 0; j < 3; ++j) {
            rgb[j] = f.colorMean[j];
            for (int i = 0; i < 3; ++i) rgb[j] += v[i] * f.colorMatrix[i * 3 + j];
        }
    } else if (f.colorModel == 4) {
        rgb[0] = v[0] + v[1] - v[2];
        rgb[1] = v[0] + v[2];
        rgb[2] = v[0] - v[1] - v[2];
    } else if (f.colorModel == 11) {
        const double y = std::exp(v[0]) - eps;
        yuv(y, v[1] * (y + eps), v[2] * (y + eps));
    } else {
        for (int c = 0; c < 3; ++c) rgb[c] = v[c];
    }
    if (f.cosine) {
        const double z = std::cos(f.lights[light].theta * kPi / 180.0);
        for (int c = 0; c < 3; ++c) rgb[c] /= z;
    }
}

void expectDecodesToProduct(const Ubo2014Factors& f, const MeasuredBtf& btf, double tolerance) {
    ASSERT_EQ(btf.width(), kW);
    ASSERT_EQ(btf.height(), kH);
    ASSERT_EQ(btf.viewCount(), views().size());
    ASSERT_EQ(btf.lightCount(), lights().size());
    for (int v = 0; v < int(btf.viewCount()); ++v)
        for (int l = 0; l < int(btf.lightCount()); ++l)
            for (int yFile = 0; yFile < kH; ++yFile)
                for (int x = 0; x < kW; ++x) {
                    double rgb[3] = {0, 0, 0};
                    expectedRgb(f, v, l, x, yFile, rgb);
                    // File row 0 is the top row: MeasuredBtf row height-1.
                    const std::size_t texel = std::size_t(kH - 1 - yFile) * kW + x;
                    for (int c = 0; c < 3; ++c)
                        ASSERT_NEAR(btf.value(v, l, texel, c), rgb[c],
                                    tolerance * std::max(1.0, std::abs(rgb[c])))
                            << "view " << v << " light " << l << " x " << x << " file row " << yFile
                            << " channel " << c;
                }
}

/** Independent little-endian byte builder for hand-made (broken) headers. */
struct Bytes {
    std::string data;
    template <typename T>
    Bytes& put(T value) {
        data.append(reinterpret_cast<const char*>(&value), sizeof value);
        return *this;
    }
    Bytes& text(const std::string& s) {
        data += s;
        return *this;
    }
};

/** A DFMF file that stops right after channel 0's dimensions. */
std::string craftedDfmfHeader(std::uint32_t width, std::uint32_t height, std::uint32_t k,
                              std::uint32_t rows, std::uint32_t cols) {
    Bytes b;
    b.text("!DFMF08FCR");
    b.put(std::uint32_t(291)).put(std::uint32_t(4)).text(std::string(240, '\0'));
    b.put(1.0f).put(1.0f).put(1.0f).put(1.0f);      // ppmm, rgb scale
    b.put(std::uint32_t(0)).put(std::uint32_t(0));  // cosine, xml length
    b.put(std::uint32_t(3));                        // channels
    for (const char* n : {"R", "G", "B"}) b.put(std::uint32_t(1)).text(n);
    b.put(std::uint32_t(1)).put(0.0f).put(0.0f).put(std::uint32_t(1)).put(0.0f).put(0.0f);
    b.put(width).put(height).put(std::uint32_t(0));  // no rotations
    b.put(std::uint32_t(1)).put(std::int32_t(0));    // max components, colour model
    for (int i = 0; i < 12; ++i) b.put(0.0f);        // mean, matrix
    b.put(std::uint8_t(4)).put(k).put(rows).put(cols);
    return b.data;
}

}  // namespace

// ---------------------------------------------------------------------------------------------
// Failures.

TEST(Ubo2014Loader, UnknownSignatureShowsTheBytes) {
    TempDir dir;
    const std::string path = dir.file("weird.btf");
    writeTextFile(path, "!XYZW12345" + std::string(300, '\0'));
    const std::string message = errorOf([&] { readUbo2014(path); });
    EXPECT_NE(message.find(path + ": unknown signature \"!XYZW12345\""), std::string::npos)
        << message;
    EXPECT_NE(message.find("21 58 59 5a"), std::string::npos) << message;
}

TEST(Ubo2014Loader, PvfAndBdiAreRefusedByName) {
    TempDir dir;
    const std::string pvf = dir.file("pvf.btf"), bdi = dir.file("bdi.btf");
    writeTextFile(pvf, "!PVF06FCR" + std::string(300, '\0'));
    writeTextFile(bdi, "!BDIF06R2!" + std::string(300, '\0'));
    std::string message = errorOf([&] { loadUbo2014(pvf); });
    EXPECT_NE(message.find(pvf + ": PVF (per-view PCA) .btf files are not supported"),
              std::string::npos)
        << message;
    message = errorOf([&] { loadUbo2014(bdi); });
    EXPECT_NE(message.find(bdi + ": BDI (raw half-float images) .btf files are not supported"),
              std::string::npos)
        << message;
}

TEST(Ubo2014Loader, WrongSizeFieldIsAnError) {
    TempDir dir;
    const std::string path = dir.file("size.btf");
    writeUbo2014(tinyDfmf(4), path);
    std::string bytes = readTextFile(path);
    std::uint32_t size;
    std::memcpy(&size, bytes.data() + 10, 4);
    EXPECT_EQ(size, 291u + 7u);  // formats.md: 291 + XML length
    ++size;
    std::memcpy(bytes.data() + 10, &size, 4);
    writeTextFile(path, bytes);
    const std::string message = errorOf([&] { readUbo2014(path); });
    EXPECT_NE(message.find(path + ": meta-data Size field says 299 bytes but the meta-data block "
                                  "(version 4) holds 298"),
              std::string::npos)
        << message;
}

TEST(Ubo2014Loader, OneByteMissingIsAnError) {
    TempDir dir;
    const std::string path = dir.file("short.btf");
    writeUbo2014(tinyDfmf(2), path);
    fs::resize_file(path, fs::file_size(path) - 1);
    const std::string message = errorOf([&] { loadUbo2014(path); });
    EXPECT_NE(message.find(path + ": "), std::string::npos) << message;
    EXPECT_NE(message.find("unexpected end of file while reading channel 2 factors"),
              std::string::npos)
        << message;
    // Reading an FMF file cut inside its last matrix names the field being read.
    const std::string fmf = dir.file("short-fmf.btf");
    writeUbo2014(tinyFmf(true, 2, true), fmf);
    std::string bytes = readTextFile(fmf);
    bytes.pop_back();
    writeTextFile(fmf, bytes);
    const std::string fmfMessage = errorOf([&] { readUbo2014(fmf); });
    EXPECT_NE(fmfMessage.find(fmf + ": unexpected end of file while reading factors"),
              std::string::npos)
        << fmfMessage;
}

TEST(Ubo2014Loader, OneByteMissingInTheHeaderNamesTheField) {
    TempDir dir;
    const std::string path = dir.file("cut.btf");
    writeUbo2014(tinyDfmf(4), path);
    // Signature (10) + meta block (298) + directions (4 + 2 views * (8 + 4 + 3 lights * 8)), then
    // 2 of the 4 bytes of the width.
    fs::resize_file(path, 10 + 298 + 4 + 2 * 36 + 2);
    const std::string message = errorOf([&] { readUbo2014(path); });
    EXPECT_NE(message.find(path + ": unexpected end of file while reading width"),
              std::string::npos)
        << message;
}

TEST(Ubo2014Loader, OneTrailingByteIsAnError) {
    TempDir dir;
    const std::string path = dir.file("long.btf");
    writeUbo2014(tinyDfmf(4), path);
    writeTextFile(path, readTextFile(path) + "x");
    const std::string message = errorOf([&] { loadUbo2014(path); });
    EXPECT_NE(message.find(path + ": 1 unexpected trailing bytes"), std::string::npos) << message;
}

TEST(Ubo2014Loader, AbsurdDimensionsAreRefusedByTheMemoryGuard) {
    TempDir dir;
    const std::string path = dir.file("huge.btf");
    writeTextFile(path, craftedDfmfHeader(1000000, 1000, 4, 1, 1000000000u));
    const std::uint64_t saved = memoryLimit();
    setMemoryLimit(std::uint64_t(1) << 20);
    const std::string message = errorOf([&] { readUbo2014(path); });
    setMemoryLimit(saved);
    EXPECT_NE(message.find(path + ": channel 0 factors: needs"), std::string::npos) << message;
    EXPECT_NE(message.find("memory limit"), std::string::npos) << message;
}

TEST(Ubo2014Loader, HeaderClaimingMoreThanTheFileHoldsIsRefusedBeforeAllocating) {
    TempDir dir;
    const std::string path = dir.file("claims.btf");
    writeTextFile(path, craftedDfmfHeader(1000, 1000, 4, 1, 1000000u));
    const std::string message = errorOf([&] { readUbo2014(path); });
    EXPECT_NE(message.find(path + ": unexpected end of file while reading channel 0 factors: the "
                                  "header announces 16000032 bytes but only 0 remain"),
              std::string::npos)
        << message;
}

TEST(Ubo2014Loader, WrongMatrixRowCountIsAnError) {
    TempDir dir;
    const std::string path = dir.file("rows.btf");
    writeTextFile(path, craftedDfmfHeader(2, 3, 1, 5, 6));
    const std::string message = errorOf([&] { readUbo2014(path); });
    EXPECT_NE(message.find(path + ": channel 0: U has 5 rows and SxV 6; expected views*lights = 1 "
                                  "and width*height = 6"),
              std::string::npos)
        << message;
}

TEST(Ubo2014Loader, UnsupportedColourModelAndScalarSizeAreRefused) {
    TempDir dir;
    const std::string lab = dir.file("lab.btf");
    writeUbo2014(tinyDfmf(4, 2), lab);
    std::string message = errorOf([&] { readUbo2014(lab); });
    EXPECT_NE(message.find(lab + ": DFMF colour model 2 is not supported"), std::string::npos)
        << message;
    const std::string odd = dir.file("odd.btf");
    std::string bytes = craftedDfmfHeader(2, 3, 1, 1, 6);
    bytes[bytes.size() - 13] = 3;  // the scalar size byte
    writeTextFile(odd, bytes);
    message = errorOf([&] { readUbo2014(odd); });
    EXPECT_NE(message.find(odd + ": channel 0: scalar size 3 is not 2 (half), 4 (float) or 8"),
              std::string::npos)
        << message;
}

// ---------------------------------------------------------------------------------------------
// Decoding.

TEST(Ubo2014Loader, DfmfFloatDecodesToTheFactorProduct) {
    TempDir dir;
    const std::string path = dir.file("f32.btf");
    const Ubo2014Factors f = tinyDfmf(4);
    writeUbo2014(f, path);
    const Ubo2014Factors read = readUbo2014(path);
    EXPECT_EQ(read.signature, "!DFMF08FCR");
    EXPECT_EQ(read.xml, "<meta/>");
    ASSERT_EQ(read.rotations.size(), 1u);
    EXPECT_EQ(read.factors[1].U.cols(), 3);
    const MeasuredBtf btf = loadUbo2014(path);
    EXPECT_EQ(btf.source, path);
    expectDecodesToProduct(f, btf, 1e-6);
}

TEST(Ubo2014Loader, DfmfHalfAndDoubleDecodeToTheFactorProduct) {
    TempDir dir;
    for (int scalarSize : {2, 8}) {
        const std::string path = dir.file("s" + std::to_string(scalarSize) + ".btf");
        const Ubo2014Factors f = tinyDfmf(scalarSize);
        writeUbo2014(f, path);
        EXPECT_EQ(fs::file_size(path) > 0, true);
        expectDecodesToProduct(f, loadUbo2014(path), 1e-6);
    }
}

TEST(Ubo2014Loader, DirectionsAreDegreesWithWrappedAzimuth) {
    TempDir dir;
    const std::string path = dir.file("dirs.btf");
    writeUbo2014(tinyDfmf(4), path);
    const std::string bytes = readTextFile(path);
    // Light 1 of view 0: after signature, meta, view count, view theta/phi, light count, light 0.
    float phiRadians;
    std::memcpy(&phiRadians, bytes.data() + 10 + 298 + 4 + 8 + 4 + 8 + 4, 4);
    EXPECT_NEAR(phiRadians, -kPi / 2, 1e-6);  // stored like btflib, in (-pi, pi]
    const Ubo2014Factors f = readUbo2014(path);
    EXPECT_EQ(f.lights[1].theta, 40.0f);
    EXPECT_EQ(f.lights[1].phi, 270.0f);
    EXPECT_EQ(f.views[1].theta, 45.0f);
    EXPECT_EQ(f.views[1].phi, 180.0f);
}

TEST(Ubo2014Loader, DfmfColourModelsAndCosine) {
    TempDir dir;
    for (int model : {1, 3, 4, 11}) {
        for (bool cosine : {false, true}) {
            Ubo2014Factors f = tinyDfmf(4, model);
            f.cosine = cosine;
            const std::string path =
                dir.file("m" + std::to_string(model) + (cosine ? "c" : "") + ".btf");
            writeUbo2014(f, path);
            SCOPED_TRACE("colour model " + std::to_string(model) + (cosine ? " cosine" : ""));
            expectDecodesToProduct(f, loadUbo2014(path), 1e-5);
        }
    }
}

TEST(Ubo2014Loader, FmfWithDynamicRangeReductionAndHeightMap) {
    TempDir dir;
    const std::string path = dir.file("fmf.btf");
    const Ubo2014Factors f = tinyFmf(true, 2, true);
    writeUbo2014(f, path);
    const Ubo2014Factors read = readUbo2014(path);
    EXPECT_EQ(read.signature, "!FMF12FCE");
    EXPECT_EQ(read.model, FactorModel::Fmf);
    EXPECT_TRUE(read.drr());
    ASSERT_EQ(read.heightMapWidth, 4);
    ASSERT_EQ(read.heightMapHeight, 2);
    EXPECT_EQ(read.heightMap, f.heightMap);
    ASSERT_EQ(read.factors.size(), 1u);
    EXPECT_EQ(read.factors[0].U.rows(), int(views().size() * lights().size() * 3));
    expectDecodesToProduct(f, decodeUbo2014(read), 1e-5);
}

TEST(Ubo2014Loader, FmfWithoutExtendedHeaderAndOldMetaVersion) {
    TempDir dir;
    const std::string path = dir.file("fmf06.btf");
    Ubo2014Factors f = tinyFmf(false, 0, false);
    f.metaVersion = 1;  // no cosine flag, XML or channel names
    f.hasRotations = true;
    writeUbo2014(f, path);
    const Ubo2014Factors read = readUbo2014(path);
    EXPECT_EQ(read.signature, "!FMF06FCR");
    EXPECT_FALSE(read.drr());
    EXPECT_EQ(read.channelNames.size(), 3u);
    expectDecodesToProduct(f, loadMeasuredBtf(path), 1e-6);
}

TEST(Ubo2014Loader, HalfStorage) {
    TempDir dir;
    const std::string path = dir.file("half.btf");
    const Ubo2014Factors f = tinyDfmf(2);
    writeUbo2014(f, path);
    LoadOptions options;
    options.storage = Storage::Half;
    const MeasuredBtf btf = loadUbo2014(path, options);
    EXPECT_EQ(btf.storage(), Storage::Half);
    expectDecodesToProduct(f, btf, 1e-3);
}

// ---------------------------------------------------------------------------------------------
// Dispatcher.

TEST(LoaderDispatch, MissingFile) {
    TempDir dir;
    const std::string path = dir.file("absent.btf");
    EXPECT_EQ(errorOf([&] { loadMeasuredBtf(path); }), path + ": no such file");
}

TEST(LoaderDispatch, EmptyFile) {
    TempDir dir;
    for (const char* name : {"empty.btf", "empty.zip", "empty.dat"}) {
        const std::string path = dir.file(name);
        writeTextFile(path, "");
        EXPECT_EQ(errorOf([&] { loadMeasuredBtf(path); }), path + ": file is empty");
    }
}

TEST(LoaderDispatch, UnreadableFile) {
    TempDir dir;
    // Tests may run as root, where chmod cannot make a file unreadable; a folder named like a
    // file cannot be opened as one by anybody.
    const std::string folder = dir.file("x.btf");
    fs::create_directory(folder);
    EXPECT_EQ(errorOf([&] { loadMeasuredBtf(folder); }), folder + ": cannot open: Is a directory");
    if (geteuid() != 0) {
        const std::string path = dir.file("locked.btf");
        writeUbo2014(tinyDfmf(4), path);
        fs::permissions(path, fs::perms::none);
        EXPECT_EQ(errorOf([&] { loadMeasuredBtf(path); }),
                  path + ": cannot open: Permission denied");
    }
}

TEST(LoaderDispatch, UnknownFileType) {
    TempDir dir;
    const std::string path = dir.file("notes.txt");
    writeTextFile(path, "hello");
    const std::string message = errorOf([&] { loadMeasuredBtf(path); });
    EXPECT_NE(message.find(path + ": unknown file type"), std::string::npos) << message;
}

TEST(LoaderDispatch, BtfByContentAndSource) {
    TempDir dir;
    const std::string path = dir.file("factors.bin");
    const Ubo2014Factors f = tinyDfmf(4);
    writeUbo2014(f, path);
    const MeasuredBtf btf = loadMeasuredBtf(path);
    EXPECT_EQ(btf.source, path);
    expectDecodesToProduct(f, btf, 1e-6);
}

// ---------------------------------------------------------------------------------------------
// Files written byte by byte from formats.md (tests/HandWrittenUbo2014.h), not by writeUbo2014:
// what another implementation of the format writes must read the same.

namespace {

/** decodeUbo2014 of the hand-written file equals the format's formula at every value. Tolerance:
 *  float factor sums and expf against double, relative 1e-5 (the values are O(1) to O(10)). */
void expectHandWrittenDecode(const test::HandWrittenBtf& f, const MeasuredBtf& btf) {
    ASSERT_EQ(btf.width(), f.width);
    ASSERT_EQ(btf.height(), f.height);
    ASSERT_EQ(btf.viewCount(), f.views.size());
    ASSERT_EQ(btf.lightCount(), f.lights.size());
    double largest = 0;
    for (int v = 0; v < int(f.views.size()); ++v)
        for (int l = 0; l < int(f.lights.size()); ++l)
            for (int yFile = 0; yFile < f.height; ++yFile)
                for (int x = 0; x < f.width; ++x) {
                    const auto rgb = f.value(v, l, x, yFile);
                    const std::size_t texel = std::size_t(f.height - 1 - yFile) * f.width + x;
                    for (int c = 0; c < 3; ++c) {
                        largest = std::max(largest, std::abs(rgb[std::size_t(c)]));
                        ASSERT_NEAR(btf.value(v, l, texel, c), rgb[std::size_t(c)],
                                    1e-5 * std::max(1.0, std::abs(rgb[std::size_t(c)])))
                            << "view " << v << " light " << l << " x " << x << " file row " << yFile
                            << " channel " << c;
                    }
                }
    EXPECT_GT(largest, 0.5);  // the formula was not trivially zero
}

void expectHandWrittenDirections(const test::HandWrittenBtf& f, const Ubo2014Factors& read) {
    ASSERT_EQ(read.views.size(), f.views.size());
    ASSERT_EQ(read.lights.size(), f.lights.size());
    for (std::size_t i = 0; i < f.views.size(); ++i) {
        EXPECT_NEAR(read.views[i].theta, f.views[i][0], 1e-3) << "view " << i;
        EXPECT_NEAR(read.views[i].phi, f.views[i][1], 1e-3) << "view " << i;
    }
    for (std::size_t i = 0; i < f.lights.size(); ++i) {
        EXPECT_NEAR(read.lights[i].theta, f.lights[i][0], 1e-3) << "light " << i;
        EXPECT_NEAR(read.lights[i].phi, f.lights[i][1], 1e-3) << "light " << i;
    }
}

}  // namespace

TEST(Ubo2014HandWritten, DfmfColourModel11WithPerChannelRanks) {
    TempDir dir;
    const test::HandWrittenBtf f = test::handWrittenDfmf11();
    const std::string path = dir.file("dfmf11.btf");
    writeTextFile(path, f.bytes);
    const Ubo2014Factors read = readUbo2014(path);
    EXPECT_EQ(read.signature, "!DFMF08FCR");
    EXPECT_EQ(read.model, FactorModel::Dfmf);
    EXPECT_EQ(read.colorModel, 11);
    EXPECT_EQ(read.measurementSetup, "hand-written test dome");
    EXPECT_EQ(read.xml, "<btf/>");
    EXPECT_EQ(read.rotations.size(), 2u);
    EXPECT_FALSE(read.cosine);
    EXPECT_EQ(read.scalarSize, 4);
    ASSERT_EQ(read.factors.size(), 3u);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(read.components(c), f.ranks[std::size_t(c)]);
    expectHandWrittenDirections(f, read);
    expectHandWrittenDecode(f, decodeUbo2014(read));
    // value() (what the native material's CPU path builds on) is the same formula.
    for (int v : {0, 4})
        for (int l : {1, 9}) {
            const auto rgb = f.value(v, l, 3, 0);  // file row 0 = the top row, y = height - 1
            const glm::vec3 got = read.value(std::size_t(v), std::size_t(l), 3, f.height - 1);
            for (int c = 0; c < 3; ++c)
                EXPECT_NEAR(got[c], rgb[std::size_t(c)], 1e-5 * std::max(1.0, std::abs(rgb[c])));
        }
}

TEST(Ubo2014HandWritten, FmfWithDynamicRangeReductionAndCosine) {
    TempDir dir;
    const test::HandWrittenBtf f = test::handWrittenFmfDrrCosine();
    const std::string path = dir.file("fmf-drr-cos.btf");
    writeTextFile(path, f.bytes);
    const Ubo2014Factors read = readUbo2014(path);
    EXPECT_EQ(read.signature, "!FMF12FCE");
    EXPECT_EQ(read.model, FactorModel::Fmf);
    EXPECT_EQ(read.headerVersion, 1);
    EXPECT_TRUE(read.drr());
    EXPECT_TRUE(read.cosine);
    EXPECT_EQ(read.scalarSize, 2);
    EXPECT_EQ(read.heightMapWidth, 0);
    EXPECT_EQ(read.components(0), 3);
    expectHandWrittenDirections(f, read);
    expectHandWrittenDecode(f, decodeUbo2014(read));
    // Through the dispatcher, half storage: ~3 significant digits.
    LoadOptions half;
    half.storage = Storage::Half;
    const MeasuredBtf btf = loadMeasuredBtf(path, half);
    const auto rgb = f.value(2, 6, 1, 4);
    EXPECT_NEAR(btf.value(2, 6, 1, 1), rgb[1], 1e-3 * std::abs(rgb[1]));  // file row 4 = y 0
}

TEST(Ubo2014HandWritten, BadFilesAreRefusedWithTheirProblem) {
    TempDir dir;
    const test::HandWrittenBtf dfmf = test::handWrittenDfmf11();
    const test::HandWrittenBtf fmf = test::handWrittenFmfDrrCosine();
    const std::string path = dir.file("bad.btf");
    auto messageFor = [&](const std::string& bytes) {
        writeTextFile(path, bytes);
        return errorOf([&] { readUbo2014(path); });
    };
    // Short: one byte missing at the end; the guard sees it before reading the matrices.
    std::string message = messageFor(fmf.bytes.substr(0, fmf.bytes.size() - 1));
    EXPECT_NE(
        message.find(path +
                     ": unexpected end of file while reading factors: the header "
                     "announces " +
                     std::to_string(fmf.bytes.size() - std::size_t(fmf.factorHeaderOffset) - 17) +
                     " bytes but only " +
                     std::to_string(fmf.bytes.size() - std::size_t(fmf.factorHeaderOffset) - 18) +
                     " remain"),
        std::string::npos)
        << message;
    // Long: a trailing byte.
    message = messageFor(dfmf.bytes + '\0');
    EXPECT_EQ(message, path + ": 1 unexpected trailing bytes after the last factor matrix");
    // Wrong sizes: channel 0's U row count one too many.
    std::string bytes = dfmf.bytes;
    std::uint32_t rows;
    std::memcpy(&rows, bytes.data() + dfmf.factorHeaderOffset + 5, 4);
    EXPECT_EQ(rows, 70u);  // 7 views x 10 lights
    ++rows;
    std::memcpy(bytes.data() + dfmf.factorHeaderOffset + 5, &rows, 4);
    message = messageFor(bytes);
    EXPECT_EQ(message, path +
                           ": channel 0: U has 71 rows and SxV 12; expected views*lights = 70 "
                           "and width*height = 12");
    // FMF rows must count the colour channels: views*lights*3.
    bytes = fmf.bytes;
    std::uint32_t fmfRows = 70;  // views*lights, as a DFMF channel would have
    std::memcpy(bytes.data() + fmf.factorHeaderOffset + 9, &fmfRows, 4);
    message = messageFor(bytes);
    EXPECT_EQ(message, path +
                           ": U has 70 rows and SxV 15; expected views*lights*3 = 210 and "
                           "width*height = 15");
    // Unknown colour model.
    bytes = dfmf.bytes;
    const std::int32_t model = 7;
    std::memcpy(bytes.data() + dfmf.colorModelOffset, &model, 4);
    message = messageFor(bytes);
    EXPECT_EQ(message, path +
                           ": DFMF colour model 7 is not supported (supported: 0 RGB, 1 YUV, "
                           "3 PCA, 4 YCoCg, 11 exp-YUV)");
}

TEST(Ubo2014HandWritten, HeaderOnlyReadSkipsTheMatricesButChecksTheirSizes) {
    TempDir dir;
    const test::HandWrittenBtf f = test::handWrittenDfmf11();
    const std::string path = dir.file("dfmf11.btf");
    writeTextFile(path, f.bytes);
    LoadOptions header;
    header.headerOnly = true;
    const Ubo2014Factors read = readUbo2014(path, header);
    ASSERT_EQ(read.factors.size(), 3u);
    for (int c = 0; c < 3; ++c) {
        EXPECT_EQ(read.components(c), f.ranks[std::size_t(c)]);
        EXPECT_EQ(read.factors[std::size_t(c)].U.rows(), 0);
        EXPECT_EQ(read.factors[std::size_t(c)].S.size(), f.ranks[std::size_t(c)]);
    }
    EXPECT_EQ(read.colorModel, 11);
    // A file one byte short or long is refused as by the full read.
    writeTextFile(path, f.bytes.substr(0, f.bytes.size() - 1));
    EXPECT_EQ(errorOf([&] {
                  readUbo2014(path, header);
              }).rfind(path + ": unexpected end of file while reading channel 2 factors", 0),
              0u);
    writeTextFile(path, f.bytes + "x");
    EXPECT_EQ(errorOf([&] { readUbo2014(path, header); }),
              path + ": 1 unexpected trailing bytes after the last factor matrix");
}

}  // namespace OSGBTF_TEST_FILE
