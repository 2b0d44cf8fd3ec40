// relight's web layout as osgBTF writes it (materials/RelightLayoutWriter.h): the quantisation
// against values worked out by hand from relight's formulas (docs/formats.md 8.4), a tiny
// material's info.json and plane bytes checked by hand, the deep-zoom pyramid complete, each
// method's material read back within the bound the 8-bit planes allow, and the failures with
// their exact messages.
//
// The round-trip bound. A plane value v in [min, max] is stored as byte b = trunc(255 (v - min) /
// (max - min)) and read back as min + b (max - min) / 255: at most one step s = (max - min) / 255
// below v (truncation). The JPEG (quality 100, 4:4:4 chroma) changes a byte by at most J; J is
// measured here on the written planes against the bytes the quantisation gives, and must stay
// within 5 (libjpeg's rounding of the colour transform and of the DCT at quality 100: 4 measured
// on these planes; 4:2:0 chroma or a lower quality fails). So |read - v| <= (1 + J) s, plus
// half-float storage of the source (a relative 2^-11). With --range-quantile 1 no value clamps;
// relight's default 0.995 clamps the outer half percent, counted in the writer's report.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>
#include <set>
#include <string>
#include <vector>

#include <nlohmann/json.hpp>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/ImageCodecs.h"
#include "core/MeasuredBtf.h"
#include "loaders/LoadBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/RelightFolder.h"
#include "materials/RelightLayoutWriter.h"
#include "materials/hsh/Hsh.h"
#include "materials/hsh/RtiFile.h"
#include "materials/ptm/Ptm.h"
#include "materials/ptm/PtmFile.h"
#include "materials/rbf/Rbf.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::errorOf;
using osgBTF::test::TempDir;
namespace fs = std::filesystem;

namespace {

/** An 8-bit RGB image file's bytes, rows as stored (top down). */
std::vector<unsigned char> decodeBytes(const std::string& path, int& width, int& height) {
    std::string error;
    const std::unique_ptr<ImageReader> reader = imageCodecs().openFile(path, 0, error);
    EXPECT_TRUE(reader) << path << ": " << error;
    if (!reader) return {};
    width = reader->header().width;
    height = reader->header().height;
    EXPECT_EQ(reader->header().channels, 3) << path;
    std::vector<unsigned char> bytes(std::size_t(width) * std::size_t(height) * 3);
    EXPECT_TRUE(reader->readBytes(bytes.data())) << path;
    return bytes;
}

nlohmann::json readJson(const std::string& path) {
    return nlohmann::json::parse(readWholeFile(path));
}

const MeasuredBtf& capture() {
    static const MeasuredBtf btf = loadMeasuredBtf(test::sourceDir() + "/tests/data/rti-icon-64");
    return btf;
}

RelightWriteOptions exact() {
    RelightWriteOptions o;
    o.quality = 100;
    o.rangeQuantile = 1.0;
    o.layout = RelightWriteOptions::Layout::Image;
    return o;
}

/** The largest |decoded - intended| byte of every plane JPEG written for `model`'s quantisation,
 *  and each plane's step, from info.json. */
struct PlaneCheck {
    int jpegError = 0;
    std::vector<double> step;
};

PlaneCheck checkPlanes(const std::string& folder, const RelightModel& model) {
    const nlohmann::json info = readJson(folder + "/info.json");
    PlaneCheck check;
    const std::size_t texels = std::size_t(model.width) * std::size_t(model.height);
    for (int j = 0; j < (model.planeCount + 2) / 3; ++j) {
        int w = 0, h = 0;
        const std::vector<unsigned char> bytes =
            decodeBytes(folder + "/plane_" + std::to_string(j) + ".jpg", w, h);
        EXPECT_EQ(w, model.width);
        EXPECT_EQ(h, model.height);
        for (int c = 0; c < 3 && 3 * j + c < model.planeCount; ++c) {
            const int m = 3 * j + c;
            RelightQuantisation q;
            q.scale = info["materials"][0]["scale"][std::size_t(m)].get<float>();
            q.bias = info["materials"][0]["bias"][std::size_t(m)].get<float>();
            check.step.push_back(double(q.scale) / 255.0);
            for (int y = 0; y < model.height; ++y)
                for (int x = 0; x < model.width; ++x) {
                    // Rows: the JPEG's top is the material's top row (y = height - 1).
                    const float v =
                        model.planes[std::size_t(m) * texels +
                                     std::size_t(model.height - 1 - y) * std::size_t(model.width) +
                                     std::size_t(x)];
                    const int want = q.quantise(v);
                    const int got = bytes[(std::size_t(y) * std::size_t(w) + std::size_t(x)) * 3 +
                                          std::size_t(c)];
                    check.jpegError = std::max(check.jpegError, std::abs(got - want));
                }
        }
    }
    return check;
}

}  // namespace

