// The RTI field's fitted files (materials/ptm/PtmFile.h, materials/hsh/RtiFile.h): hostile
// headers first, with their exact messages; then fixtures of a few pixels written here byte by
// byte from the format descriptions (docs/formats.md section 8), whose values are worked out by
// hand; then the writers' round trips within the 8-bit step.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdint>
#include <cstring>
#include <string>
#include <vector>

#include "core/FloatImage.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/hsh/RtiFile.h"
#include "materials/ptm/PtmFile.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::errorOf;
using osgBTF::test::TempDir;

namespace {

std::string bytes(std::initializer_list<int> values) {
    std::string out;
    for (const int v : values) out += char(v);
    return out;
}

/** A float as the 4 little-endian bytes of its IEEE 754 single encoding. */
std::string le(float value) {
    std::uint32_t bits;
    std::memcpy(&bits, &value, 4);
    return bytes(
        {int(bits & 0xFF), int((bits >> 8) & 0xFF), int((bits >> 16) & 0xFF), int(bits >> 24)});
}

const std::string kPtmHeader =
    "PTM_1.2\nPTM_FORMAT_RGB\n2\n1\n2 2 2 2 2 1\n128 128 128 128 128 0\n";

/** 2 x 1 pixels of PTM_FORMAT_RGB: planes R, G, B, each pixel a0..a5. */
std::string ptmRgbFixture() {
    return kPtmHeader +
           // R: pixel 0 a0 = (140 - 128) 2 = 24, a3 = (118 - 128) 2 = -20, a5 = 255; pixel 1 zeros
           bytes({140, 128, 128, 118, 128, 255, 128, 128, 128, 128, 128, 0}) +
           // G: pixel 0 a5 = 102; pixel 1 a4 = (138 - 128) 2 = 20, a5 = 51
           bytes({128, 128, 128, 128, 128, 102, 128, 128, 128, 128, 138, 51}) +
           // B: every coefficient 0 but pixel 1's a5 = 255
           bytes({128, 128, 128, 128, 128, 0, 128, 128, 128, 128, 128, 255});
}

}  // namespace

// ---- hostile headers ---------------------------------------------------------------------------

TEST(PtmFileErrors, HeadersThatLieAreRefusedWithTheirProblem) {
    const auto problem = [](const std::string& data) {
        return errorOf([&] { ptmMaterialFromBytes("x.ptm", data); });
    };
    EXPECT_EQ(problem("PTM_1.1\nPTM_FORMAT_RGB\n"),
              "x.ptm: not a PTM 1.2 file (the first line is 'PTM_1.1', not 'PTM_1.2')");
    // The JPEG variants are read (materials_rti_compressed_files_test.cpp): their header goes on.
    EXPECT_EQ(problem("PTM_1.2\nPTM_FORMAT_JPEG_LRGB\n1 1\n"),
              "x.ptm: header: scale 0 '' is not a number");
    EXPECT_EQ(problem("PTM_1.2\nPTM_FORMAT_LUM\n1 1\n"),
              "x.ptm: format 'PTM_FORMAT_LUM' is not read (PTM_FORMAT_RGB, PTM_FORMAT_LRGB, "
              "PTM_FORMAT_JPEG_RGB and PTM_FORMAT_JPEG_LRGB are)");
    EXPECT_EQ(problem("PTM_1.2\nPTM_FORMAT_RGB\nwide\n1\n"),
              "x.ptm: header: width 'wide' is not an integer");
    EXPECT_EQ(problem("PTM_1.2\nPTM_FORMAT_RGB\n0\n1\n"),
              "x.ptm: header: size 0x1 is not 1..1048576 on each side");
    EXPECT_EQ(problem("PTM_1.2\nPTM_FORMAT_RGB\n2\n1\n2 2 nan 2 2 1\n"),
              "x.ptm: header: scale 2 is not finite");
    EXPECT_EQ(problem("PTM_1.2\nPTM_FORMAT_RGB\n2\n1\n2 2 2 2 2 1\n128 128 128\n"),
              "x.ptm: header: bias 3 '' is not an integer");
    EXPECT_EQ(problem(kPtmHeader + bytes({1, 2, 3})),
              "x.ptm: truncated: PTM_FORMAT_RGB 2x1 needs 36 bytes of coefficients, the file "
              "has 3");
    // A size whose data would be 18 TB: refused from the header, before anything is allocated.
    EXPECT_EQ(problem("PTM_1.2\nPTM_FORMAT_LRGB\n1048576\n1048576\n1 1 1 1 1 1\n0 0 0 0 0 0\n"),
              "x.ptm: truncated: PTM_FORMAT_LRGB 1048576x1048576 needs 9895604649984 bytes of "
              "coefficients, the file has 0");
}

