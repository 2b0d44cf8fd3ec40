// The RTI field's JPEG-compressed files: relight's web layout (info.json + plane_N.jpg,
// materials/RelightFolder.h) and the legacy .ptm variants PTM_FORMAT_JPEG_LRGB / _JPEG_RGB
// (materials/ptm/PtmFile.h). The fixtures in tests/data/rti-files/ are written by
// make_fixtures.py there (numpy and Pillow, nothing of osgBTF) from the layouts of
// docs/formats.md 8.1.1 and 8.4; the values below are worked out by hand from the bytes that
// script writes. Then hostile inputs, each with its exact one-line message.
//
// JPEG bound: the legacy streams are uniform grey planes (exact at quality 100). The relight
// planes are RGB through YCbCr, not all uniform: the script checks that every decoded byte is
// within 1 of the intended one; the tolerances here allow 2 bytes, propagated through the
// scale of each plane and the basis (stated per test).
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/MeasuredBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/RelightFolder.h"
#include "materials/hsh/Hsh.h"
#include "materials/ptm/PtmFile.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::errorOf;
using osgBTF::test::TempDir;
namespace fs = std::filesystem;

namespace {

std::string fixture(const std::string& name) {
    return osgBTF::test::sourceDir() + "/tests/data/rti-files/" + name;
}

const glm::vec3 kView(0, 0, 1);
const glm::vec3 kLightX(0.6f, 0, 0.8f);  // u = 0.6, v = 0
const glm::vec3 kLightY(0, 0.6f, 0.8f);  // u = 0, v = 0.6 (v up the image)
const glm::vec3 kLightUp(0, 0, 1);

void expectNear(const glm::vec3& got, const glm::vec3& want, float tolerance,
                const std::string& where) {
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(got[c], want[c], tolerance) << where << " channel " << c;
}

/** A copy of a relight fixture folder to spoil. */
std::string copyFolder(const TempDir& dir, const std::string& name) {
    const fs::path to = dir.path() / name;
    fs::copy(fixture(name), to, fs::copy_options::recursive);
    return to.string();
}

/** info.json of a copied folder with `from` replaced by `to` (once; the text must hold it). */
void editInfo(const std::string& folder, const std::string& from, const std::string& to) {
    const std::string path = folder + "/info.json";
    std::string text = osgBTF::test::readTextFile(path);
    const std::size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    osgBTF::test::writeTextFile(path, text);
}

}  // namespace

// ---- relight's web layout ----------------------------------------------------------------------

TEST(RelightFolder, PtmLrgbReadsAsALuminancePtmWithTheWebTermOrderRowsTopDownAndYUp) {
    // plane_0 base colour: top row (255, 153, 51) = (1, 0.6, 0.2), the rows below (51, 102, 204)
    // = (0.2, 0.4, 0.8). Luminance (scale 2, bias 0.5): 1 -> 204 = 0.6, x -> 255 = 1.0,
    // y -> 153 = 0.2 (top row) / 102 = -0.2 (below); x^2 -> 51 (scale 1, bias 0) = 0.2, xy, y^2 0.
    const osg::ref_ptr<Material> m = loadMaterial(fixture("relight-ptm-lrgb/info.json"));
    ASSERT_EQ(m->methodName(), "ptm");
    const auto& ptm = static_cast<const PtmMaterial&>(*m);
    EXPECT_TRUE(ptm.shape().luminance);
    EXPECT_EQ(m->width(), 4);
    EXPECT_EQ(m->height(), 3);
    // Light x = 0.6: L = 0.6 + 1.0 * 0.6 + 0.2 * 0.36 = 1.272 in every row.
    // Bound: colour +-2/255, L +-(4/255)(1 + 0.6 + 0.36) = 0.031: value +-(0.031 + 1.272 * 0.008).
    const float tol = 0.042f;
    expectNear(m->evaluate(0, 2, kView, kLightX), {1.272f, 0.7632f, 0.2544f}, tol, "top, x");
    expectNear(m->evaluate(3, 0, kView, kLightX), {0.2544f, 0.5088f, 1.0176f}, tol, "bottom, x");
    // Light y = 0.6 (up the image): top row L = 0.6 + 0.2 * 0.6 = 0.72, the others 0.48.
    expectNear(m->evaluate(1, 2, kView, kLightY), {0.72f, 0.432f, 0.144f}, tol, "top, y");
    expectNear(m->evaluate(1, 1, kView, kLightY), {0.096f, 0.192f, 0.384f}, tol, "middle, y");
    // info.json's three lights are the material's measured lights.
    ASSERT_EQ(m->lights().size(), 3u);
    EXPECT_NEAR(m->lights().vector(1).y, 0.6f, 1e-3f);
}