// ---- failures first ----------------------------------------------------------------------------

TEST(RelightWriter, RefusesWhatTheLayoutCannotHold) {
    TempDir dir;
    const osg::ref_ptr<Material> lambert = findMethod("lambert").fit(capture(), FitOptions());
    EXPECT_EQ(errorOf([&] { writeRelightLayout(*lambert, dir.file("web/info.json")); }),
              dir.file("web/info.json") +
                  ": relight's web layout holds materials of hsh, ptm, rbf, not lambert");
    EXPECT_FALSE(fs::exists(dir.path() / "web" / "info.json"));
    const osg::ref_ptr<Material> ptm = findMethod("ptm").fit(capture(), FitOptions());
    EXPECT_EQ(errorOf([&] { writeRelightLayout(*ptm, dir.file("web/relight.json")); }),
              dir.file("web/relight.json") +
                  ": relight's web layout is a folder named by its info.json (DIR/info.json)");
    RelightWriteOptions bad;
    bad.quality = 0;
    EXPECT_EQ(errorOf([&] { writeRelightLayout(*ptm, dir.file("web/info.json"), bad); }),
              dir.file("web/info.json") + ": JPEG quality 0 is not 1..100");
    bad = RelightWriteOptions();
    bad.tileSize = 8;
    EXPECT_EQ(errorOf([&] { writeRelightLayout(*ptm, dir.file("web/info.json"), bad); }),
              dir.file("web/info.json") +
                  ": tile size 8 with overlap 0 (tiles of 16..4096 pixels, overlap at most half "
                  "a tile)");
    // A per-view model: nothing is left behind, not even the staging folder.
    const osg::ref_ptr<PtmMaterial> perView = PtmMaterial::create(
        2, 2, DirectionSet("views", {{0, 0}, {30, 0}, {30, 120}}), capture().lights(),
        PtmMaterial::Shape{false, true, MaterialTexture::Float});
    EXPECT_EQ(errorOf([&] { writeRelightLayout(*perView, dir.file("web/info.json")); }),
              dir.file("web/info.json") +
                  ": relight's web layout holds one view; this ptm material has one per view "
                  "(views=all): fit with views=front");
    EXPECT_TRUE(!fs::exists(dir.path() / "web") || fs::is_empty(dir.path() / "web"));
}

TEST(RelightWriter, AMipMappedMaterialIsRefusedWithWhatToDo) {
    TempDir dir;
    const std::string out = dir.file("m.btfmat");
    const test::CommandResult fit = test::runCommand(
        test::shellQuote(test::builtTool("btf")) + " --no-progress fit " +
        test::shellQuote(test::sourceDir() + "/tests/data/rti-icon-64") + " -m hsh -o " + out);
    ASSERT_EQ(fit.exitCode, 0) << fit.output;
    const osg::ref_ptr<Material> mip = loadMaterial(out);
    EXPECT_EQ(errorOf([&] { writeRelightLayout(*mip, dir.file("web/info.json")); }),
              dir.file("web/info.json") +
                  ": relight's web layout has no mip levels: fit with --no-mipmap");
}

