// A UBO2014 .btf opens as the `fmf` material of its stored factors wherever
// a material is opened: openMaterial, MaterialNode, the osgDB plugins (osgdb_btf and the
// .btfmaterial pseudo-loader, hence osgviewer and btfviewer). Inputs are the hand-written files
// of tests/HandWrittenUbo2014.h, so the expected values come from the format's formulas. No
// OpenGL here (GPU == CPU: materials/fmf/test/fmf_native_gl_test.cpp).
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <filesystem>
#include <string>
#include <utility>
#include <vector>

#include <gtest/gtest.h>

#include <osg/Geode>
#include <osgDB/ReadFile>
#include <osgDB/Registry>
#include <osgDB/WriteFile>

#include "core/MeasuredBtf.h"
#include "loaders/LoadBtf.h"
#include "loaders/Ubo2014.h"
#include "materials/fmf/Fmf.h"
#include "scene/MaterialNode.h"
#include "scene/OpenMaterial.h"
#include "tests/HandWrittenUbo2014.h"
#include "tests/NotifyCapture.h"
#include "tests/PluginTestUtil.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using osgBTF::test::errorOf;
using osgBTF::test::HandWrittenBtf;
using osgBTF::test::TempDir;
using ReadResult = osgDB::ReaderWriter::ReadResult;
using osgBTF::test::asMaterialNode;
using osgBTF::test::readNode;
using osgBTF::test::usePluginsFromBuild;

namespace {

std::string writeFile(const TempDir& dir, const HandWrittenBtf& f, const std::string& name) {
    const std::string path = dir.file(name);
    osgBTF::test::writeTextFile(path, f.bytes);
    return path;
}

glm::vec3 direction(const std::array<double, 2>& d) {
    return Direction{float(d[0]), float(d[1])}.toVector();
}

/** The fmf material's CPU evaluator at every measured (view, light) and texel equals the format's
 *  formula. Tolerance: the files' values are exact in half, so only float arithmetic (sums,
 *  expf, direction vectors from degrees) differs from the double formula: relative 1e-5. */
void expectEvaluatesTheFormula(const Material& m, const HandWrittenBtf& f) {
    ASSERT_EQ(m.width(), f.width);
    ASSERT_EQ(m.height(), f.height);
    ASSERT_EQ(m.views().size(), f.views.size());
    ASSERT_EQ(m.lights().size(), f.lights.size());
    for (int v = 0; v < int(f.views.size()); ++v)
        for (int l = 0; l < int(f.lights.size()); ++l)
            for (int y = 0; y < f.height; ++y)
                for (int x = 0; x < f.width; ++x) {
                    const auto want = f.value(v, l, x, f.height - 1 - y);
                    const glm::vec3 got = m.evaluate(x, y, direction(f.views[std::size_t(v)]),
                                                     direction(f.lights[std::size_t(l)]));
                    for (int c = 0; c < 3; ++c)
                        ASSERT_NEAR(got[c], want[std::size_t(c)],
                                    1e-5 * std::max(1.0, std::abs(want[std::size_t(c)])))
                            << "view " << v << " light " << l << " texel " << x << "," << y
                            << " channel " << c;
                }
}

/** evaluateMeasured (what btf fit's error and btf compare use) equals the decoded file. */
void expectMeasuredEqualsDecode(const Material& m, const std::string& path) {
    const MeasuredBtf decoded = loadMeasuredBtf(path);
    std::vector<float> model(decoded.viewCount() * decoded.lightCount() * 3);
    for (std::size_t texel = 0; texel < decoded.texelCount(); ++texel) {
        m.evaluateMeasured(texel, model.data());
        const std::vector<float> want = decoded.abrdf(texel);
        for (std::size_t i = 0; i < want.size(); ++i)
            ASSERT_NEAR(model[i], want[i], 1e-5 * std::max(1.0f, std::abs(want[i])))
                << "texel " << texel << " value " << i;
    }
}

}  // namespace

