// Tests for plugins/exr (osgdb_btfexr), loaded the way applications load it: through osgDB.
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>

#include <gtest/gtest.h>

#include <Imath/half.h>
#include <OpenEXR/ImfChannelList.h>
#include <OpenEXR/ImfHeader.h>
#include <OpenEXR/ImfInputFile.h>
#include <osg/Image>
#include <osg/Texture>
#include <osgDB/ReadFile>
#include <osgDB/Registry>
#include <osgDB/WriteFile>

#include "core/FittedMaterialFile.h"
#include "core/FloatImage.h"
#include "scene/OwnPlugins.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using osgBTF::test::buildDir;
using osgBTF::test::runCommand;
using osgBTF::test::shellQuote;
using osgBTF::test::TempDir;

namespace {

/** The build's osgdb_btfexr, found through the library path like any installed plugin and
 *  reached for ".exr" through libosgBTF's alias exr -> btfexr. */
osgDB::ReaderWriter* exrPlugin() {
    static osgDB::ReaderWriter* plugin = [] {
        const std::string dir = buildDir() + "/lib";
        setenv("OSG_LIBRARY_PATH", dir.c_str(), 0);
        // The registry may exist already (other tests), so its search list is edited directly;
        // prepended, so the system plugins other tests use stay reachable.
        osgDB::FilePathList& paths = osgDB::Registry::instance()->getLibraryFilePathList();
        if (std::find(paths.begin(), paths.end(), dir) == paths.end()) paths.push_front(dir);
        osgBTF::aliasOwnPlugins();
        return osgDB::Registry::instance()->getReaderWriterForExtension("exr");
    }();
    return plugin;
}

class ExrPlugin : public ::testing::Test {
protected:
    void SetUp() override {
        ASSERT_NE(exrPlugin(), nullptr)
            << "osgdb_btfexr not found under " << buildDir() << "/lib (build target osgdb_btfexr)";
    }
    TempDir dir;
};

osg::ref_ptr<osgDB::Options> opts(const char* text) {
    return new osgDB::Options(text);
}

void oiiotool(const std::string& arguments) {
    const auto result = runCommand("oiiotool " + arguments);
    ASSERT_EQ(result.exitCode, 0) << result.output;
}

float valueAt(const osg::Image& image, int x, int row, int c) {
    const unsigned n = osg::Image::computeNumComponents(image.getPixelFormat());
    const unsigned char* p = image.data(x, row);
    if (image.getDataType() == GL_FLOAT) {
        float v;
        std::memcpy(&v, p + 4 * c, 4);
        return v;
    }
    EXPECT_EQ(image.getDataType(), GLenum(GL_HALF_FLOAT));
    EXPECT_LT(unsigned(c), n);
    Imath::half h;
    std::uint16_t bits;
    std::memcpy(&bits, p + 2 * c, 2);
    h.setBits(bits);
    return float(h);
}

osg::ref_ptr<osg::Image> floatImage(int width, int height, GLenum format, unsigned seed) {
    osg::ref_ptr<osg::Image> image = new osg::Image;
    image->allocateImage(width, height, 1, format, GL_FLOAT, 1);
    const unsigned n = osg::Image::computeNumComponents(format);
    std::mt19937 rng(seed);
    std::uniform_real_distribution<float> dist(-10.0f, 10.0f);
    float* data = reinterpret_cast<float*>(image->data());
    for (std::size_t i = 0; i < std::size_t(width) * height * n; ++i) data[i] = dist(rng);
    return image;
}

}  // namespace

TEST_F(ExrPlugin, IsRegisteredWithItsOptions) {
    const auto extensions = exrPlugin()->supportedExtensions();
    EXPECT_EQ(extensions.at("exr"), "OpenEXR float image");
    const auto options = exrPlugin()->supportedOptions();
    EXPECT_EQ(options.count("half"), 1u);
    EXPECT_EQ(options.count("float"), 1u);
}