TEST(RtiFileErrors, HeadersThatLieAreRefusedWithTheirProblem) {
    const auto problem = [](const std::string& data) {
        return errorOf([&] { hshMaterialFromBytes("x.rti", data); });
    };
    EXPECT_EQ(problem("#HSH1.2\n2\n4 4 3\n"),
              "x.rti: RTI type 2 is not read (only 3, hemispherical harmonics)");
    EXPECT_EQ(problem("#HSH1.2\n3\n4 4\n"),
              "x.rti: header: the size (width height bands) line '4 4' needs 3 integers");
    EXPECT_EQ(problem("#HSH1.2\n3\n4 4 1\n9 2 1\n"), "x.rti: header: 1 colour bands (3 are read)");
    EXPECT_EQ(problem("#HSH1.2\n3\n4 4 3\n7 2 1\n"),
              "x.rti: header: 7 terms per band (4, 9 or 16: hemispherical harmonics of order 2 "
              "to 4)");
    EXPECT_EQ(problem("#HSH1.2\n3\n4 4 3\n4 2 2\n"),
              "x.rti: header: element size 2 (1 byte per term is read)");
    EXPECT_EQ(problem("#HSH1.2\n3\n4 4 3\n4 2 1\n" + le(0) + le(0)),
              "x.rti: truncated: the 4 term ranges need 32 bytes, the file has 8");
    EXPECT_EQ(problem("#HSH1.2\n3\n4 4 3\n4 2 1\n" + le(0) + le(NAN) + le(0) + le(0) + le(1) +
                      le(1) + le(1) + le(1)),
              "x.rti: header: the range of term 1 is not finite");
    EXPECT_EQ(problem("#HSH1.2\n3\n1048576 1048576 3\n16 2 1\n" + std::string(128, '\0')),
              "x.rti: truncated: 1048576x1048576 pixels of 3 x 16 terms need 52776558133248 "
              "bytes, the file has 0");
    EXPECT_EQ(problem("#HSH1.2\n"), "x.rti: header: no type line");
}

// ---- hand-made fixtures ------------------------------------------------------------------------

// PTM_FORMAT_RGB, 2 x 1: a_k = (byte - bias_k) scale_k in 8-bit units, / 255 in the material.
// Pixel 0 lit from the normal (u = v = 0): R = a5 = 255/255 = 1, G = 102/255 = 0.4, B = 0. Lit
// from (u, v) = (0.6, 0) (light (0.6, 0, 0.8)): R = (24 * 0.36 - 20 * 0.6 + 255) / 255
// = 251.64 / 255. Pixel 1 from (0, 0.5): G = (20 * 0.5 + 51) / 255 = 61 / 255, B = 1.
TEST(PtmFile, ReadsAHandWrittenRgbFileAsTheFormatDefinesIt) {
    const osg::ref_ptr<PtmMaterial> m = ptmMaterialFromBytes("fixture.ptm", ptmRgbFixture());
    ASSERT_EQ(m->width(), 2);
    ASSERT_EQ(m->height(), 1);
    EXPECT_FALSE(m->shape().luminance);
    EXPECT_FALSE(m->shape().perView);
    const glm::vec3 view(0, 0, 1);
    const glm::vec3 top = m->evaluate(0, 0, view, {0, 0, 1});
    EXPECT_NEAR(top.r, 1.0, 1e-6);
    EXPECT_NEAR(top.g, 0.4, 1e-6);
    EXPECT_NEAR(top.b, 0.0, 1e-6);
    EXPECT_NEAR(m->evaluate(0, 0, view, {0.6f, 0, 0.8f}).r, 251.64 / 255, 1e-6);
    const glm::vec3 second = m->evaluate(1, 0, view, {0, 0.5f, float(std::sqrt(0.75))});
    EXPECT_NEAR(second.g, 61.0 / 255, 1e-6);
    EXPECT_NEAR(second.b, 1.0, 1e-6);
    EXPECT_NEAR(second.r, 0.0, 1e-6);
}

