// Method "rbf" (materials/rbf/Rbf.h): the weights as relight computes them (hand-worked values),
// the fit (a lossless PCA with a narrow sigma reproduces the measured values; fewer planes keep
// less), the file round trip, memory, and relight's web layout of types rbf and bilinear
// (colorspace mrgb) read from the fixtures of tests/data/rti-files/make_fixtures.py (numpy and
// Pillow; nothing of osgBTF), with hostile variants refused by one exact line each.
//
// JPEG bound: the fixtures' planes decode within 1 byte of the intended ones (the script checks);
// the tolerances allow 2 bytes, 2 / 255 = 0.0078 per coefficient, times the largest sum of |E_p|
// over the planes of a node (rbf fixture: 1 + 2 + 0.5 = 3.5, so 0.028; bilinear: 1 + 0 + 0).
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/RelightFolder.h"
#include "materials/rbf/Rbf.h"
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
const glm::vec3 kL0(0.6f, 0, 0.8f);
const glm::vec3 kL1(0, 0.6f, 0.8f);  // y up the image
const glm::vec3 kL2(0, 0, 1);

void expectNear(const glm::vec3& got, const glm::vec3& want, float tolerance,
                const std::string& where) {
    for (int c = 0; c < 3; ++c)
        EXPECT_NEAR(got[c], want[c], tolerance) << where << " channel " << c;
}

std::string copyFolder(const TempDir& dir, const std::string& name) {
    const fs::path to = dir.path() / name;
    fs::copy(fixture(name), to, fs::copy_options::recursive);
    return to.string();
}

void editInfo(const std::string& folder, const std::string& from, const std::string& to) {
    const std::string path = folder + "/info.json";
    std::string text = osgBTF::test::readTextFile(path);
    const std::size_t at = text.find(from);
    ASSERT_NE(at, std::string::npos) << from;
    text.replace(at, from.size(), to);
    osgBTF::test::writeTextFile(path, text);
}

/** Three nodes at kL0, kL1, kL2, one plane, node i's mean profile = (i + 1) / 10 grey, E_1 = 0. */
osg::ref_ptr<RbfMaterial> threeNodes(float sigma) {
    const DirectionSet lights("three", {Direction::fromVector(kL0), Direction::fromVector(kL1),
                                        Direction::fromVector(kL2)});
    osg::ref_ptr<RbfMaterial> m = RbfMaterial::create(1, 1, DirectionSet("v", {{0, 0}}), lights, 1,
                                                      3, sigma, 0, MaterialTexture::Float);
    const glm::vec3 nodes[3] = {kL0, kL1, kL2};
    for (int i = 0; i < 3; ++i) {
        m->setNode(i, nodes[i]);
        m->setBasisValue(0, i, glm::vec3(float(i + 1) / 10));
    }
    return m;
}

/** A small capture: 6 x 5 texels, one view, 4 lights, values that differ per texel, light and
 *  channel. */
MeasuredBtf smallCapture() {
    const DirectionSet lights("four", {{0, 0}, {40, 0}, {40, 120}, {60, 240}});
    MeasuredBtf btf(6, 5, DirectionSet("front", {{0, 0}}), lights);
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        for (std::size_t l = 0; l < 4; ++l)
            for (int c = 0; c < 3; ++c)
                btf.setValue(0, l, t, c,
                             0.1f + 0.05f * float(t % 7) + 0.2f * float(l) * float(c + 1) / 3 +
                                 0.03f * float((t * 5 + l * 3 + std::size_t(c)) % 4));
    return btf;
}

}  // namespace

// ---- the weights -------------------------------------------------------------------------------