TEST(RelightReader, DeepZoomFailuresNameTheFileAndTheProblem) {
    TempDir dir;
    const osg::ref_ptr<Material> hsh =
        findMethod("hsh").fit(capture(), FitOptions::parse("order=2"));
    RelightWriteOptions o;
    o.layout = RelightWriteOptions::Layout::DeepZoom;
    o.tileSize = 32;
    const std::string info = dir.file("dz/info.json");
    writeRelightLayout(*hsh, info, o);
    const std::string tile = dir.file("dz/plane_2_files/1/1_0.jpg");
    ASSERT_TRUE(fs::exists(tile));
    fs::remove(tile);
    EXPECT_EQ(errorOf([&] { loadMaterial(info); }),
              tile + ": no such file (tile 1,0 of level 1, the full size of " +
                  dir.file("dz/plane_2.dzi") + ")");
    test::writeTextFile(dir.file("dz/plane_1.dzi"),
                        "<?xml version=\"1.0\"?><Image TileSize=\"32\" Overlap=\"0\" "
                        "Format=\"jpg\"><Size Width=\"60\" Height=\"64\"/></Image>");
    EXPECT_EQ(errorOf([&] { loadMaterial(info); }),
              dir.file("dz/plane_1.dzi") + ": Size is 60x64, info.json gives 64x64");
    test::writeTextFile(dir.file("dz/plane_0.dzi"),
                        "<Image TileSize=\"32\" Overlap=\"32\" Format=\"jpg\"><Size Width=\"64\" "
                        "Height=\"64\"/></Image>");
    EXPECT_EQ(errorOf([&] { loadMaterial(info); }),
              dir.file("dz/plane_0.dzi") +
                  ": TileSize and Overlap are not integers with 1 <= TileSize <= 8192 and 0 <= "
                  "Overlap < TileSize");
    test::writeTextFile(dir.file("dz/plane_0.dzi"),
                        "<Image TileSize=\"32\" Overlap=\"0\" Format=\"png\"><Size Width=\"64\" "
                        "Height=\"64\"/></Image>");
    EXPECT_EQ(errorOf([&] { loadMaterial(info); }),
              dir.file("dz/plane_0.dzi") + ": Format is not \"jpg\" (tiles in JPEG are read)");
}

// ---- quantisation, by hand ---------------------------------------------------------------------

TEST(RelightWriter, RangeAndBytesFollowRelightsFormulas) {
    // Twenty values k / 20, quantile 0.85: indices trunc(0.075 x 20) = trunc(1.5) = 1 and
    // trunc(0.925 x 20) = trunc(18.5) = 18, so min 0.05, max 0.9, scale 0.85, bias -0.05 / 0.85
    // = -1 / 17.
    std::vector<float> values;
    for (int k = 0; k < 20; ++k) values.push_back(float((k * 7) % 20) / 20.0f);  // shuffled
    const RelightQuantisation q = relightRange(values, 0.85);
    EXPECT_FLOAT_EQ(q.scale, 0.85f);
    EXPECT_FLOAT_EQ(q.bias, -1.0f / 17.0f);
    // 255 (0.523 - 0.05) / 0.85 = 141.9 -> 141 (truncated, as relight's int conversion; rounding
    // would give 142).
    EXPECT_EQ(q.quantise(0.523f), 141);
    EXPECT_EQ(q.quantise(0.0f), 0);     // below min: clamped
    EXPECT_EQ(q.quantise(0.95f), 255);  // above max: clamped
    EXPECT_GE(q.quantise(0.9f), 254);   // 255 exactly, or just below in float
    // Quantile 1: the whole range. A constant plane: relight's max = min + 1e-6 / 255 would
    // vanish in float beside 0.25; the step is 1e-5 x 0.25 instead, and 0.25 reads back.
    std::vector<float> constant(5, 0.25f);
    const RelightQuantisation c = relightRange(constant, 1.0);
    EXPECT_NEAR(c.scale, 2.5e-6f, 3e-8f);  // the float spacing at 0.25
    EXPECT_EQ(c.quantise(0.25f), 0);
    EXPECT_NEAR((0.0 - double(c.bias)) * double(c.scale), 0.25, 1e-7);
    std::vector<float> zeros(3, 0.0f);
    EXPECT_NEAR(relightRange(zeros, 1.0).scale, 1e-6f / 255.0f, 1e-12f);
    // relight's deep-zoom levels: halving with truncation until one tile holds the level.
    EXPECT_EQ(deepZoomLevels(64, 64, 32), (std::vector<std::pair<int, int>>{{32, 32}, {64, 64}}));
    EXPECT_EQ(deepZoomLevels(600, 300, 256),
              (std::vector<std::pair<int, int>>{{150, 75}, {300, 150}, {600, 300}}));
    EXPECT_EQ(deepZoomLevels(5, 3, 2), (std::vector<std::pair<int, int>>{{2, 1}, {5, 3}}));
    EXPECT_EQ(deepZoomLevels(200, 100, 256), (std::vector<std::pair<int, int>>{{200, 100}}));
}