TEST_F(ExrPlugin, ReadsOiiotoolFloatExrExactly) {
    const std::string path = dir.file("x.exr");
    oiiotool("--pattern constant:color=2.5,-1,0.25 4x3 3 -d float -o " + shellQuote(path));
    osg::ref_ptr<osg::Image> image = osgDB::readRefImageFile(path);
    ASSERT_TRUE(image.valid());
    EXPECT_EQ(image->s(), 4);
    EXPECT_EQ(image->t(), 3);
    EXPECT_EQ(image->r(), 1);
    EXPECT_EQ(image->getPixelFormat(), GLenum(GL_RGB));
    EXPECT_EQ(image->getDataType(), GLenum(GL_FLOAT));
    EXPECT_EQ(image->getInternalTextureFormat(), GLint(GL_RGB32F_ARB));
    for (int row = 0; row < 3; ++row)
        for (int x = 0; x < 4; ++x) {
            EXPECT_EQ(valueAt(*image, x, row, 0), 2.5f);
            EXPECT_EQ(valueAt(*image, x, row, 1), -1.0f);
            EXPECT_EQ(valueAt(*image, x, row, 2), 0.25f);
        }
}

TEST_F(ExrPlugin, KeepsHalfFilesHalf) {
    const std::string path = dir.file("h.exr");
    oiiotool("--pattern constant:color=2.5,-1,0.25,0.5 4x3 4 -d half -o " + shellQuote(path));
    osg::ref_ptr<osg::Image> image = osgDB::readRefImageFile(path);
    ASSERT_TRUE(image.valid());
    EXPECT_EQ(image->getPixelFormat(), GLenum(GL_RGBA));
    EXPECT_EQ(image->getDataType(), GLenum(GL_HALF_FLOAT));
    EXPECT_EQ(image->getInternalTextureFormat(), GLint(GL_RGBA16F_ARB));
    EXPECT_EQ(valueAt(*image, 3, 2, 0), 2.5f);
    EXPECT_EQ(valueAt(*image, 3, 2, 1), -1.0f);
    EXPECT_EQ(valueAt(*image, 0, 0, 3), 0.5f);
}

TEST_F(ExrPlugin, MapsOneTwoThreeAndFourChannels) {
    struct Case {
        std::vector<std::string> names;
        GLenum format;
        GLint internal;
    };
    const Case cases[] = {{{"Y"}, GL_LUMINANCE, GL_LUMINANCE32F_ARB},
                          {{"Y", "A"}, GL_LUMINANCE_ALPHA, GL_LUMINANCE_ALPHA32F_ARB},
                          {{"R", "G", "B"}, GL_RGB, GL_RGB32F_ARB},
                          {{"R", "G", "B", "A"}, GL_RGBA, GL_RGBA32F_ARB},
                          {{"depth"}, GL_LUMINANCE, GL_LUMINANCE32F_ARB}};
    for (const Case& c : cases) {
        SCOPED_TRACE(c.names.size());
        FloatImage file(3, 2, int(c.names.size()));
        file.channelNames = c.names;
        for (std::size_t i = 0; i < file.pixels.size(); ++i) file.pixels[i] = float(i) - 2.5f;
        const std::string path =
            dir.file("c" + std::to_string(c.names.size()) + c.names[0] + ".exr");
        writeFloatImage(file, path);
        osg::ref_ptr<osg::Image> image = osgDB::readRefImageFile(path);
        ASSERT_TRUE(image.valid());
        EXPECT_EQ(image->getPixelFormat(), c.format);
        EXPECT_EQ(image->getInternalTextureFormat(), c.internal);
        for (int y = 0; y < 2; ++y)
            for (int x = 0; x < 3; ++x)
                for (int ch = 0; ch < file.channels; ++ch)
                    EXPECT_EQ(valueAt(*image, x, 1 - y, ch), file.at(x, y, ch));
    }
}

