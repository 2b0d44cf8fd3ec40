// osgBTF::EnvironmentLight (reading maps through osgDB, serialization) and per-vertex
// environment lighting of a scene with Embree visibility (environment/VertexEnvironment.h).
#include <algorithm>
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Group>
#include <osg/Image>
#include <osg/LightSource>
#include <osg/MatrixTransform>
#include <osgDB/ReadFile>
#include <osgDB/WriteFile>

#include "environment/VertexEnvironment.h"
#include "scene/EnvironmentLight.h"
#include "tests/NotifyCapture.h"
#include "tests/PluginTestUtil.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::errorOf;
using osgBTF::test::TempDir;

namespace {

constexpr double kPi = 3.14159265358979323846;

/** A W x H float RGB image whose pixel (c, r) is (c, r, 1) / 8 (rows bottom-up). */
osg::ref_ptr<osg::Image> rampImage(int width, int height) {
    osg::ref_ptr<osg::Image> image = new osg::Image;
    image->allocateImage(width, height, 1, GL_RGB, GL_FLOAT);
    image->setInternalTextureFormat(GL_RGB32F_ARB);
    float* p = reinterpret_cast<float*>(image->data());
    for (int r = 0; r < height; ++r)
        for (int c = 0; c < width; ++c, p += 3)
            p[0] = c / 8.0f, p[1] = r / 8.0f, p[2] = 1.0f / 8.0f;
    return image;
}

/** Writes a flat (not run-length encoded) Radiance file, top row first ("-Y H +X W"): OSG
 *  3.6.5's own hdr writer swaps width and height in the header, so non-square maps it writes
 *  read back wrong. */
void writeRadiance(const osg::Image& image, const std::string& path) {
    std::ofstream out(path, std::ios::binary);
    out << "#?RADIANCE\nFORMAT=32-bit_rle_rgbe\n\n-Y " << image.t() << " +X " << image.s() << "\n";
    for (int r = image.t() - 1; r >= 0; --r)
        for (int c = 0; c < image.s(); ++c) {
            const float* p = reinterpret_cast<const float*>(image.data(c, r));
            const float m = std::max({p[0], p[1], p[2]});
            unsigned char rgbe[4] = {0, 0, 0, 0};
            if (m > 1e-32f) {
                int e = 0;
                std::frexp(m, &e);
                for (int ch = 0; ch < 3; ++ch)
                    rgbe[ch] = static_cast<unsigned char>(std::ldexp(p[ch], 8 - e));
                rgbe[3] = static_cast<unsigned char>(e + 128);
            }
            out.write(reinterpret_cast<const char*>(rgbe), 4);
        }
}

/** A grid of n x n quads over [-s, s]^2 at height z, facing +Z or -Z, as indexed triangles. */
osg::ref_ptr<osg::Geometry> grid(int n, float s, float z, bool up) {
    osg::ref_ptr<osg::Geometry> g = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> v = new osg::Vec3Array;
    for (int j = 0; j <= n; ++j)
        for (int i = 0; i <= n; ++i)
            v->push_back(osg::Vec3(-s + 2 * s * i / n, -s + 2 * s * j / n, z));
    g->setVertexArray(v);
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array;
    normals->assign(v->size(), osg::Vec3(0, 0, up ? 1 : -1));
    g->setNormalArray(normals, osg::Array::BIND_PER_VERTEX);
    osg::ref_ptr<osg::DrawElementsUInt> t = new osg::DrawElementsUInt(GL_TRIANGLES);
    for (int j = 0; j < n; ++j)
        for (int i = 0; i < n; ++i) {
            const unsigned a = j * (n + 1) + i, b = a + 1, c = a + n + 1, d = c + 1;
            for (unsigned k : {a, b, d, a, d, c}) t->push_back(k);
        }
    g->addPrimitiveSet(t);
    return g;
}

/** A UV sphere of radius 1 with radial normals. */
osg::ref_ptr<osg::Geometry> sphere(int rings, int sectors) {
    osg::ref_ptr<osg::Geometry> g = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> v = new osg::Vec3Array, n = new osg::Vec3Array;
    for (int r = 0; r <= rings; ++r)
        for (int s = 0; s <= sectors; ++s) {
            const double theta = kPi * r / rings, phi = 2 * kPi * s / sectors;
            const osg::Vec3 p(std::sin(theta) * std::cos(phi), std::sin(theta) * std::sin(phi),
                              std::cos(theta));
            v->push_back(p);
            n->push_back(p);
        }
    g->setVertexArray(v);
    g->setNormalArray(n, osg::Array::BIND_PER_VERTEX);
    osg::ref_ptr<osg::DrawElementsUInt> t = new osg::DrawElementsUInt(GL_TRIANGLES);
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < sectors; ++s) {
            const unsigned a = r * (sectors + 1) + s, b = a + 1, c = a + sectors + 1, d = c + 1;
            for (unsigned k : {a, c, d, a, d, b}) t->push_back(k);
        }
    g->addPrimitiveSet(t);
    return g;
}