TEST(RelightWriter, ATinyHshMaterialsInfoAndPlanesByHand) {
    // 1 x 3 texels (a column), order 2: 4 terms x 3 colours = 12 planes in 4 JPEGs. Plane m at
    // texel y (bottom-up) is 0.1 m + {0.2, 0.3, 0.6}[y] - 0.5 for term 0 red; the others the same
    // pattern shifted. Each plane: min = its y = 0 value, max = its y = 2 value, scale 0.4.
    DirectionSet lights("lights", {{0, 0}, {30, 60}});
    const osg::ref_ptr<HshMaterial> m =
        HshMaterial::create(1, 3, DirectionSet("view", {{0, 0}}), lights,
                            HshMaterial::Shape{2, false, MaterialTexture::Float});
    const float pattern[3] = {0.2f, 0.3f, 0.6f};
    for (int k = 0; k < 4; ++k)
        for (int c = 0; c < 3; ++c)
            for (std::size_t y = 0; y < 3; ++y)
                m->setCoefficient(y, 0, k, c, 0.1f * float(3 * k + c) + pattern[y] - 0.5f);
    TempDir dir;
    const std::string lost = writeRelightLayout(*m, dir.file("web/info.json"), exact());
    EXPECT_EQ(lost.rfind("12 planes in 4 JPEGs (quality 100), 8-bit: largest step 0.00156863", 0),
              0u)
        << lost;
    const nlohmann::json info = readJson(dir.file("web/info.json"));
    EXPECT_EQ(info["width"], 1);
    EXPECT_EQ(info["height"], 3);
    EXPECT_EQ(info["format"], "jpg");
    EXPECT_EQ(info["type"], "hsh");
    EXPECT_EQ(info["colorspace"], "rgb");
    EXPECT_EQ(info["nplanes"], 12);
    EXPECT_EQ(info["quality"], 100);
    EXPECT_FALSE(info.contains("basis"));
    // The lights: (theta, phi) = (0, 0) degrees is (0, 0, 1); (30, 60) is (sin 30 cos 60, sin 30
    // sin 60, cos 30) = (0.25, 0.433, 0.866), three decimals.
    EXPECT_EQ(info["lights"], nlohmann::json::parse("[0,0,1,0.25,0.433,0.866]"));
    for (std::size_t p = 0; p < 12; ++p) {
        EXPECT_NEAR(info["materials"][0]["scale"][p].get<double>(), 0.4, 1e-6) << p;
        // bias = -min / scale = -(0.1 p + 0.2 - 0.5) / 0.4
        EXPECT_NEAR(info["materials"][0]["bias"][p].get<double>(), -(0.1 * double(p) - 0.3) / 0.4,
                    1e-5)
            << p;
    }
    // Bytes: y = 0 (bottom, the JPEG's last row) 0; y = 1: 255 x 0.1 / 0.4 = 63.75 -> 63; y = 2
    // (the JPEG's first row) 255. The JPEG may move a byte by one or two.
    for (int j = 0; j < 4; ++j) {
        int w = 0, h = 0;
        const std::vector<unsigned char> bytes =
            decodeBytes(dir.file("web/plane_" + std::to_string(j) + ".jpg"), w, h);
        ASSERT_EQ(w, 1);
        ASSERT_EQ(h, 3);
        for (int c = 0; c < 3; ++c) {
            EXPECT_NEAR(bytes[std::size_t(c)], 255, 2) << j << " " << c;
            EXPECT_NEAR(bytes[3 + std::size_t(c)], 63, 2) << j << " " << c;
            EXPECT_NEAR(bytes[6 + std::size_t(c)], 0, 2) << j << " " << c;
        }
    }
    EXPECT_TRUE(fs::exists(dir.path() / "web" / "index.html"));
    // Nothing but the layout: no staging folder left.
    std::set<std::string> names;
    for (const auto& e : fs::directory_iterator(dir.path() / "web"))
        names.insert(e.path().filename().string());
    EXPECT_EQ(names, (std::set<std::string>{"index.html", "info.json", "plane_0.jpg", "plane_1.jpg",
                                            "plane_2.jpg", "plane_3.jpg"}));
}