TEST(RelightFolder, FirstDegreePtmRgbHasZeroQuadraticTerms) {
    // Constant (153, 102, 51) = (0.6, 0.4, 0.2); x (scale 2, bias 0.5): (204, 153, 153) =
    // (0.6, 0.2, 0.2); y: top row (255, 153, 153) = (1.0, 0.2, 0.2), below 0.2 each.
    const osg::ref_ptr<Material> m = loadMaterial(fixture("relight-ptm-rgb/info.json"));
    const auto& ptm = static_cast<const PtmMaterial&>(*m);
    EXPECT_FALSE(ptm.shape().luminance);
    for (int k = 0; k < 3; ++k) EXPECT_EQ(ptm.coefficient(0, 0, k, 0), 0.0f);  // x^2, y^2, xy
    // Bound: 2/255 + 0.6 (4/255) = 0.0173 per channel.
    const float tol = 0.018f;
    expectNear(m->evaluate(2, 1, kView, kLightX), {0.96f, 0.52f, 0.32f}, tol, "x");
    expectNear(m->evaluate(2, 2, kView, kLightY), {1.2f, 0.52f, 0.32f}, tol, "top, y");
    expectNear(m->evaluate(2, 0, kView, kLightY), {0.72f, 0.52f, 0.32f}, tol, "bottom, y");
    // No lights in info.json: the nominal ones.
    EXPECT_EQ(m->lights().size(), 81u);
}

TEST(RelightFolder, HshRgbReadsInTheSameTermOrderAsTheHshMethod) {
    // 4 terms, scale 1, bias 0: c0 = (1, 0.6, 0.2), c1 = (0.2, 0, 0), c2 = top row (0.4, 0.2, 0),
    // below 0, c3 = 0. Light up: h0 = 1/sqrt(2 pi) = 0.398942, h2 = sqrt(3/(2 pi)) = 0.690988.
    const osg::ref_ptr<Material> m = loadMaterial(fixture("relight-hsh-rgb/info.json"));
    ASSERT_EQ(m->methodName(), "hsh");
    EXPECT_EQ(static_cast<const HshMaterial&>(*m).terms(), 4);
    const float tol = 0.012f;  // 2/255 (0.399 + 0.691 + 0.553)
    expectNear(m->evaluate(0, 2, kView, kLightUp), {0.675337f, 0.377563f, 0.079788f}, tol, "top");
    expectNear(m->evaluate(0, 0, kView, kLightUp), {0.398942f, 0.239365f, 0.079788f}, tol,
               "bottom");
    // Light x = 0.6: t = 0.8, s = 0.4, h1 = sqrt(6/pi) 0.4 = 0.552791, h2 = 0.690988 * 0.6.
    expectNear(m->evaluate(0, 0, kView, kLightX),
               {0.398942f + 0.2f * 0.552791f, 0.239365f, 0.079788f}, tol, "bottom, x");
}

TEST(RelightFolder, HshLrgbBecomesPerChannelCoefficientsColourTimesLuminance) {
    // Base colour (255, 102, 51) = (1, 0.4, 0.2); luminance terms (scale 2, bias 0.5):
    // 0.6, 0.2, 0.2 | 0.2, 0.2, 0.2 | -0.2, 0.2, 0.2. Light up: h0 = 0.398942, h2 = 0.690988,
    // h6 = sqrt(5/(2 pi)) = 0.892062, the others 0: L = 0.239365 + 0.138198 - 0.178412.
    const osg::ref_ptr<Material> m = loadMaterial(fixture("relight-hsh-lrgb/info.json"));
    const auto& hsh = static_cast<const HshMaterial&>(*m);
    EXPECT_EQ(hsh.terms(), 9);
    EXPECT_NEAR(hsh.coefficient(5, 0, 0, 1), 0.4f * 0.6f, 0.02f);  // colour_G * L_0
    const float L = 0.199151f, tol = 0.035f;  // L +-(4/255)(0.399 + 0.691 + 0.892)
    expectNear(m->evaluate(2, 1, kView, kLightUp), {L, 0.4f * L, 0.2f * L}, tol, "up");
}

