// The smooth shadow terminator's CPU reference (scene/ShadowTerminator.h, Sattler et al. 2003
// sec. 4.3) and MaterialNode's terminator and shadow properties through .osgt / .osgb. No OpenGL
// here (tests/gl/shadow_test.cpp compares the GPU with this reference).
#include <cmath>
#include <fstream>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <osgDB/ReadFile>
#include <osgDB/WriteFile>

#include "scene/MaterialNode.h"
#include "scene/ShadowTerminator.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

glm::vec3 atAngle(double degrees) {
    const double r = degrees * M_PI / 180.0;
    return glm::vec3(float(std::sin(r)), 0.0f, float(std::cos(r)));
}

}  // namespace

TEST(ShadowTerminator, CoordinateIsTheSeedsFormula) {
    const glm::vec3 n(0, 0, 1);
    // u = (1 + cos(alpha + angle)) / 2: 0.5 at angle = 90 - alpha.
    EXPECT_NEAR(terminatorCoordinate(n, n, 15), (1 + std::cos(15 * M_PI / 180)) / 2, 1e-6);
    EXPECT_NEAR(terminatorCoordinate(n, atAngle(75), 15), 0.5, 1e-6);
    EXPECT_NEAR(terminatorCoordinate(n, atAngle(90), 0), 0.5, 1e-6);
    EXPECT_NEAR(terminatorCoordinate(n, atAngle(60), 30), 0.5, 1e-6);
    EXPECT_NEAR(terminatorCoordinate(n, -n, 0), 0.0, 1e-6);
}

TEST(ShadowTerminator, StepIsABlurredBlackWhiteStep) {
    const float w = 0.1f;
    EXPECT_EQ(terminatorStep(0.0f, w), 0.0f);
    EXPECT_EQ(terminatorStep(0.45f, w), 0.0f);
    EXPECT_NEAR(terminatorStep(0.5f, w), 0.5f, 1e-6);
    EXPECT_EQ(terminatorStep(0.55f, w), 1.0f);
    EXPECT_EQ(terminatorStep(1.0f, w), 1.0f);
    EXPECT_EQ(terminatorStep(0.49f, 0.0f), 0.0f);
    EXPECT_EQ(terminatorStep(0.5f, 0.0f), 1.0f);
    float previous = 0;
    for (int i = 0; i <= 1000; ++i) {
        const float v = terminatorStep(i / 1000.0f, w);
        EXPECT_GE(v, previous);
        previous = v;
    }
    const std::vector<float> texels = terminatorTexels(w);
    ASSERT_EQ(texels.size(), std::size_t(kTerminatorTexels));
    EXPECT_EQ(texels.front(), 0.0f);
    EXPECT_EQ(texels.back(), 1.0f);
}

TEST(ShadowTerminator, SamplingIsGlsLinearFilter) {
    const std::vector<float> texels = {0.0f, 1.0f, 3.0f, 7.0f};
    // Texel centres (i + 0.5) / 4 give the texel; halfway between two centres the mean; the
    // edges clamp.
    EXPECT_FLOAT_EQ(sampleTerminatorTexels(texels, 0.125f), 0.0f);
    EXPECT_FLOAT_EQ(sampleTerminatorTexels(texels, 0.375f), 1.0f);
    EXPECT_FLOAT_EQ(sampleTerminatorTexels(texels, 0.5f), 2.0f);
    EXPECT_FLOAT_EQ(sampleTerminatorTexels(texels, 0.75f), 5.0f);
    EXPECT_FLOAT_EQ(sampleTerminatorTexels(texels, 0.8125f), 6.0f);
    EXPECT_FLOAT_EQ(sampleTerminatorTexels(texels, 0.0f), 0.0f);
    EXPECT_FLOAT_EQ(sampleTerminatorTexels(texels, 1.0f), 7.0f);
    EXPECT_FLOAT_EQ(sampleTerminatorTexels(texels, -3.0f), 0.0f);
}