// Rows run bottom to top: in a 1 x 2 file the first pixel is the bottom texel (y = 0).
// PTM_FORMAT_LRGB: pixel 0 L = a5 = (200 - 0) 1 = 200, colour (255, 0, 51); pixel 1 L = 100,
// colour (0, 255, 0): values L / 255 * colour / 255.
TEST(PtmFile, ReadsAHandWrittenLrgbFileBottomRowFirst) {
    const std::string data = "PTM_1.2\nPTM_FORMAT_LRGB\n1 2\n1 1 1 1 1 1\n0 0 0 0 0 0\n" +
                             bytes({0, 0, 0, 0, 0, 200, 0, 0, 0, 0, 0, 100}) +
                             bytes({255, 0, 51, 0, 255, 0});
    const osg::ref_ptr<PtmMaterial> m = ptmMaterialFromBytes("l.ptm", data);
    ASSERT_TRUE(m->shape().luminance);
    const glm::vec3 bottom = m->evaluate(0, 0, {0, 0, 1}, {0, 0, 1});
    const glm::vec3 top = m->evaluate(0, 1, {0, 0, 1}, {0, 0, 1});
    EXPECT_NEAR(bottom.r, 200.0 / 255, 1e-6);
    EXPECT_NEAR(bottom.g, 0.0, 1e-6);
    EXPECT_NEAR(bottom.b, 200.0 / 255 * 0.2, 1e-6);
    EXPECT_NEAR(top.g, 100.0 / 255, 1e-6);
    EXPECT_NEAR(top.r, 0.0, 1e-6);
}

// HSH, 1 x 2, 4 terms: c_k = min_k + (max_k - min_k) byte / 255 with min (0, -1, 0, 0) and max
// (1, 1, 2, 1). Rows run top to bottom: the first pixel is the top texel (y = 1). Top pixel R:
// bytes (255, 0, 0, 0): c = (1, -1, 0, 0); lit from the normal h = (1/sqrt(2 pi), 0,
// sqrt(3/(2 pi)), 0), so R = 1/sqrt(2 pi) = 0.398942. Bottom pixel G: bytes (0, 255, 255, 0):
// c = (0, 1, 2, 0): from the normal 2 sqrt(3/(2 pi)) = 1.381977; B: bytes (0, 51, 0, 0): c1 = -1
// + 2 * 51/255 = -0.6, which the normal does not see: 0.
TEST(RtiFile, ReadsAHandWrittenHshFileTopRowFirst) {
    const std::string data =
        "#HSH1.2\n# a second comment line\n3\n1 2 3\n4 2 1\n" + le(0) + le(-1) + le(0) + le(0) +
        le(1) + le(1) + le(2) + le(1) +
        bytes({255, 0, 0, 0, 0, 127, 0, 0, 0, 127, 0, 0}) +  // top: R, G, B terms
        bytes({0, 127, 0, 0, 0, 255, 255, 0, 0, 51, 0, 0});  // bottom
    const osg::ref_ptr<HshMaterial> m = hshMaterialFromBytes("f.rti", data);
    ASSERT_EQ(m->shape().order, 2);
    ASSERT_EQ(m->height(), 2);
    const double pi = 3.14159265358979323846;
    const glm::vec3 top = m->evaluate(0, 1, {0, 0, 1}, {0, 0, 1});
    const glm::vec3 bottom = m->evaluate(0, 0, {0, 0, 1}, {0, 0, 1});
    EXPECT_NEAR(top.r, 1 / std::sqrt(2 * pi), 1e-6);
    EXPECT_NEAR(bottom.g, 2 * std::sqrt(3 / (2 * pi)), 1e-6);
    EXPECT_NEAR(bottom.b, 0.0, 1e-6);
    EXPECT_NEAR(m->coefficient(0, 0, 1, 2), -0.6, 1e-6);
}

// ---- writers -----------------------------------------------------------------------------------