TEST(RelightFolder, InfoAndPluginNamesAndTheReadOnlyFormat) {
    EXPECT_NE(findForeignFile("a/b/INFO.JSON"), nullptr);
    EXPECT_EQ(findForeignFile("a/b/results.json"), nullptr);
    EXPECT_EQ(findForeignFile("a/b/myinfo.json"), nullptr);  // a whole name matches only itself
    EXPECT_NE(findForeignFile("a/b/coin.PTM"), nullptr);
    EXPECT_EQ(findForeignFile("a/b/.ptm"), nullptr);
    EXPECT_EQ(relightInfo(fixture("relight-hsh-lrgb/info.json")),
              "relight web layout (single images), type hsh, colorspace lrgb, 12 planes (9 terms) "
              "in 4 JPEGs, 4x3\nlights: none recorded");
    TempDir dir;
    const osg::ref_ptr<Material> m = loadMaterial(fixture("relight-ptm-rgb/info.json"));
    const std::string target = dir.file("info.json");
    // Written too (tests/materials_relight_writer_test.cpp): here only that saveMaterial goes
    // there, and that a material of another method is refused with the methods it holds.
    EXPECT_EQ(saveMaterial(*m, target).rfind("18 planes in 6 JPEGs (quality 95)", 0), 0u);
    EXPECT_TRUE(fs::exists(dir.file("plane_5.jpg")));
    const osg::ref_ptr<Material> pca =
        findMethod("pca").fit(osgBTF::test::smallSampleBtf(4), FitOptions::parse("components=2"));
    EXPECT_EQ(errorOf([&] { saveMaterial(*pca, target); }),
              target + ": a info.json file holds a hsh, ptm or rbf material, not pca");
}

TEST(RelightFolderErrors, HostileFoldersAreRefusedWithOneLineNamingTheFile) {
    TempDir dir;
    const std::string f = copyFolder(dir, "relight-ptm-lrgb");
    const std::string info = f + "/info.json";
    const auto problem = [&] { return errorOf([&] { loadMaterial(info); }); };

    // nplanes inconsistent with scale and bias.
    editInfo(f, "\"nplanes\": 9", "\"nplanes\": 12");
    EXPECT_EQ(problem(), info + ": materials[0].scale has 9 values, \"nplanes\" is 12");
    editInfo(f, "\"nplanes\": 12", "\"nplanes\": 9");
    // A scale that is not finite: JSON has no NaN or infinity; a number too large for a double
    // is refused by the parser, a string in its place by the reader.
    editInfo(f, "\"scale\": [\n    1,", "\"scale\": [\n    1e999,");
    EXPECT_EQ(problem(), info +
                             ": not JSON: [json.exception.out_of_range.406] number overflow "
                             "parsing '1e999'");
    editInfo(f, "1e999", "\"NaN\"");
    EXPECT_EQ(problem(), info + ": materials[0].scale[0] is not a number");
    editInfo(f, "\"NaN\"", "1");
    // Another colorspace, another type.
    editInfo(f, "\"lrgb\"", "\"ycc\"");
    EXPECT_EQ(problem(), info + ": colorspace 'ycc' is not read (rgb, lrgb, mrgb and mycc are)");
    editInfo(f, "\"ycc\"", "\"lrgb\"");
    editInfo(f, "\"ptm\"", "\"sh\"");
    EXPECT_EQ(problem(), info + ": type 'sh' is not read (bilinear, hsh, ptm, rbf are)");
    editInfo(f, "\"sh\"", "\"ptm\"");
    // A plane of the wrong size.
    fs::copy_file(fixture("wrong-size-5x3.jpg"), f + "/plane_1.jpg",
                  fs::copy_options::overwrite_existing);
    EXPECT_EQ(problem(), f + "/plane_1.jpg: the JPEG is 5x3 with 3 channels, info.json gives 4x3 "
                             "with 3 channels");
    // A truncated JPEG.
    const std::string plane = osgBTF::test::readTextFile(fixture("relight-ptm-lrgb/plane_1.jpg"));
    osgBTF::test::writeTextFile(f + "/plane_1.jpg", plane.substr(0, plane.size() / 2));
    EXPECT_EQ(problem(), f + "/plane_1.jpg: truncated JPEG (no end-of-image marker)");
    // A missing plane file.
    osgBTF::test::writeTextFile(f + "/plane_1.jpg", plane);
    fs::remove(f + "/plane_2.jpg");
    EXPECT_EQ(problem(), f + "/plane_2.jpg: no such file (" + info +
                             " has 9 planes: plane_0.jpg .. plane_2.jpg)");
    // A size beyond the memory guard, refused before anything is allocated.
    editInfo(f, "\"width\": 4", "\"width\": 1048576");
    editInfo(f, "\"height\": 3", "\"height\": 1048576");
    const std::string big = problem();
    EXPECT_EQ(big.rfind(info + ": 9 planes of 1048576x1048576: needs ", 0), 0u) << big;
}