TEST(NativeUbo2014, DfmfOpensAsAnFmfMaterialWithTheFilesRanks) {
    TempDir dir;
    const HandWrittenBtf f = test::handWrittenDfmf11();
    const std::string path = writeFile(dir, f, "dfmf11.btf");
    osg::ref_ptr<Material> m = openMaterial(path);
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(m->methodName(), "fmf");
    EXPECT_EQ(m->sourceFile, path);
    const auto* fmf = dynamic_cast<const FmfMaterial*>(m.get());
    ASSERT_NE(fmf, nullptr);
    EXPECT_EQ(fmf->storage(), MaterialTexture::Half);
    EXPECT_EQ(fmf->factors().model, FactorModel::Dfmf);
    EXPECT_EQ(fmf->factors().colorModel, 11);
    for (int c = 0; c < 3; ++c) EXPECT_EQ(fmf->factors().components(c), f.ranks[std::size_t(c)]);
    expectEvaluatesTheFormula(*m, f);
    expectMeasuredEqualsDecode(*m, path);
    // The file stores floats: float textures on request.
    osg::ref_ptr<Material> asFloat = openUbo2014Material(path, MaterialTexture::Float);
    EXPECT_EQ(dynamic_cast<const FmfMaterial&>(*asFloat).storage(), MaterialTexture::Float);
    expectEvaluatesTheFormula(*asFloat, f);
}

TEST(NativeUbo2014, FmfWithDrrAndCosineOpensAsStored) {
    TempDir dir;
    const HandWrittenBtf f = test::handWrittenFmfDrrCosine();
    const std::string path = writeFile(dir, f, "fmf.btf");
    osg::ref_ptr<Material> m = openMaterial(path, MaterialTexture::Float);
    const auto* fmf = dynamic_cast<const FmfMaterial*>(m.get());
    ASSERT_NE(fmf, nullptr);
    // A half file gains nothing from float textures: it stays half.
    EXPECT_EQ(fmf->storage(), MaterialTexture::Half);
    EXPECT_EQ(fmf->factors().model, FactorModel::Fmf);
    EXPECT_TRUE(fmf->factors().drr());
    EXPECT_TRUE(fmf->factors().cosine);
    EXPECT_EQ(fmf->factors().components(0), 3);
    expectEvaluatesTheFormula(*m, f);
    expectMeasuredEqualsDecode(*m, path);
}

TEST(NativeUbo2014, OpeningReadsTheTexelFactorsIntoTheMaterialAsFromFactorsConvertsThem) {
    // openMaterial hands the reader fmf's receiver (FactorHooks::receiver: SxV straight into its
    // texture, never as floats); fromFactors on the reader's floats is the reference. Same
    // textures bit for bit, for a float DFMF file (read as half and as float) and a half FMF.
    TempDir dir;
    const std::string dfmf = writeFile(dir, test::handWrittenDfmf11(), "dfmf11.btf");
    const std::string fmf = writeFile(dir, test::handWrittenFmfDrrCosine(), "fmf.btf");
    for (const auto& [path, storage] :
         std::vector<std::pair<std::string, MaterialTexture::PixelKind>>{
             {dfmf, MaterialTexture::Half},
             {dfmf, MaterialTexture::Float},
             {fmf, MaterialTexture::Half}}) {
        SCOPED_TRACE(path + " " + MaterialTexture::kindName(storage));
        Ubo2014Factors file = readUbo2014(path);
        EXPECT_EQ(file.factors[0].SxV.rows(), file.width * file.height);
        const osg::ref_ptr<FmfMaterial> reference =
            FmfMaterial::fromFactors(std::move(static_cast<FactoredBtf&>(file)),
                                     file.scalarSize == 2 ? MaterialTexture::Half : storage);
        const osg::ref_ptr<Material> opened = openUbo2014Material(path, storage);
        const FittedMaterial want = reference->toFittedMaterial(), got = opened->toFittedMaterial();
        ASSERT_EQ(got.textures.size(), want.textures.size());
        for (std::size_t t = 0; t < want.textures.size(); ++t) {
            SCOPED_TRACE(want.textures[t].name);
            EXPECT_EQ(got.textures[t].name, want.textures[t].name);
            EXPECT_EQ(got.textures[t].kind, want.textures[t].kind);
            EXPECT_EQ(got.textures[t].depth, want.textures[t].depth);
            EXPECT_EQ(got.textures[t].data, want.textures[t].data);
            EXPECT_EQ(got.textures[t].halves.size(), want.textures[t].halves.size());
            for (std::size_t i = 0; i < want.textures[t].halves.size(); ++i)
                ASSERT_EQ(got.textures[t].halves[i].bits(), want.textures[t].halves[i].bits())
                    << "value " << i;
        }
    }
}

