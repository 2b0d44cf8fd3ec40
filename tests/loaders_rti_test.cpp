// The RTI reader (loaders/Rti.h): light-position files written here by hand as the dome, handheld
// and RTIBuilder tools write them, malformed ones with their exact messages, and the real capture
// crop in tests/data/rti-icon-64 (MIT, see its LICENSE) read through loadMeasuredBtf, its pixels
// checked against OSG's own JPEG reader and the sRGB formula.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <fstream>

#include <glm/geometric.hpp>
#include <osg/Image>
#include <osgDB/ReadFile>
#include <osgDB/WriteFile>

#include "core/Error.h"
#include "loaders/LoadBtf.h"
#include "loaders/Rti.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using test::errorOf;
namespace fs = std::filesystem;

namespace {

std::string fixture() {
    return test::sourceDir() + "/tests/data/rti-icon-64";
}

/** A copy of the fixture in a temporary folder, with `lp` as its dirs.lp. */
void copyFixture(const test::TempDir& dir, const std::string& lp) {
    for (const auto& entry : fs::directory_iterator(fixture()))
        if (entry.path().extension() == ".jpg")
            fs::copy_file(entry.path(), dir.path() / entry.path().filename());
    test::writeTextFile(dir.file("dirs.lp"), lp);
}

float srgbToLinear(float v) {
    return v <= 0.04045f ? v / 12.92f : std::pow((v + 0.055f) / 1.055f, 2.4f);
}

}  // namespace

TEST(RtiLightPositions, ReadsWhatCaptureToolsWrite) {
    // CRLF, a blank line, a Windows path, a name with a space, a direction not of unit length.
    const std::string text =
        "3\r\n"
        "C:\\captures\\coin\\jpeg-exports\\IMG_0001.JPG 0.6 0.0 0.8\r\n"
        "\r\n"
        "my photo 2.jpg -0.30 0.40 1.2000\r\n"
        "./sub/three.png 0 0 2\r\n";
    const std::vector<RtiLight> lights = parseLightPositions(text, "x.lp");
    ASSERT_EQ(lights.size(), 3u);
    EXPECT_EQ(lights[0].image, "C:\\captures\\coin\\jpeg-exports\\IMG_0001.JPG");
    EXPECT_EQ(lights[1].image, "my photo 2.jpg");
    EXPECT_EQ(lights[2].image, "./sub/three.png");
    EXPECT_EQ(lights[1].line, 4);
    EXPECT_NEAR(lights[0].direction.x, 0.6f, 1e-7f);
    EXPECT_NEAR(lights[0].direction.z, 0.8f, 1e-7f);
    const float length = std::sqrt(0.09f + 0.16f + 1.44f);
    EXPECT_NEAR(lights[1].direction.x, -0.3f / length, 1e-7f);
    EXPECT_NEAR(lights[1].direction.y, 0.4f / length, 1e-7f);
    EXPECT_NEAR(glm::length(lights[2].direction), 1.0f, 1e-7f);
}

TEST(RtiLightPositions, MalformedFilesNameTheLine) {
    auto error = [](const std::string& text) {
        return errorOf([&] { parseLightPositions(text, "d.lp"); });
    };
    EXPECT_EQ(error(""), "d.lp: empty light-position file (expected the number of images)");
    EXPECT_EQ(error("two\na.jpg 0 0 1\n"),
              "d.lp:1: the first line must be the number of images, got 'two'");
    EXPECT_EQ(error("3\na.jpg 0 0 1\nb.jpg 0 0.5 0.5\n"),
              "d.lp:1: says 3 images, but 2 are listed");
    EXPECT_EQ(error("1\na.jpg 0 1\n"), "d.lp:2: expected 'IMAGE X Y Z', got 'a.jpg 0 1'");
    EXPECT_EQ(error("1\na.jpg 0 x 1\n"), "d.lp:2: 'x' is not a number (expected 'IMAGE X Y Z')");
    EXPECT_EQ(error("1\na.jpg 0 0 0\n"), "d.lp:2: image 'a.jpg': light direction of zero length");
    EXPECT_EQ(error("1\na.jpg 0.5 0 -0.2\n"),
              "d.lp:2: image 'a.jpg': light direction below the horizon (z = -0.2)");
    EXPECT_EQ(error("2\na.jpg 0 0 1\na.jpg 0 1 1\n"),
              "d.lp:3: image 'a.jpg' is listed twice (also on line 2)");
}