TEST(RelightFolderErrors, TiledLayoutsAreNamed) {
    TempDir dir;
    const std::string f = copyFolder(dir, "relight-ptm-rgb");
    for (int j = 0; j < 3; ++j) fs::remove(f + "/plane_" + std::to_string(j) + ".jpg");
    const std::string info = f + "/info.json";
    osgBTF::test::writeTextFile(f + "/plane_0.tzi", "{}");
    EXPECT_EQ(errorOf([&] { loadMaterial(info); }),
              info +
                  ": relight's tiled layout tarzoom (plane_0.tzi) is not read; the "
                  "single-image (plane_0.jpg ...) and deep-zoom (plane_0.dzi ...) layouts are");
    // The deep-zoom layout is read (tests/materials_relight_writer_test.cpp): a broken .dzi.
    osgBTF::test::writeTextFile(f + "/plane_0.dzi", "<Image/>");
    EXPECT_EQ(errorOf([&] { loadMaterial(info); }),
              f + "/plane_0.dzi: TileSize and Overlap are not integers with 1 <= TileSize <= "
                  "8192 and 0 <= Overlap < TileSize");
    fs::remove(f + "/plane_0.dzi");
    fs::remove(f + "/plane_0.tzi");
    EXPECT_EQ(errorOf([&] { loadMaterial(info); }),
              f + "/plane_0.jpg: no such file (the first plane of " + info + ")");
}

// ---- the legacy .ptm JPEG variants -------------------------------------------------------------

TEST(PtmJpegFile, LrgbStreamsWithPredictionInversionOrderAndSideInformation) {
    // Final values (0..255 units): a0 = 10 (stream 0: predicted from stream 3 inverted, with
    // wrap-around), a1 = a2 = 0, a3 = (100 - 50) * 2 = 100 (predicted from stream 5),
    // a4 = (128 - 128) = 0 but 50 at position 0 (bottom left) and -50 at position 7 (row 1 from
    // the bottom, x = 3), a5 = 150; colour (255, 128, 0) / 255. Uniform grey JPEGs: exact.
    const osg::ref_ptr<Material> m = loadMaterial(fixture("jpeg-lrgb.ptm"));
    const auto& ptm = static_cast<const PtmMaterial&>(*m);
    ASSERT_TRUE(ptm.shape().luminance);
    EXPECT_EQ(m->fitInfo.at("file-format"), "PTM_FORMAT_JPEG_LRGB");
    const float g = 128.0f / 255.0f;
    // u = 0.6: L = 10 * 0.36 + 100 * 0.6 + 150 = 213.6 everywhere.
    const float lx = 213.6f / 255.0f;
    expectNear(m->evaluate(2, 1, kView, kLightX), {lx, g * lx, 0}, 1e-5f, "x");
    // v = 0.6: L = 0.6 a4 + 150.
    expectNear(m->evaluate(0, 0, kView, kLightY), {180 / 255.0f, g * 180 / 255.0f, 0}, 1e-5f,
               "position 0");
    expectNear(m->evaluate(3, 1, kView, kLightY), {120 / 255.0f, g * 120 / 255.0f, 0}, 1e-5f,
               "position 7");
    expectNear(m->evaluate(0, 2, kView, kLightY), {150 / 255.0f, g * 150 / 255.0f, 0}, 1e-5f,
               "elsewhere");
}