TEST(NativeUbo2014, AHalfInfinityInTheTexelFactorsIsRefusedAsTheFloatPathRefusesIt) {
    // The FMF file ends with its SxV: its last half made +infinity.
    TempDir dir;
    HandWrittenBtf f = test::handWrittenFmfDrrCosine();
    f.bytes[f.bytes.size() - 2] = '\x00';
    f.bytes[f.bytes.size() - 1] = '\x7c';
    const std::string path = writeFile(dir, f, "inf.btf");
    EXPECT_EQ(errorOf([&] { openMaterial(path); }),
              path + ": fmf: SxV value inf exceeds the half range (65504); use storage=float");
}

TEST(NativeUbo2014, EvaluateRowEqualsEvaluateBitForBit) {
    // btf eval --cpu and Python's Material.image evaluate rows (Material::evaluateRow; fmf
    // blends its U rows once a row): the same floats as evaluate, at measured directions and
    // between them.
    TempDir dir;
    const HandWrittenBtf f = test::handWrittenDfmf11();
    const osg::ref_ptr<Material> m = openMaterial(writeFile(dir, f, "dfmf11.btf"));
    const std::vector<std::pair<glm::vec3, glm::vec3>> queries = {
        {direction(f.views[1]), direction(f.lights[2])},
        {Direction{17.5f, 33}.toVector(), Direction{41, 200}.toVector()}};
    for (const auto& [view, light] : queries)
        for (int y = 0; y < m->height(); ++y) {
            std::vector<glm::vec3> row(std::size_t(m->width()));
            m->evaluateRow(0, y, m->width(), view, light, row.data());
            for (int x = 0; x < m->width(); ++x) {
                const glm::vec3 want = m->evaluate(x, y, view, light);
                for (int c = 0; c < 3; ++c)
                    EXPECT_EQ(row[std::size_t(x)][c], want[c])
                        << "texel " << x << "," << y << " channel " << c;
            }
        }
}

TEST(NativeUbo2014, OpensWhereDecodingIsRefusedByTheMemoryGuard) {
    TempDir dir;
    const HandWrittenBtf f = test::handWrittenDfmf11();
    const std::string path = writeFile(dir, f, "dfmf11.btf");
    const Ubo2014Factors factors = readUbo2014(path);
    ASSERT_LT(factors.factorBytes() * 2, factors.decodedBytes());
    const std::uint64_t saved = memoryLimit();
    // Above the factors, below the decoded data: the native open works, a decode is refused.
    setMemoryLimit(factors.factorBytes() + 512);
    std::string problem;
    osg::ref_ptr<Material> m;
    try {
        m = openMaterial(path);
    } catch (const std::exception& e) {
        problem = e.what();
    }
    const std::string refused = errorOf([&] { loadMeasuredBtf(path); });
    setMemoryLimit(saved);
    EXPECT_EQ(problem, "");
    ASSERT_NE(m, nullptr);
    EXPECT_EQ(m->methodName(), "fmf");
    EXPECT_NE(refused.find("memory limit"), std::string::npos) << refused;
}

TEST(NativeUbo2014, BrokenFileIsAnErrorNamingIt) {
    TempDir dir;
    HandWrittenBtf f = test::handWrittenDfmf11();
    f.bytes.pop_back();
    const std::string path = writeFile(dir, f, "short.btf");
    const std::string message = errorOf([&] { openMaterial(path); });
    EXPECT_EQ(message.rfind(path + ": unexpected end of file while reading channel 2 factors", 0),
              0u)
        << message;
    const ReadResult result = readNode(path);
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message(), message);
}

TEST(NativeUbo2014, MaterialNodeOpensAndSharesTheFile) {
    TempDir dir;
    const std::string path = writeFile(dir, test::handWrittenFmfDrrCosine(), "fmf.btf");
    osg::ref_ptr<MaterialNode> a = new MaterialNode, b = new MaterialNode;
    ASSERT_TRUE(a->setMaterialFile(path)) << a->getMaterialError();
    ASSERT_TRUE(b->setMaterialFile(path));
    EXPECT_EQ(a->getMaterial()->methodName(), "fmf");
    EXPECT_EQ(a->getMaterial(), b->getMaterial());  // one material, one set of textures
    // A scene refers to the .btf by name and opens it the same way when read back.
    a->addChild(new osg::Geode);
    usePluginsFromBuild();
    const std::string scene = dir.file("scene.osgt");
    ASSERT_TRUE(osgDB::writeNodeFile(*a, scene));
    osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(scene);
    auto* node = dynamic_cast<MaterialNode*>(read.get());
    ASSERT_NE(node, nullptr);
    EXPECT_EQ(node->getMaterialFile(), path);
    ASSERT_NE(node->getMaterial(), nullptr) << node->getMaterialError();
    EXPECT_EQ(node->getMaterial()->methodName(), "fmf");
}