EnvironmentMap white(int width) {
    EnvironmentMap m;
    m.width = width;
    m.height = width / 2;
    m.rgb.assign(std::size_t(m.width) * m.height * 3, 1.0f);
    return m;
}

}  // namespace

TEST(EnvironmentLight, ReadsHdrAndExrThroughOsgDB) {
    test::usePluginsFromBuild();
    TempDir dir;
    const osg::ref_ptr<osg::Image> image = rampImage(8, 4);
    for (const std::string name : {"ramp.hdr", "ramp.exr"}) {
        if (name == "ramp.hdr")
            writeRadiance(*image, dir.file(name));
        else
            ASSERT_TRUE(osgDB::writeImageFile(*image, dir.file(name))) << name;
        osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
        light->setFile(dir.file(name));
        ASSERT_TRUE(light->hasMap()) << name << ": " << light->getError();
        const EnvironmentMap m = light->map();
        ASSERT_EQ(m.width, 8) << name;
        ASSERT_EQ(m.height, 4) << name;
        // Radiance RGBE keeps 8 mantissa bits: values of 1/8 .. 7/8 are exact in both formats.
        for (int r = 0; r < 4; ++r)
            for (int c = 0; c < 8; ++c)
                EXPECT_EQ(m.texel(c, r), glm::vec3(c / 8.0f, r / 8.0f, 1 / 8.0f))
                    << name << " texel " << c << ", " << r;
    }
}

TEST(EnvironmentLight, MissingFileIsReported) {
    test::ScopedNotifyCapture capture;
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    light->setFile("no-such-sky.hdr");
    EXPECT_FALSE(light->hasMap());
    EXPECT_EQ(light->getError(), "no-such-sky.hdr: file not found");
    EXPECT_EQ(light->getFile(), "no-such-sky.hdr");
    EXPECT_NE(capture.text().find("osgBTF::EnvironmentLight: no-such-sky.hdr: file not found"),
              std::string::npos)
        << capture.text();
    EXPECT_EQ(errorOf([&] { light->projectionMap(); }),
              "osgBTF::EnvironmentLight: no map (no-such-sky.hdr: file not found)");
}

TEST(EnvironmentLight, RoundTripsThroughOsgt) {
    test::usePluginsFromBuild();
    TempDir dir;
    writeRadiance(*rampImage(8, 4), dir.file("sky.hdr"));
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options;
    options->getDatabasePathList().push_back(dir.path().string());
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    light->setFile("sky.hdr", options.get());
    ASSERT_TRUE(light->hasMap()) << light->getError();
    light->setExposure(0.5f);
    light->setRotation(30.0f);
    light->setProjectionWidth(4);
    ASSERT_TRUE(osgDB::writeObjectFile(*light, dir.file("env.osgt")));
    osg::ref_ptr<EnvironmentLight> back =
        dynamic_cast<EnvironmentLight*>(osgDB::readRefObjectFile(dir.file("env.osgt")).get());
    ASSERT_TRUE(back);
    EXPECT_EQ(back->getFile(), "sky.hdr");
    EXPECT_EQ(back->getExposure(), 0.5f);
    EXPECT_EQ(back->getRotation(), 30.0f);
    EXPECT_EQ(back->getProjectionWidth(), 4);
    // The file is found next to the scene (osgDB's database path of the file being read).
    EXPECT_TRUE(back->hasMap()) << back->getError();
    EXPECT_EQ(back->projectionMap().width, 4);
    EXPECT_EQ(back->projectionMap().rotationDegrees, 30.0f);
}