TEST(RbfWeights, NormalisedGaussiansOfTheDistanceToEachLight) {
    // sigma 0.5 at kL2: |kL2 - kL0|^2 = |kL2 - kL1|^2 = 0.36 + 0.04 = 0.4, g = exp(-0.4 / 0.25)
    // = 0.201897 for both, 1 for kL2 itself: weights 0.201897 / 1.403793 = 0.143822 and
    // 1 / 1.403793 = 0.712356, all above the threshold.
    const osg::ref_ptr<RbfMaterial> m = threeNodes(0.5f);
    const auto w = m->lightWeights(kL2);
    ASSERT_EQ(w.size(), 3u);
    EXPECT_NEAR(w[0].second, 0.143822f, 1e-5f);
    EXPECT_NEAR(w[1].second, 0.143822f, 1e-5f);
    EXPECT_NEAR(w[2].second, 0.712356f, 1e-5f);
    // The value is the weighted mean profiles: 0.1 w0 + 0.2 w1 + 0.3 w2 = 0.256853.
    expectNear(m->evaluate(0, 0, kView, kL2), glm::vec3(0.256853f), 1e-5f, "sigma 0.5");
}

TEST(RbfWeights, WeightsAtOrBelowTheThresholdAreDroppedAndTheRestRenormalised) {
    // sigma 0.2: the other nodes weigh exp(-10) / (1 + 2 exp(-10)) = 4.54e-5 <= 0.001: dropped.
    const osg::ref_ptr<RbfMaterial> m = threeNodes(0.2f);
    const auto w = m->lightWeights(kL2);
    ASSERT_EQ(w.size(), 1u);
    EXPECT_EQ(w[0].first, 2);
    EXPECT_EQ(w[0].second, 1.0f);
    // Between kL0 and kL2 (l = normalise(0.3, 0, 0.954)): d^2 to kL0 0.114, to kL2 0.092, to
    // kL1 0.474; relative to the nearest, g = 0.583, 1 and exp(-9.54) = 7.2e-5, whose share
    // 4.5e-5 is dropped: the two kept are renormalised to sum 1.
    const glm::vec3 between = glm::normalize(glm::vec3(0.3f, 0, 0.954f));
    const auto b = m->lightWeights(between);
    ASSERT_EQ(b.size(), 2u);
    EXPECT_EQ(b[0].first, 0);
    EXPECT_EQ(b[1].first, 2);
    const float d0 = glm::dot(between - kL0, between - kL0),
                d2 = glm::dot(between - kL2, between - kL2);
    const float e0 = std::exp(-d0 / 0.04f), e2 = std::exp(-d2 / 0.04f);
    EXPECT_NEAR(b[0].second, e0 / (e0 + e2), 1e-5f);
    EXPECT_NEAR(b[1].second, e2 / (e0 + e2), 1e-5f);
    EXPECT_NEAR(b[0].second + b[1].second, 1.0f, 1e-6f);
}

TEST(RbfWeights, FarFromEveryLightTheNearestWinsInsteadOfZeroOverZero) {
    // sigma 0.001: exp(-d^2 / sigma^2) underflows for every node at a grazing light; the weights
    // are taken relative to the nearest node, so it gets weight 1.
    const osg::ref_ptr<RbfMaterial> m = threeNodes(0.001f);
    const auto w = m->lightWeights(glm::normalize(glm::vec3(-1, -1, 0.2f)));
    ASSERT_EQ(w.size(), 1u);
    EXPECT_EQ(w[0].second, 1.0f);
    EXPECT_TRUE(std::isfinite(m->evaluate(0, 0, kView, glm::vec3(-1, 0, 0)).r));
}

// ---- the fit -----------------------------------------------------------------------------------

TEST(RbfFit, AllPlanesAndANarrowSigmaReproduceTheMeasuredValues) {
    // 4 lights: profiles of 12 values; 12 planes keep every direction of the PCA, and sigma
    // 0.01 gives each measured light its own node alone (the others weigh exp(-d^2 / 1e-4) with
    // d^2 >= 0.4). Stored as float: what remains is float rounding.
    const MeasuredBtf btf = smallCapture();
    const osg::ref_ptr<RbfMaterial> m =
        RbfMaterial::fit(btf, FitOptions::parse("planes=12 sigma=0.01 storage=float"));
    ASSERT_EQ(m->planes(), 12);
    ASSERT_EQ(m->nodeCount(), 4);
    double worst = 0;
    for (std::size_t t = 0; t < btf.texelCount(); ++t)
        for (std::size_t l = 0; l < 4; ++l) {
            const glm::vec3 v = m->evaluate(int(t % 6), int(t / 6), kView, btf.lights().vector(l));
            for (int c = 0; c < 3; ++c)
                worst = std::max(worst, double(std::abs(v[c] - btf.value(0, l, t, c))));
        }
    EXPECT_LT(worst, 1e-5);
    EXPECT_EQ(m->fitInfo.at("variance-kept"), "1");
}