TEST(RtiCapture, TheRealCaptureReadsAsOneViewUnder72Lights) {
    const std::string folder = fixture();
    ASSERT_TRUE(isRtiCapture(folder));
    const MeasuredBtf btf = loadMeasuredBtf(folder);
    EXPECT_EQ(btf.width(), 64);
    EXPECT_EQ(btf.height(), 64);
    ASSERT_EQ(btf.viewCount(), 1u);
    ASSERT_EQ(btf.lightCount(), 72u);
    EXPECT_EQ(btf.views().name(), "rti-view");
    EXPECT_EQ(btf.views()[0].theta, 0.0f);
    EXPECT_EQ(btf.decoding, "sRGB");
    // dirs.lp's first line: image01.jpg 0.205158607891401 -0.237020612397229 0.949595268999854.
    const glm::vec3 first = btf.lights().vector(0);
    EXPECT_NEAR(first.x, 0.205158607891401f, 1e-5f);
    EXPECT_NEAR(first.y, -0.237020612397229f, 1e-5f);
    EXPECT_NEAR(first.z, 0.949595268999854f, 1e-5f);
    // Pixels: OSG's own JPEG reader (libjpeg through osgdb_jpeg, rows bottom-up as osgBTF stores
    // them) and the sRGB formula of IEC 61966-2-1. Both readers use libjpeg's default IDCT;
    // allowed one 8-bit step in case a build of them differs.
    osg::ref_ptr<osg::Image> image = osgDB::readImageFile(folder + "/image01.jpg");
    ASSERT_TRUE(image.valid());
    ASSERT_EQ(image->s(), 64);
    double worst = 0;
    for (int y = 0; y < 64; ++y)
        for (int x = 0; x < 64; ++x)
            for (int c = 0; c < 3; ++c) {
                const float byte = image->data(x, y)[c] / 255.0f;
                const float value = btf.value(0, 0, std::size_t(y) * 64 + x, c);
                worst = std::max(worst, double(std::abs(value - srgbToLinear(byte))));
            }
    EXPECT_LE(worst, srgbToLinear(1.0f) - srgbToLinear(254.0f / 255.0f));
    // Told otherwise, the same bytes are linear.
    LoadOptions linear;
    linear.curve = LoadOptions::DecodeCurve::Linear;
    const MeasuredBtf raw = loadMeasuredBtf(folder + "/dirs.lp", linear);
    EXPECT_EQ(raw.decoding, "linear");
    EXPECT_NEAR(raw.value(0, 0, 0, 0), image->data(0, 0)[0] / 255.0f, 1.0f / 255.0f);
}

TEST(RtiCapture, BadSetsAreRefusedWithTheFileAndLine) {
    const std::string lp = test::readTextFile(fixture() + "/dirs.lp");
    {
        test::TempDir dir;
        std::string missing = lp;
        missing.replace(missing.find("image05.jpg"), 11, "image99.jpg");
        copyFixture(dir, missing);
        EXPECT_EQ(
            errorOf([&] { loadMeasuredBtf(dir.path().string()); }),
            dir.file("dirs.lp") + ":6: image 'image99.jpg' not found in " + dir.path().string());
    }
    {
        test::TempDir dir;
        copyFixture(dir, lp);
        test::writeTextFile(dir.file("other.lp"), "1\nimage01.jpg 0 0 1\n");
        EXPECT_EQ(errorOf([&] { loadMeasuredBtf(dir.path().string()); }),
                  dir.path().string() +
                      ": more than one light-position file: 'dirs.lp' and 'other.lp' (name the "
                      "one to use)");
        // Naming one works.
        EXPECT_EQ(loadMeasuredBtf(dir.file("other.lp")).lightCount(), 1u);
    }
    {
        test::TempDir dir;
        copyFixture(dir, lp);
        osg::ref_ptr<osg::Image> small = osgDB::readImageFile(fixture() + "/image02.jpg");
        small->scaleImage(32, 32, 1);
        fs::remove(dir.file("image02.jpg"));
        ASSERT_TRUE(osgDB::writeImageFile(*small, dir.file("image02.jpg")));
        EXPECT_EQ(errorOf([&] { loadMeasuredBtf(dir.path().string()); }),
                  dir.path().string() +
                      ": member 'image02.jpg' is 32x32 pixels but 'image01.jpg' is 64x64");
    }
    {
        // A photo cut short (libjpeg would decode it, the rest grey, with a warning only), read in
        // memory and out of core alike; a complete one with zero padding after its end is read.
        test::TempDir dir;
        copyFixture(dir, lp);
        std::string bytes = test::readTextFile(dir.file("image07.jpg"));
        test::writeTextFile(dir.file("image07.jpg"), bytes + std::string(16, '\0'));
        EXPECT_EQ(loadMeasuredBtf(dir.path().string()).lightCount(), 72u);
        test::writeTextFile(dir.file("image07.jpg"), bytes.substr(0, bytes.size() / 2));
        const std::string message =
            dir.path().string() + ": member 'image07.jpg': truncated JPEG (no end-of-image marker)";
        EXPECT_EQ(errorOf([&] { loadMeasuredBtf(dir.path().string()); }), message);
        LoadOptions disk;
        disk.placement = LoadOptions::Placement::Disk;
        EXPECT_EQ(errorOf([&] { openBtfSource(dir.path().string(), disk); }), message);
    }
}

}  // namespace OSGBTF_TEST_FILE