// ---- round trips -------------------------------------------------------------------------------

TEST(RelightWriter, PtmAndHshReadBackWithinTheQuantisationBound) {
    for (const char* setting : {"colour=rgb", "colour=luminance", "order=3", "order=4"}) {
        const bool isHsh = std::string(setting).rfind("order", 0) == 0;
        const osg::ref_ptr<Material> fitted =
            findMethod(isHsh ? "hsh" : "ptm").fit(capture(), FitOptions::parse(setting));
        TempDir dir;
        const std::string info = dir.file("web/info.json");
        writeRelightLayout(*fitted, info, exact());
        const RelightModel model =
            isHsh ? relightModelOfHsh(static_cast<const HshMaterial&>(*fitted), info)
                  : relightModelOfPtm(static_cast<const PtmMaterial&>(*fitted), info);
        const PlaneCheck check = checkPlanes(dir.file("web"), model);
        EXPECT_LE(check.jpegError, 5) << setting;
        // Read back: the planes of the material read equal the written ones within (1 + J)
        // steps (their model seen through the same maker).
        const osg::ref_ptr<Material> read = loadMaterial(info);
        const RelightModel back =
            isHsh ? relightModelOfHsh(static_cast<const HshMaterial&>(*read), info)
                  : relightModelOfPtm(static_cast<const PtmMaterial&>(*read), info);
        ASSERT_EQ(back.planes.size(), model.planes.size());
        const std::size_t texels = std::size_t(model.width) * std::size_t(model.height);
        for (int m = 0; m < model.planeCount; ++m) {
            // lrgb: the base colour has scale 1 (step 1 / 255); the luminance planes are
            // rescaled per texel by the base colour's largest channel, which the reader's
            // product leaves unchanged: compare the products instead.
            double worst = 0;
            for (std::size_t t = 0; t < texels; ++t)
                worst =
                    std::max(worst, double(std::fabs(back.planes[std::size_t(m) * texels + t] -
                                                     model.planes[std::size_t(m) * texels + t])));
            const double bound = (1 + check.jpegError) * check.step[std::size_t(m)] * 1.001 + 1e-6;
            if (!model.baseColourPlanes || m < 3) {
                EXPECT_LE(worst, bound) << setting << " plane " << m;
            }
        }
        // The whole model where it is linear in the planes: the material evaluated at every
        // measured direction moves at most sum_k |basis_k| (1 + J) step_k; checked loosely
        // through the RMS, which must not exceed the largest such bound.
        const std::size_t values = capture().imageCount() * 3;
        std::vector<float> a(values), b(values);
        double sum = 0;
        for (std::size_t t = 0; t < texels; ++t) {
            fitted->evaluateMeasured(t, a.data());
            read->evaluateMeasured(t, b.data());
            for (std::size_t i = 0; i < values; ++i) sum += double(a[i] - b[i]) * (a[i] - b[i]);
        }
        double stepSum = 0;
        for (const double s : check.step) stepSum += s;
        EXPECT_LE(std::sqrt(sum / double(texels * values)), (1 + check.jpegError) * stepSum)
            << setting;
    }
}