TEST(RbfFit, FewerPlanesKeepLessAndEvaluateMeasuredEqualsEvaluate) {
    const MeasuredBtf btf = smallCapture();
    double previous = 1e9;
    for (const int planes : {1, 2, 4, 8}) {
        const osg::ref_ptr<RbfMaterial> m =
            RbfMaterial::fit(btf, FitOptions::parse("sigma=0.01 planes=" + std::to_string(planes)));
        double error = 0;
        std::vector<float> abrdf(4 * 3);
        for (std::size_t t = 0; t < btf.texelCount(); ++t) {
            m->evaluateMeasured(t, abrdf.data());
            for (std::size_t l = 0; l < 4; ++l) {
                const glm::vec3 v =
                    m->evaluate(int(t % 6), int(t / 6), kView, btf.lights().vector(l));
                for (int c = 0; c < 3; ++c) {
                    EXPECT_EQ(abrdf[l * 3 + std::size_t(c)], v[c]);
                    const double d = v[c] - btf.value(0, l, t, c);
                    error += d * d;
                }
            }
        }
        // The PCA is nested: each added plane can only lower the squared error (half storage
        // adds at most its rounding).
        EXPECT_LE(error, previous + 1e-4) << planes << " planes";
        previous = error;
    }
}

TEST(RbfFit, OptionsAreChecked) {
    const MeasuredBtf btf = smallCapture();
    EXPECT_EQ(errorOf([&] { RbfMaterial::fit(btf, FitOptions::parse("planes=13")); }),
              "rbf: option planes 13 exceeds 3 x lights (12) or the texels (30)");
    EXPECT_NE(errorOf([&] {
                  RbfMaterial::fit(btf, FitOptions::parse("planes=0"));
              }).find("rbf: option planes must be"),
              std::string::npos);
    EXPECT_NE(errorOf([&] {
                  RbfMaterial::fit(btf, FitOptions::parse("sigma=0"));
              }).find("rbf: option sigma must be"),
              std::string::npos);
}

TEST(RbfFit, SavedAndLoadedItEvaluatesTheSameAndCountsItsBytes) {
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;
    sample.views = DirectionSet("front", {{0, 0}});
    const MeasuredBtf btf = makeSampleBtf(sample);
    const osg::ref_ptr<RbfMaterial> m = RbfMaterial::fit(btf, FitOptions::parse("planes=4"));
    TempDir dir;
    saveMaterial(*m, dir.file("m.exr"));
    const osg::ref_ptr<Material> loaded = loadMaterial(dir.file("m.exr"));
    ASSERT_EQ(loaded->methodName(), std::string("rbf"));
    for (const glm::vec3& light : {kL0, kL1, kL2, glm::normalize(glm::vec3(-0.3f, 0.5f, 0.6f))})
        for (int y = 0; y < 6; y += 5)
            for (int x = 0; x < 8; x += 3)
                EXPECT_EQ(loaded->evaluate(x, y, kView, light), m->evaluate(x, y, kView, light));
    // 4 planes: 2 half RGB layers per texel = 12 bytes; shared: the basis 5 x 81 and the nodes
    // 81 x 1, float RGB, over 48 texels.
    const MemoryFootprint f = m->memory();
    EXPECT_DOUBLE_EQ(f.bytesPerTexel, 12.0 + (5 * 81 + 81) * 3 * 4 / 48.0);
    EXPECT_EQ(f.sharedBytes, std::uint64_t((5 * 81 + 81) * 3 * 4));
}

// ---- relight's web layout ----------------------------------------------------------------------