TEST_F(ExrPlugin, RowZeroIsTheFilesBottomRow) {
    const std::string path = dir.file("g.exr");
    oiiotool("--pattern fill:top=1,0,0:bottom=0,0,1 4x4 3 -d float -o " + shellQuote(path));
    osg::ref_ptr<osg::Image> image = osgDB::readRefImageFile(path);
    ASSERT_TRUE(image.valid());
    EXPECT_EQ(valueAt(*image, 1, 0, 0), 0.0f);
    EXPECT_EQ(valueAt(*image, 1, 0, 2), 1.0f);
    EXPECT_EQ(valueAt(*image, 1, 3, 0), 1.0f);
    EXPECT_EQ(valueAt(*image, 1, 3, 2), 0.0f);

    FloatImage rows(2, 5, 1);
    for (int y = 0; y < 5; ++y) rows.at(0, y, 0) = rows.at(1, y, 0) = float(y);  // y = file row
    writeFloatImage(rows, dir.file("rows.exr"), true);
    image = osgDB::readRefImageFile(dir.file("rows.exr"));
    ASSERT_TRUE(image.valid());
    for (int row = 0; row < 5; ++row) EXPECT_EQ(valueAt(*image, 1, row, 0), float(4 - row));
}

TEST_F(ExrPlugin, WritesWhatOpenExrReadsBack) {
    osg::ref_ptr<osg::Image> image = floatImage(5, 3, GL_RGBA, 1);
    const std::string path = dir.file("w.exr");
    ASSERT_TRUE(osgDB::writeImageFile(*image, path));
    EXPECT_EQ(Imf::InputFile(path.c_str()).header().channels().findChannel("A")->type, Imf::FLOAT);
    const FloatImage file = readFloatImage(path);  // OpenEXR, top-down
    ASSERT_EQ(file.channels, 4);
    for (int y = 0; y < 3; ++y)
        for (int x = 0; x < 5; ++x)
            for (int c = 0; c < 4; ++c) ASSERT_EQ(file.at(x, y, c), valueAt(*image, x, 2 - y, c));

    // Writing and reading through the plugin gives the same image back.
    osg::ref_ptr<osg::Image> back = osgDB::readRefImageFile(path);
    ASSERT_TRUE(back.valid());
    EXPECT_EQ(back->getPixelFormat(), GLenum(GL_RGBA));
    EXPECT_EQ(std::memcmp(back->data(), image->data(), image->getTotalSizeInBytes()), 0);

    // "half" option: half channels with half-rounded values.
    const std::string half = dir.file("half.exr");
    ASSERT_TRUE(osgDB::writeImageFile(*image, half, opts("half").get()));
    EXPECT_EQ(Imf::InputFile(half.c_str()).header().channels().findChannel("R")->type, Imf::HALF);
    back = osgDB::readRefImageFile(half);
    ASSERT_TRUE(back.valid());
    EXPECT_EQ(back->getDataType(), GLenum(GL_HALF_FLOAT));
    EXPECT_EQ(valueAt(*back, 4, 0, 2), float(Imath::half(valueAt(*image, 4, 0, 2))));

    // Half images stay half; the "float" option widens them.
    const std::string again = dir.file("again.exr"), wide = dir.file("wide.exr");
    ASSERT_TRUE(osgDB::writeImageFile(*back, again));
    EXPECT_EQ(Imf::InputFile(again.c_str()).header().channels().findChannel("R")->type, Imf::HALF);
    ASSERT_TRUE(osgDB::writeImageFile(*back, wide, opts("float").get()));
    EXPECT_EQ(Imf::InputFile(wide.c_str()).header().channels().findChannel("R")->type, Imf::FLOAT);
    EXPECT_EQ(readFloatImage(wide).at(4, 2, 2), valueAt(*back, 4, 0, 2));

    // One channel and 8-bit data.
    osg::ref_ptr<osg::Image> gray = floatImage(3, 2, GL_LUMINANCE, 2);
    ASSERT_TRUE(osgDB::writeImageFile(*gray, dir.file("gray.exr")));
    EXPECT_EQ(readFloatImage(dir.file("gray.exr")).channelNames, std::vector<std::string>{"Y"});
    osg::ref_ptr<osg::Image> bytes = new osg::Image;
    bytes->allocateImage(2, 2, 1, GL_RGB, GL_UNSIGNED_BYTE, 1);
    for (unsigned i = 0; i < 12; ++i) bytes->data()[i] = static_cast<unsigned char>(i * 20);
    ASSERT_TRUE(osgDB::writeImageFile(*bytes, dir.file("bytes.exr")));
    const FloatImage b = readFloatImage(dir.file("bytes.exr"));
    EXPECT_EQ(b.at(0, 1, 1), 20.0f / 255.0f);  // osg row 0 is the file's last row
    EXPECT_EQ(b.at(1, 0, 2), 220.0f / 255.0f);

    for (const auto& entry : fs::directory_iterator(dir.path()))
        EXPECT_EQ(entry.path().string().find(".tmp"), std::string::npos) << entry.path();
}