TEST(RelightWriter, RbfReadsBackWithinTheQuantisationBound) {
    const osg::ref_ptr<Material> fitted = findMethod("rbf").fit(capture(), FitOptions());
    const RbfMaterial& rbf = static_cast<const RbfMaterial&>(*fitted);
    TempDir dir;
    const std::string info = dir.file("web/info.json");
    writeRelightLayout(*fitted, info, exact());
    const RelightModel model = relightModelOfRbf(rbf, info);
    const PlaneCheck check = checkPlanes(dir.file("web"), model);
    EXPECT_LE(check.jpegError, 5);
    const nlohmann::json json = readJson(info);
    EXPECT_EQ(json["type"], "rbf");
    EXPECT_EQ(json["colorspace"], "mrgb");
    EXPECT_FLOAT_EQ(json["sigma"].get<float>(), rbf.sigma());
    ASSERT_EQ(json["basis"].size(), std::size_t(rbf.planes() + 1) * 72 * 3);
    const osg::ref_ptr<Material> readMaterial = loadMaterial(info);
    const RbfMaterial& read = static_cast<const RbfMaterial&>(*readMaterial);
    ASSERT_EQ(read.planes(), rbf.planes());
    ASSERT_EQ(read.nodeCount(), 72);
    const std::size_t texels = rbf.texelCount();
    for (int p = 0; p < rbf.planes(); ++p) {
        const double range = json["materials"][0]["range"][std::size_t(p)].get<double>();
        double coefficient = 0, basis = 0;
        for (std::size_t t = 0; t < texels; ++t)
            coefficient = std::max(
                coefficient, double(std::fabs(read.coefficient(t, p) - rbf.coefficient(t, p))));
        for (int i = 0; i < 72; ++i)
            for (int c = 0; c < 3; ++c)
                basis = std::max(basis, double(std::fabs(read.basisValue(p + 1, i)[c] -
                                                         rbf.basisValue(p + 1, i)[c])));
        EXPECT_LE(coefficient, (1 + check.jpegError) * check.step[std::size_t(p)] * 1.001 + 1e-6)
            << p;
        // 127 + range E truncated: at most one unit, 1 / range in E.
        EXPECT_LE(basis, 1.0 / range + 1e-6) << p;
    }
    for (int i = 0; i < 72; ++i) {
        for (int c = 0; c < 3; ++c) {
            EXPECT_LE(std::fabs(read.basisValue(0, i)[c] - rbf.basisValue(0, i)[c]),
                      1.0 / 255 + 1e-6);  // the mean, truncated to 0..255
            EXPECT_LE(std::fabs(read.node(i)[c] - rbf.node(i)[c]), 0.0005 + 1e-6);  // 3 decimals
        }
    }
}