TEST(RelightRbf, ReadsTheBasisThePlanesAndSigmaAsRelightComputesThem) {
    const std::string info = fixture("relight-rbf-mrgb/info.json");
    const osg::ref_ptr<Material> loaded = loadMaterial(info);
    ASSERT_EQ(loaded->methodName(), std::string("rbf"));
    const RbfMaterial& m = static_cast<const RbfMaterial&>(*loaded);
    EXPECT_EQ(m.planes(), 3);
    EXPECT_EQ(m.nodeCount(), 3);
    EXPECT_FLOAT_EQ(m.sigma(), 0.2f);
    // Basis: mean / 255 and (b - 127) / range.
    expectNear(m.basisValue(0, 0), glm::vec3(0.2f, 0.4f, 0.6f), 1e-6f, "mean 0");
    expectNear(m.basisValue(2, 2), glm::vec3(2, 0, 0), 1e-6f, "E_2 node 2");
    expectNear(m.basisValue(3, 0), glm::vec3(-0.5f, 0, 0), 1e-6f, "E_3 node 0");
    expectNear(m.basisValue(3, 2), glm::vec3(0, 0.5f, 0), 1e-6f, "E_3 node 2");
    // sigma 0.2: at a node only that node counts. Top row (y = 2, rows bottom-up), a = (0.3,
    // 0.1, -0.3); below, a = (0.5, -0.1, 0.1).
    //   node 2: (0.8, 0.6, 0) + a_1 (0, 0, -1) + a_2 (2, 0, 0) + a_3 (0, 0.5, 0)
    //   node 0: (0.2, 0.4, 0.6) + a_1 (1, 0, 0) + a_3 (-0.5, 0, 0)
    //   node 1: (0.4, 0.4, 0.4) + a_1 (0, 1, 0)
    const float tol = 0.028f;
    expectNear(m.evaluate(1, 2, kView, kL2), glm::vec3(1.0f, 0.45f, -0.3f), tol, "top, light 2");
    expectNear(m.evaluate(1, 0, kView, kL2), glm::vec3(0.6f, 0.65f, -0.5f), tol, "low, light 2");
    expectNear(m.evaluate(3, 2, kView, kL0), glm::vec3(0.65f, 0.4f, 0.6f), tol, "top, light 0");
    expectNear(m.evaluate(0, 1, kView, kL0), glm::vec3(0.65f, 0.4f, 0.6f), tol, "low, light 0");
    // Light 1 is y up: the top row's a_1 = 0.3 lifts green to 0.7, the rows below 0.9.
    expectNear(m.evaluate(2, 2, kView, kL1), glm::vec3(0.4f, 0.7f, 0.4f), tol, "top, light 1");
    expectNear(m.evaluate(2, 1, kView, kL1), glm::vec3(0.4f, 0.9f, 0.4f), tol, "low, light 1");
}

TEST(RelightRbf, SigmaComesFromInfoJson) {
    // sigma 0.5: at light 2 the weights 0.143822, 0.143822, 0.712356 (RbfWeights above) blend
    // the top row's node profiles (0.65, 0.4, 0.6), (0.4, 0.7, 0.4), (1.0, 0.45, -0.3).
    TempDir dir;
    const std::string f = copyFolder(dir, "relight-rbf-mrgb");
    editInfo(f, "\"sigma\": 0.2", "\"sigma\": 0.5");
    const osg::ref_ptr<Material> m = loadMaterial(f + "/info.json");
    const glm::vec3 want = 0.143822f * glm::vec3(0.65f, 0.4f, 0.6f) +
                           0.143822f * glm::vec3(0.4f, 0.7f, 0.4f) +
                           0.712356f * glm::vec3(1.0f, 0.45f, -0.3f);
    expectNear(m->evaluate(1, 2, kView, kL2), want, 0.028f, "sigma 0.5");
}