TEST_F(ExrPlugin, ReadsMultiPartFittedMaterialsByPart) {
    FittedMaterial m;
    m.method = "test";
    for (const char* name : {"albedo", "normal"}) {
        MaterialTexture t;
        t.name = name;
        t.width = 3;
        t.height = 2;
        t.channels = 3;
        t.kind = name[0] == 'a' ? MaterialTexture::Half : MaterialTexture::Float;
        for (int i = 0; i < 18; ++i) t.data.push_back(float(i) + (name[0] == 'a' ? 0.0f : 0.5f));
        m.textures.push_back(t);
    }
    const std::string path = dir.file("m.exr");
    saveFittedMaterial(m, path);
    osg::ref_ptr<osg::Image> albedo = osgDB::readRefImageFile(path);
    osg::ref_ptr<osg::Image> normal = osgDB::readRefImageFile(path, opts("part=1").get());
    ASSERT_TRUE(albedo.valid());
    ASSERT_TRUE(normal.valid());
    EXPECT_EQ(albedo->getDataType(), GLenum(GL_HALF_FLOAT));
    EXPECT_EQ(normal->getDataType(), GLenum(GL_FLOAT));
    // Both bottom-up: texture rows and osg rows agree.
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 3; ++x)
            for (int c = 0; c < 3; ++c) {
                EXPECT_EQ(valueAt(*albedo, x, y, c), m.textures[0].data[(y * 3 + x) * 3 + c]);
                EXPECT_EQ(valueAt(*normal, x, y, c), m.textures[1].data[(y * 3 + x) * 3 + c]);
            }
    const auto result = exrPlugin()->readImage(path, opts("part=2").get());
    EXPECT_EQ(result.status(), osgDB::ReaderWriter::ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message(), path + ": the file has 2 part(s), no part 2");
    const auto layer = exrPlugin()->readImage(path, opts("layer=x").get());
    EXPECT_EQ(layer.message(), path + ": no layer 'x' (layers: 'albedo')");
}

TEST_F(ExrPlugin, ReadsFromStreams) {
    const std::string path = dir.file("s.exr");
    oiiotool("--pattern constant:color=2.5,-1,0.25 4x3 3 -d float -o " + shellQuote(path));
    std::ifstream in(path, std::ios::binary);
    auto result = exrPlugin()->readImage(in);
    ASSERT_TRUE(result.success()) << result.message();
    EXPECT_EQ(valueAt(*result.getImage(), 3, 2, 1), -1.0f);

    std::stringstream garbage("not an exr");
    EXPECT_EQ(exrPlugin()->readImage(garbage).message(),
              "<stream>: not an OpenEXR file (wrong magic number)");

    std::stringstream out;
    ASSERT_TRUE(exrPlugin()->writeImage(*result.getImage(), out).success());
    std::istringstream again(out.str());
    auto back = exrPlugin()->readImage(again);
    ASSERT_TRUE(back.success()) << back.message();
    EXPECT_EQ(valueAt(*back.getImage(), 0, 0, 0), 2.5f);
}