TEST(PtmJpegFile, RgbStreamsAreColourMajor) {
    // Streams R a0..a5, G a0..a5, B a0..a5 (scale 1, bias 0): R a3 = a5 = 100; G a4 = 100,
    // a5 = 50; B a0 = 200, a5 = 0 but 255 at position 11 (top right).
    const osg::ref_ptr<Material> m = loadMaterial(fixture("jpeg-rgb.ptm"));
    EXPECT_FALSE(static_cast<const PtmMaterial&>(*m).shape().luminance);
    expectNear(m->evaluate(0, 0, kView, kLightX), glm::vec3(160, 50, 72) / 255.0f, 1e-5f, "x");
    expectNear(m->evaluate(0, 0, kView, kLightY), glm::vec3(100, 110, 0) / 255.0f, 1e-5f, "y");
    expectNear(m->evaluate(3, 2, kView, kLightY), glm::vec3(100, 110, 255) / 255.0f, 1e-5f,
               "top right");
}

namespace {

/** The JPEG_LRGB fixture with header line `line` (0-based; 12 = compressed sizes) replaced, and
 *  the data as they are. */
std::string withHeaderLine(int line, const std::string& text, std::string* dataOut = nullptr) {
    const std::string file = osgBTF::test::readTextFile(fixture("jpeg-lrgb.ptm"));
    std::vector<std::string> lines;
    std::size_t at = 0;
    for (int i = 0; i < 14; ++i) {
        const std::size_t end = file.find('\n', at);
        lines.push_back(file.substr(at, end - at));
        at = end + 1;
    }
    if (dataOut) *dataOut = file.substr(at);
    lines[std::size_t(line)] = text;
    std::string out;
    for (const std::string& l : lines) out += l + "\n";
    return out + file.substr(at);
}

}  // namespace

TEST(PtmJpegFileErrors, HostileHeadersAndStreamsAreRefusedWithTheirProblem) {
    const auto problem = [](const std::string& bytes) {
        return errorOf([&] { ptmMaterialFromBytes("x.ptm", bytes); });
    };
    // Lines (0-based): 6 compression, 7 transforms, 8/9 motion x/y, 10 order, 11 reference,
    // 12 compressed sizes (333 334 334 333 331 333 333 331 334), 13 side-information sizes.
    EXPECT_EQ(problem(withHeaderLine(8, "0 0 3 0 0 0 0 0 0")),
              "x.ptm: stream 2: motion vector (3, 0) is not read (only 0, 0)");
    EXPECT_EQ(problem(withHeaderLine(7, "2 0 0 0 0 0 0 0 0")),
              "x.ptm: stream 0: transform 2 (motion compensation) is not read (0 and 1 are)");
    EXPECT_EQ(problem(withHeaderLine(10, "2 3 4 1 5 0 6 7 7")),
              "x.ptm: header: order 7 is given to streams 7 and 8 (a permutation of 0..8 is read)");
    EXPECT_EQ(problem(withHeaderLine(11, "3 -1 -1 5 -1 8 -1 -1 -1")),
              "x.ptm: stream 5 is predicted from stream 8, which is not decoded before it (order "
              "8 >= 0)");
    EXPECT_EQ(problem(withHeaderLine(13, "0 0 0 0 7 0 0 0 0")),
              "x.ptm: stream 4: side-information size 7 is not a multiple of 5 (records of 5 "
              "bytes)");
    // A stream size larger than the file.
    std::string data;
    withHeaderLine(12, "", &data);
    EXPECT_EQ(problem(withHeaderLine(12, "333 334 334 333 331 333 333 331 99999")),
              "x.ptm: truncated: the 9 JPEG streams and their side information need " +
                  std::to_string(data.size() - 334 + 99999) + " bytes, the file has " +
                  std::to_string(data.size()));
    // A truncated JPEG stream: stream 8 given 20 bytes fewer (and the file cut to match).
    const std::string cut = withHeaderLine(12, "333 334 334 333 331 333 333 331 314");
    EXPECT_EQ(problem(cut.substr(0, cut.size() - 20)),
              "x.ptm: JPEG stream 8: truncated JPEG (no end-of-image marker)");
    // Side information outside the image: position 7 becomes 0x0100_0007.
    std::string far = osgBTF::test::readTextFile(fixture("jpeg-lrgb.ptm"));
    const std::size_t record = far.find(std::string("\0\0\0\x07N", 5));
    ASSERT_NE(record, std::string::npos);
    far[record] = 1;
    EXPECT_EQ(problem(far), "x.ptm: JPEG stream 4: side information 1 sets pixel 16777223 of 12");
}

}  // namespace OSGBTF_TEST_FILE