TEST(ShadowTerminator, BoundaryOnACoarseSphereIsWithinOneEdgeOfTheCircle) {
    // A coarse UV sphere (12 x 6 quads, edges of 30 degrees), lit from a direction off every
    // axis. Along each edge whose vertices' u straddle 0.5 the boundary lies where linear
    // interpolation of u (the rasteriser's) crosses 0.5. Its angle from the light must be within
    // one edge length of the analytic circle 90 - alpha degrees; a per-face cut would be off by
    // up to a whole face.
    const int slices = 12, stacks = 6;
    const double alpha = kDefaultTerminatorAlpha;
    const glm::vec3 light = glm::normalize(glm::vec3(0.3f, -0.5f, 0.8f));
    auto vertex = [&](int i, int j) {
        const double phi = 2 * M_PI * i / slices, theta = M_PI * j / stacks;
        return glm::vec3(float(std::sin(theta) * std::cos(phi)),
                         float(std::sin(theta) * std::sin(phi)), float(std::cos(theta)));
    };
    int crossings = 0;
    double worst = 0, longestEdge = 0;
    auto edge = [&](const glm::vec3& a, const glm::vec3& b) {
        longestEdge = std::max(longestEdge, double(std::acos(glm::dot(a, b))));
        const float ua = terminatorCoordinate(a, light, float(alpha));
        const float ub = terminatorCoordinate(b, light, float(alpha));
        if ((ua - 0.5f) * (ub - 0.5f) >= 0) return;
        const float t = (0.5f - ua) / (ub - ua);
        const glm::vec3 p = glm::normalize(a + t * (b - a));
        const double angle = std::acos(glm::dot(p, light)) * 180 / M_PI;
        worst = std::max(worst, std::abs(angle - (90 - alpha)));
        ++crossings;
    };
    for (int j = 0; j < stacks; ++j)
        for (int i = 0; i < slices; ++i) {
            edge(vertex(i, j), vertex(i + 1, j));
            edge(vertex(i, j), vertex(i, j + 1));
            edge(vertex(i, j), vertex(i + 1, j + 1));  // the quad's diagonal
        }
    EXPECT_GE(crossings, slices);
    EXPECT_LE(worst, longestEdge * 180 / M_PI);
    // Much closer than that in fact: the angles interpolate almost linearly along a short arc.
    EXPECT_LE(worst, 3.0);
}

class TerminatorSerializer : public ::testing::TestWithParam<const char*> {};

TEST_P(TerminatorSerializer, PropertiesRoundTripAndDefaultWhenAbsent) {
    test::TempDir dir;
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    EXPECT_TRUE(node->getShadowTerminator());
    EXPECT_EQ(node->getTerminatorAlpha(), 15.0f);
    EXPECT_EQ(node->getTerminatorSoftness(), 0.1f);
    EXPECT_EQ(node->getShadowLight(), -1);
    node->setShadowTerminator(false);
    node->setTerminatorAlpha(22.5f);
    node->setTerminatorSoftness(0.25f);
    node->setShadowLight(2);
    const std::string scene = dir.file(std::string("terminator.") + GetParam());
    ASSERT_TRUE(osgDB::writeNodeFile(*node, scene));
    osg::ref_ptr<MaterialNode> read =
        dynamic_cast<MaterialNode*>(osgDB::readRefNodeFile(scene).get());
    ASSERT_NE(read, nullptr);
    EXPECT_FALSE(read->getShadowTerminator());
    EXPECT_EQ(read->getTerminatorAlpha(), 22.5f);
    EXPECT_EQ(read->getTerminatorSoftness(), 0.25f);
    EXPECT_EQ(read->getShadowLight(), 2);
}

INSTANTIATE_TEST_SUITE_P(SceneFormats, TerminatorSerializer, ::testing::Values("osgt", "osgb"));

TEST(TerminatorSerializer, OsgtWrittenBeforeItReadsWithTheDefaults) {
    // A scene file of the previous format: no terminator or shadow fields.
    test::TempDir dir;
    const std::string scene = dir.file("old.osgt");
    {
        std::ofstream out(scene);
        out << "#Ascii Scene\n#Version 161\n#Generator OpenSceneGraph 3.6.5\n\n"
               "osgBTF::MaterialNode {\n  UniqueID 1\n  TextureScale 2\n}\n";
    }
    osg::ref_ptr<MaterialNode> read =
        dynamic_cast<MaterialNode*>(osgDB::readRefNodeFile(scene).get());
    ASSERT_NE(read, nullptr);
    EXPECT_EQ(read->getTextureScale(), 2.0f);
    EXPECT_TRUE(read->getShadowTerminator());
    EXPECT_EQ(read->getTerminatorAlpha(), kDefaultTerminatorAlpha);
    EXPECT_EQ(read->getShadowLight(), -1);
}

}  // namespace OSGBTF_TEST_FILE