TEST(RelightWriter, TheDeepZoomPyramidIsCompleteAndReadsAsTheImageLayout) {
    const osg::ref_ptr<Material> fitted = findMethod("ptm").fit(capture(), FitOptions());
    TempDir dir;
    RelightWriteOptions o = exact();
    o.layout = RelightWriteOptions::Layout::DeepZoom;
    o.tileSize = 24;  // 64 = 24 + 24 + 16: a partial last tile
    o.overlap = 2;
    writeRelightLayout(*fitted, dir.file("dz/info.json"), o);
    writeRelightLayout(*fitted, dir.file("image/info.json"), exact());
    // Levels of 64: 64 > 24 -> 32 > 24 -> 16: three levels, 16, 32, 64 pixels.
    const int sizes[3] = {16, 32, 64};
    for (int j = 0; j < 6; ++j) {
        const std::string stem = dir.file("dz/plane_" + std::to_string(j));
        EXPECT_FALSE(fs::exists(stem + ".jpg"));  // relight removes the plane once tiled
        const std::string dzi = readWholeFile(stem + ".dzi");
        EXPECT_NE(dzi.find("TileSize=\"24\""), std::string::npos);
        EXPECT_NE(dzi.find("Overlap=\"2\""), std::string::npos);
        EXPECT_NE(dzi.find("<Size Height=\"64\" Width=\"64\"/>"), std::string::npos);
        std::size_t files = 0;
        for (const auto& e : fs::recursive_directory_iterator(stem + "_files"))
            files += e.is_regular_file();
        std::size_t expected = 0;
        for (int level = 0; level < 3; ++level) {
            const int n = (sizes[level] + 23) / 24;
            expected += std::size_t(n * n);
            for (int row = 0; row < n; ++row)
                for (int col = 0; col < n; ++col) {
                    // Tile extent: [col 24 - 2 (not for the first), (col + 1) 24 + 2], clipped.
                    const int x0 = std::max(0, col * 24 - 2), y0 = std::max(0, row * 24 - 2);
                    const int x1 = std::min(sizes[level], (col + 1) * 24 + 2);
                    const int y1 = std::min(sizes[level], (row + 1) * 24 + 2);
                    int w = 0, h = 0;
                    decodeBytes(stem + "_files/" + std::to_string(level) + "/" +
                                    std::to_string(col) + "_" + std::to_string(row) + ".jpg",
                                w, h);
                    EXPECT_EQ(w, x1 - x0) << level << " " << col << "," << row;
                    EXPECT_EQ(h, y1 - y0) << level << " " << col << "," << row;
                }
        }
        EXPECT_EQ(files, expected) << stem;
    }
    // The full-size level read back is the image layout's plane within two JPEGs' error (the
    // same bytes coded twice, tile by tile and whole: 2 x 5 levels).
    const osg::ref_ptr<Material> tiled = loadMaterial(dir.file("dz/info.json"));
    const osg::ref_ptr<Material> image = loadMaterial(dir.file("image/info.json"));
    // Each against the fitted coefficients, in steps of its plane: the quantisation bound, with
    // the JPEG's share J as in the other round trips (tiles hold partial 8 x 8 blocks at their
    // edges, and are coded apart).
    const PtmMaterial& fit = static_cast<const PtmMaterial&>(*fitted);
    const nlohmann::json info = readJson(dir.file("dz/info.json"));
    for (const Material* read : {tiled.get(), image.get()}) {
        const PtmMaterial& a = static_cast<const PtmMaterial&>(*read);
        double worst = 0;
        // Web term w (1, x, y, x^2, xy, y^2) is the material's term kWeb[w] (docs/formats.md).
        constexpr int kWeb[6] = {5, 3, 4, 0, 2, 1};
        for (int w = 0; w < 6; ++w)
            for (int c = 0; c < 3; ++c) {
                const int k = kWeb[w];
                const double step =
                    info["materials"][0]["scale"][std::size_t(3 * w + c)].get<double>() / 255;
                for (std::size_t t = 0; t < a.texelCount(); ++t)
                    worst = std::max(
                        worst,
                        std::fabs(a.coefficient(t, 0, k, c) - fit.coefficient(t, 0, k, c)) / step);
            }
        // 1 step of truncation + J <= 5 (measured: 4.8 steps in all whole, 5.0 tiled).
        EXPECT_LE(worst, 1 + 5 + 1e-3) << (read == tiled.get() ? "tiled" : "image");
        std::cout << (read == tiled.get() ? "tiled" : "image") << ": largest change " << worst
                  << " steps\n";
    }
    EXPECT_NE(relightInfo(dir.file("dz/info.json"))
                  .find("relight web layout (deep-zoom pyramids), type ptm, colorspace rgb, 18 "
                        "planes (6 terms) in 6 pyramids, 64x64"),
              std::string::npos);
}

}  // namespace OSGBTF_TEST_FILE