TEST(RelightRbf, BilinearReadsTheOctahedralGridWeights) {
    // 2 x 2 grid, mean profiles red, green, blue, black at nodes (0, 0), (1, 0), (0, 1), (1, 1);
    // E_1 = 1 everywhere, a_1 = 0.3. Light (0, 0, 1): u = v = 0.5, each node 1/4: 0.25 + 0.3.
    // Light (0.6, 0, 0.8): s = 1.4, u = (0.6 / 1.4 + 1) / 2 = 0.714286, v = (-0.6 / 1.4 + 1) / 2
    // = 0.285714: weights (1-u)(1-v) = 0.204082, u(1-v) = 0.510204, (1-u)v = 0.081633, uv =
    // 0.204082.
    const osg::ref_ptr<Material> loaded = loadMaterial(fixture("relight-bilinear-mrgb/info.json"));
    ASSERT_EQ(loaded->methodName(), std::string("rbf"));
    EXPECT_EQ(static_cast<const RbfMaterial&>(*loaded).resolution(), 2);
    const float tol = 2.0f / 255;
    expectNear(loaded->evaluate(0, 0, kView, kL2), glm::vec3(0.55f), tol, "light (0, 0, 1)");
    expectNear(loaded->evaluate(3, 2, kView, kL0),
               glm::vec3(0.204082f + 0.3f, 0.510204f + 0.3f, 0.081633f + 0.3f), tol,
               "light (0.6, 0, 0.8)");
}

TEST(RelightRbf, MyccReadsItsLuminanceAndChromaPlanesAsRelightRendersThem) {
    // Only node 2 is non-zero (make_fixtures.py): at light 2 (sigma 0.2: node 2 alone), (Y, Co,
    // Cg) = mean (0.6, 0.2, 0) + 0.3 E_1 + 0.1 E_2 - 0.1 E_3 + 0.1 E_4 = (1.0, 0.3, -0.1), the
    // basis channels relight's renderer ignores left out; RGB: tmp = Y - Cg / 2 = 1.05, G = Cg +
    // tmp = 0.95, B = tmp - Co / 2 = 0.9, R = B + Co = 1.2. JPEG bound: 2 bytes, 0.0078, on each
    // coefficient; Y holds two: |dR| <= 0.0157 + 0.0039 + 0.0039 = 0.024.
    const osg::ref_ptr<Material> m = loadMaterial(fixture("relight-rbf-mycc/info.json"));
    ASSERT_EQ(m->methodName(), std::string("rbf"));
    EXPECT_EQ(static_cast<const RbfMaterial&>(*m).planes(), 4);
    expectNear(m->evaluate(2, 1, kView, kL2), glm::vec3(1.2f, 0.95f, 0.9f), 0.025f, "light 2");
    expectNear(m->evaluate(2, 1, kView, kL0), glm::vec3(0.0f), 1e-6f, "light 0");
    EXPECT_NE(relightInfo(fixture("relight-rbf-mycc/info.json"))
                  .find("type rbf, colorspace mycc, 4 planes (4 terms) in 2 JPEGs"),
              std::string::npos);
}

TEST(RelightRbf, InfoNamesTheBasis) {
    const std::string rbf = relightInfo(fixture("relight-rbf-mrgb/info.json"));
    EXPECT_NE(rbf.find("type rbf, colorspace mrgb, 3 planes (3 terms) in 1 JPEGs, 4x3"),
              std::string::npos)
        << rbf;
    EXPECT_NE(rbf.find("basis: the lights' PCA profiles, Gaussian weights, sigma 0.2"),
              std::string::npos)
        << rbf;
    const std::string bilinear = relightInfo(fixture("relight-bilinear-mrgb/info.json"));
    EXPECT_NE(bilinear.find("basis: PCA profiles on a 2x2 octahedral grid, bilinear weights"),
              std::string::npos)
        << bilinear;
}