TEST_F(ExrPlugin, BadFilesFailCleanlyWithAMessage) {
    using RR = osgDB::ReaderWriter::ReadResult;
    const std::string good = dir.file("good.exr");
    FloatImage noise(64, 64, 3);
    std::mt19937 rng(1);
    for (float& v : noise.pixels) v = float(rng() % 1000) / 7.0f;
    writeFloatImage(noise, good);
    const std::string data = test::readTextFile(good);
    for (std::size_t keep : {data.size() / 2, std::size_t(50)}) {
        const std::string cut = dir.file("cut" + std::to_string(keep) + ".exr");
        test::writeTextFile(cut, data.substr(0, keep));
        EXPECT_FALSE(osgDB::readRefImageFile(cut).valid());
        const RR result = exrPlugin()->readImage(cut);
        EXPECT_EQ(result.status(), RR::ERROR_IN_READING_FILE);
        EXPECT_EQ(result.message().rfind(cut + ": ", 0), 0u) << result.message();
        EXPECT_GT(result.message().size(), cut.size() + 10) << result.message();
    }

    const std::string png = dir.file("p.png"), renamed = dir.file("png.exr");
    oiiotool("--pattern constant:color=0.5 4x4 3 -d uint8 -o " + shellQuote(png));
    fs::copy_file(png, renamed);
    EXPECT_FALSE(osgDB::readRefImageFile(renamed).valid());
    EXPECT_EQ(exrPlugin()->readImage(renamed).message(),
              renamed + ": not an OpenEXR file (wrong magic number)");

    const std::string empty = dir.file("empty.exr");
    test::writeTextFile(empty, "");
    EXPECT_EQ(exrPlugin()->readImage(empty).message(), empty + ": file is empty");

    EXPECT_EQ(exrPlugin()->readImage(dir.file("missing.exr")).status(), RR::FILE_NOT_FOUND);
    EXPECT_EQ(exrPlugin()->readImage(png).status(), RR::FILE_NOT_HANDLED);

    using WR = osgDB::ReaderWriter::WriteResult;
    osg::ref_ptr<osg::Image> volume = new osg::Image;
    volume->allocateImage(2, 2, 2, GL_RGB, GL_FLOAT, 1);
    const WR r3d = exrPlugin()->writeImage(*volume, dir.file("v.exr"));
    EXPECT_EQ(r3d.status(), WR::ERROR_IN_WRITING_FILE);
    EXPECT_EQ(r3d.message(), dir.file("v.exr") + ": 3D images (r = 2) cannot be written as EXR");
    EXPECT_FALSE(fs::exists(dir.file("v.exr")));

    osg::ref_ptr<osg::Image> big = floatImage(2, 1, GL_LUMINANCE, 3);
    reinterpret_cast<float*>(big->data())[1] = 1e6f;
    const WR overflow = exrPlugin()->writeImage(*big, good, opts("half").get());
    EXPECT_EQ(overflow.message(), good +
                                      ": 1 values exceed the half-float range (65504); write "
                                      "with the \"float\" option");
    EXPECT_EQ(test::readTextFile(good), data);  // the failed write left the old file alone

    const WR nowhere = exrPlugin()->writeImage(*big, dir.file("no/such.exr"));
    EXPECT_EQ(nowhere.status(), WR::ERROR_IN_WRITING_FILE);
    EXPECT_NE(nowhere.message().find(dir.file("no/such.exr")), std::string::npos);
}

}  // namespace OSGBTF_TEST_FILE