// A fitted material written and read back: every coefficient within one byte step of its term
// (PTM: the scale, as the integer bias can shift the range by up to half a step; HSH: half the
// range / 255), what the writer reports too.
TEST(RtiFiles, WrittenFilesReadBackWithinTheEightBitStep) {
    TempDir dir;
    const MeasuredBtf btf = test::sampleBtf(6, 5);
    for (const char* colour : {"rgb", "luminance"}) {
        const osg::ref_ptr<Material> fitted = findMethod("ptm").fit(
            btf, FitOptions::parse(std::string("storage=float colour=") + colour));
        const auto& ptm = static_cast<const PtmMaterial&>(*fitted);
        const std::string path = dir.file(std::string(colour) + ".ptm");
        const PtmQuantisation q = writePtmFile(ptm, path);
        EXPECT_LE(q.largestCoefficientError, q.largestStep * (1 + 1e-6)) << colour;
        const osg::ref_ptr<PtmMaterial> back = readPtmFile(path);
        ASSERT_EQ(back->shape().luminance, ptm.shape().luminance);
        // Values at a few lights: within the sum of the terms' steps (monomials are at most 1)
        // times the colour (at most 1 in the file, the rest folded into the polynomial).
        for (const glm::vec3& light : {glm::vec3(0, 0, 1), glm::vec3(0.48f, 0.6f, 0.64f)})
            for (int y = 0; y < ptm.height(); ++y)
                for (int x = 0; x < ptm.width(); ++x) {
                    const glm::vec3 a = ptm.evaluate(x, y, {0, 0, 1}, light);
                    const glm::vec3 b = back->evaluate(x, y, {0, 0, 1}, light);
                    for (int c = 0; c < 3; ++c)
                        EXPECT_NEAR(a[c], b[c], 6 * q.largestStep * 1.5 + 2.0 / 255)
                            << colour << " texel " << x << "," << y;
                }
    }
    for (const int order : {2, 3, 4}) {
        const osg::ref_ptr<Material> fitted = findMethod("hsh").fit(
            btf, FitOptions::parse("storage=float order=" + std::to_string(order)));
        const auto& hsh = static_cast<const HshMaterial&>(*fitted);
        const std::string path = dir.file("o" + std::to_string(order) + ".rti");
        const auto [error, step] = writeRtiFile(hsh, path);
        EXPECT_LE(error, step / 2 * (1 + 1e-5)) << order;
        const osg::ref_ptr<HshMaterial> back = readRtiFile(path);
        ASSERT_EQ(back->terms(), hsh.terms());
        for (std::size_t t = 0; t < hsh.texelCount(); ++t)
            for (int k = 0; k < hsh.terms(); ++k)
                for (int c = 0; c < 3; ++c)
                    ASSERT_NEAR(back->coefficient(t, 0, k, c), hsh.coefficient(t, 0, k, c),
                                step / 2 * (1 + 1e-5) + 1e-7)
                        << "order " << order << " texel " << t << " term " << k;
    }
}

TEST(RtiFiles, MaterialsTheFormatsCannotHoldAreRefusedAndNothingIsWritten) {
    TempDir dir;
    const MeasuredBtf btf = test::sampleBtf(3, 2);
    const osg::ref_ptr<Material> perView =
        findMethod("ptm").fit(btf, FitOptions::parse("views=all"));
    EXPECT_EQ(errorOf([&] { saveMaterial(*perView, dir.file("a.ptm")); }),
              dir.file("a.ptm") +
                  ": a .ptm file holds one view; this ptm material has one per view (views=all): "
                  "fit with views=front");
    const osg::ref_ptr<Material> hsh = findMethod("hsh").fit(btf, FitOptions());
    EXPECT_EQ(errorOf([&] { saveMaterial(*hsh, dir.file("b.ptm")); }),
              dir.file("b.ptm") + ": a .ptm file holds a ptm material, not hsh");
    EXPECT_FALSE(std::filesystem::exists(dir.file("a.ptm")));
    EXPECT_FALSE(std::filesystem::exists(dir.file("b.ptm")));
    // loadMaterial finds the format by extension, any case.
    saveMaterial(*hsh, dir.file("c.RTI"));
    EXPECT_EQ(loadMaterial(dir.file("c.RTI"))->methodName(), "hsh");
}

}  // namespace OSGBTF_TEST_FILE