TEST(RelightRbfErrors, HostileFoldersAreRefusedWithOneLineNamingTheFile) {
    TempDir dir;
    const std::string f = copyFolder(dir, "relight-rbf-mrgb");
    const std::string info = f + "/info.json";
    const auto problem = [&] { return errorOf([&] { loadMaterial(info); }); };
    editInfo(f, "\"sigma\": 0.2", "\"sigma\": 0");
    EXPECT_EQ(problem(), info + ": \"sigma\" 0 is not positive");
    // A sigma whose 1 / sigma^2 is no finite float.
    editInfo(f, "\"sigma\": 0", "\"sigma\": 1e-20");
    EXPECT_EQ(problem(), info + ": rbf: sigma 1e-20 is not in 1e-06..1e+06");
    editInfo(f, "\"sigma\": 1e-20", "\"sigma\": 0");
    editInfo(f, "\"sigma\": 0", "\"sigmaX\": 0.2");
    EXPECT_EQ(problem(), info + ": no \"sigma\" (type rbf)");
    editInfo(f, "\"sigmaX\": 0.2", "\"sigma\": 0.2");
    editInfo(f, "\"range\": [\n    127,", "\"range\": [\n    0,");
    EXPECT_EQ(problem(), info + ": materials[0].range[0] is 0");
    editInfo(f, "\"range\": [\n    0,", "\"range\": [\n");
    EXPECT_EQ(problem(), info + ": materials[0].range has 2 values, \"nplanes\" is 3");
    editInfo(f, "\"range\": [\n", "\"range\": [\n    127,");
    editInfo(f, "\"basis\": [\n  51,", "\"basis\": [\n");
    EXPECT_EQ(problem(), info + ": \"basis\" has 35 values, (nplanes + 1) x 3 lights x 3 is 36");
    editInfo(f, "\"basis\": [\n", "\"basis\": [\n  \"51\",");
    EXPECT_EQ(problem(), info + ": \"basis\"[0] is not a number");
    editInfo(f, "\"51\",", "51,");
    editInfo(f, "\"mrgb\"", "\"rgb\"");
    EXPECT_EQ(problem(),
              info +
                  ": type 'rbf' with colorspace 'rgb' (relight writes its PCA types in mrgb or "
                  "mycc)");
    editInfo(f, "\"rgb\"", "\"ycc\"");
    EXPECT_EQ(problem(), info + ": colorspace 'ycc' is not read (rgb, lrgb, mrgb and mycc are)");
    // mycc counts its planes in "yccplanes", which this file lacks.
    editInfo(f, "\"ycc\"", "\"mycc\"");
    EXPECT_EQ(problem(), info + ": no \"yccplanes\" (colorspace mycc)");
    editInfo(f, "\"nplanes\": 3", "\"yccplanes\": [1, 1, 2]");
    EXPECT_EQ(problem(), info +
                             ": \"yccplanes\" [1,1,2] (relight's renderer reads luminance "
                             "planes >= chroma planes, the two chroma counts equal)");
    editInfo(f, "\"yccplanes\": [1, 1, 2]", "\"nplanes\": 3");
    editInfo(f, "\"mycc\"", "\"mrgb\"");
    editInfo(f, "\"rbf\"", "\"ptm\"");
    EXPECT_EQ(problem(), info +
                             ": colorspace mrgb with type 'ptm' (relight writes mrgb and mycc "
                             "for its PCA types: bilinear, rbf)");
    editInfo(f, "\"ptm\"", "\"rbf\"");
    // Without lights an rbf has no nodes.
    editInfo(f, "\"lights\"", "\"lightsX\"");
    EXPECT_EQ(problem(), info + ": no \"lights\" (type rbf interpolates between them)");
    editInfo(f, "\"lightsX\"", "\"lights\"");
    EXPECT_EQ(loadMaterial(info)->methodName(), std::string("rbf"));  // restored

    const std::string g = copyFolder(dir, "relight-bilinear-mrgb");
    const std::string ginfo = g + "/info.json";
    editInfo(g, "\"resolution\": 2", "\"resolution\": 1");
    EXPECT_EQ(errorOf([&] { loadMaterial(ginfo); }), ginfo + ": \"resolution\" 1 is not 2..64");
    editInfo(g, "\"resolution\": 1", "\"resolution\": 3");
    EXPECT_EQ(errorOf([&] { loadMaterial(ginfo); }),
              ginfo + ": \"basis\" has 48 values, (nplanes + 1) x 9 grid nodes x 3 is 108");
}

TEST(RelightRbf, RbfIsARegisteredMethodAndRelightType) {
    ASSERT_NE(findMethodIfRegistered("rbf"), nullptr);
    const std::vector<std::string> types = relightTypes();
    EXPECT_NE(std::find(types.begin(), types.end(), "rbf"), types.end());
    EXPECT_NE(std::find(types.begin(), types.end(), "bilinear"), types.end());
}

}  // namespace OSGBTF_TEST_FILE