TEST(NativeUbo2014, PluginOpensTheStoredFactorsUnlessAMethodIsGiven) {
    TempDir dir;
    const HandWrittenBtf f = test::handWrittenDfmf11();
    const std::string path = writeFile(dir, f, "dfmf11.btf");
    test::ScopedNotifyCapture capture;
    ReadResult result = readNode(path, "scale=2 components=8 cache=" + dir.file("cache"));
    MaterialNode* node = asMaterialNode(result);
    ASSERT_NE(node, nullptr) << result.message();
    ASSERT_NE(node->getMaterial(), nullptr);
    EXPECT_EQ(node->getMaterial()->methodName(), "fmf");
    EXPECT_EQ(node->getTextureScale(), 2.0f);
    EXPECT_EQ(node->getMaterialFile(), path);
    const auto& factors = dynamic_cast<const FmfMaterial&>(*node->getMaterial()).factors();
    for (int c = 0; c < 3; ++c) EXPECT_EQ(factors.components(c), f.ranks[std::size_t(c)]);
    EXPECT_NE(capture.text().find("osgBTF: " + path +
                                  ": opening its stored factorisation as an fmf material "
                                  "(method=NAME fits a method instead); fit options without "
                                  "method= ignored: components=8"),
              std::string::npos)
        << capture.text();
    EXPECT_FALSE(fs::exists(dir.file("cache")));  // nothing fitted, nothing cached

    // storage=float applies to the stored factors; a bad value is an error naming the option.
    result = readNode(path, "storage=float");
    ASSERT_NE(asMaterialNode(result), nullptr) << result.message();
    EXPECT_EQ(dynamic_cast<const FmfMaterial&>(*asMaterialNode(result)->getMaterial()).storage(),
              MaterialTexture::Float);
    result = readNode(path, "storage=unorm8");
    EXPECT_EQ(result.status(), ReadResult::ERROR_IN_READING_FILE);
    EXPECT_EQ(result.message(),
              "option storage=unorm8: expected half or float (the textures of a UBO2014 file's "
              "stored factors)");

    // method= decodes and fits as before.
    result = readNode(path, "method=lambert cache=off");
    ASSERT_NE(asMaterialNode(result), nullptr) << result.message();
    EXPECT_EQ(asMaterialNode(result)->getMaterial()->methodName(), "lambert");
}

TEST(NativeUbo2014, PseudoLoaderPutsAModelUnderTheStoredMaterial) {
    TempDir dir;
    const std::string path = writeFile(dir, test::handWrittenFmfDrrCosine(), "carpet.btf");
    osg::ref_ptr<osg::Geode> model = new osg::Geode;
    model->setName("the model");
    usePluginsFromBuild();
    ASSERT_TRUE(osgDB::writeNodeFile(*model, dir.file("model.osgt")));
    // What `osgviewer "model.osgt.(carpet.btf,scale=4).btfmaterial"` reads.
    const ReadResult result =
        readNode(dir.file("model.osgt") + ".(" + path + ",scale=4).btfmaterial");
    MaterialNode* node = asMaterialNode(result);
    ASSERT_NE(node, nullptr) << result.message();
    ASSERT_NE(node->getMaterial(), nullptr);
    EXPECT_EQ(node->getMaterial()->methodName(), "fmf");
    EXPECT_EQ(node->getTextureScale(), 4.0f);
    ASSERT_EQ(node->getNumChildren(), 1u);
    EXPECT_EQ(node->getChild(0)->getName(), "the model");
    // With a method: fitted, as before.
    const ReadResult fitted =
        readNode(dir.file("model.osgt") + ".(" + path + ",method=lambert,cache=off).btfmaterial");
    ASSERT_NE(asMaterialNode(fitted), nullptr) << fitted.message();
    EXPECT_EQ(asMaterialNode(fitted)->getMaterial()->methodName(), "lambert");
}

}  // namespace OSGBTF_TEST_FILE