TEST(VertexEnvironment, ConvexSphereIsUnoccluded) {
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(sphere(6, 8));
    std::size_t calls = 0;
    VertexEnvironmentOptions options;
    options.progress = [&](std::size_t, std::size_t total) {
        ++calls;
        EXPECT_EQ(total, 7u * 9u);
    };
    const std::vector<GeometryEnvironment> result =
        computeVertexEnvironment(*geode, geode.get(), DirectionSet::bonn81(), white(32), options);
    ASSERT_EQ(result.size(), 1u);
    EXPECT_EQ(calls, 7u * 9u);
    for (double omega : result[0].visibleSolidAngle) EXPECT_NEAR(omega, 2 * kPi, 1e-3);
}

TEST(VertexEnvironment, OccluderBlocksItsSolidAngle) {
    // A ground grid under a square roof [-a, a]^2 at height h (facing down): the ground's
    // centre vertex loses the roof's solid angle 4 asin(a^2 / (a^2 + h^2)) (the rectangle
    // formula on its axis). The map's 1.4 degree texels (256 wide) decide along the roof's edges,
    // about 200 texels of 6e-4 sr whose errors cancel in part: 1 % of the occluded angle.
    const float a = 1.0f, h = 1.0f;
    osg::ref_ptr<osg::Geode> ground = new osg::Geode;
    ground->addDrawable(grid(2, 3.0f, 0.0f, true));
    osg::ref_ptr<osg::Group> scene = new osg::Group;
    scene->addChild(ground);
    osg::ref_ptr<osg::Geode> roof = new osg::Geode;
    roof->addDrawable(grid(1, a, 0.0f, false));
    osg::ref_ptr<osg::MatrixTransform> lift =
        new osg::MatrixTransform(osg::Matrix::translate(0, 0, h));
    lift->addChild(roof);
    scene->addChild(lift);
    const std::vector<GeometryEnvironment> lit =
        computeVertexEnvironment(*ground, scene.get(), DirectionSet::bonn81(), white(256), {});
    ASSERT_EQ(lit.size(), 1u);
    const std::size_t centre = 1 * 3 + 1;
    ASSERT_EQ(lit[0].frames[centre].position, glm::vec3(0.0f));
    const double occluded = 4 * std::asin(a * a / (a * a + h * h));
    EXPECT_NEAR(2 * kPi - lit[0].visibleSolidAngle[centre], occluded, 0.01 * occluded);
    // A corner of the ground (-3, -3) sees the roof lower and smaller: less occluded, not zero.
    const double corner = 2 * kPi - lit[0].visibleSolidAngle[0];
    EXPECT_GT(corner, 0.01);
    EXPECT_LT(corner, occluded);
    // Without visibility nothing is lost.
    VertexEnvironmentOptions off;
    off.visibility = false;
    const std::vector<GeometryEnvironment> open =
        computeVertexEnvironment(*ground, scene.get(), DirectionSet::bonn81(), white(64), off);
    EXPECT_NEAR(open[0].visibleSolidAngle[centre], 2 * kPi, 1e-3);
}

TEST(EnvironmentLight, RepresentativeLightSourcesCarryThePowerTimesExposure) {
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    EXPECT_EQ(representativeLightSources(*light, 8)->getNumChildren(), 0u);  // no map: no lights
    light->setMap(white(32));
    light->setExposure(0.5f);
    const osg::ref_ptr<osg::Group> group = representativeLightSources(*light, 8);
    ASSERT_EQ(group->getNumChildren(), 8u);
    double red = 0;
    for (unsigned i = 0; i < 8; ++i) {
        const osg::LightSource* source = dynamic_cast<osg::LightSource*>(group->getChild(i));
        ASSERT_TRUE(source);
        red += source->getLight()->getDiffuse().r();
        EXPECT_EQ(source->getLight()->getPosition().w(), 0.0f);  // directional
    }
    // A white sphere of radiance 1 carries 4 pi, times the exposure.
    EXPECT_NEAR(red, 0.5 * 4 * kPi, 1e-4);
    EXPECT_EQ(light->getExposureUniform()->getName(), "osgBTF_envExposure");
    float exposure = 0;
    light->getExposureUniform()->get(exposure);
    EXPECT_EQ(exposure, 0.5f);
}

}  // namespace OSGBTF_TEST_FILE
