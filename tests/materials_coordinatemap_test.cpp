// Materialising a fitted material through a coordinate map (materials/CoordinateMapRendering.h):
// for every registered method, the remapped material evaluates at texel (x, y) exactly what the
// original evaluates at map(x, y), so the CPU reference of a render through a map is the
// remapped material. The GPU half is tests/gl/coordinate_map_test.cpp.
#include <algorithm>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/ShaderSource.h"
#include "fit/MipMapping.h"
#include "harness/sample/BlockMap.h"
#include "harness/sample/SampleBtf.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/MethodPrograms.h"
#include "materials/MethodRegistry.h"
#include "materials/ShaderInterface.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

/** Every third Bonn direction: 27 views and lights keep every fit quick; interpolation still
 *  has triangles all over the hemisphere. */
DirectionSet fewDirections() {
    const DirectionSet bonn = DirectionSet::bonn81();
    std::vector<Direction> directions;
    for (std::size_t i = 0; i < bonn.size(); i += 3) directions.push_back(bonn[i]);
    return DirectionSet("bonn81/3", directions);
}

const MeasuredBtf& sample() {
    static const MeasuredBtf btf = [] {
        SampleOptions options;
        options.width = 8;
        options.height = 6;  // not square: catches swapped axes
        options.views = options.lights = fewDirections();
        return makeSampleBtf(options);
    }();
    return btf;
}

std::string testName(const ::testing::TestParamInfo<std::string>& info) {
    std::string name = info.param;
    std::replace(name.begin(), name.end(), '-', '_');
    return name;
}

}  // namespace

class CoordinateMapRemap : public ::testing::TestWithParam<std::string> {};

TEST_P(CoordinateMapRemap, RemappedMaterialEvaluatesLikeTheMapExactly) {
    const MethodInfo& info = findMethod(GetParam());
    osg::ref_ptr<Material> material = info.fit(sample(), FitOptions::parse(info.quickFitOptions));
    // Independent random texels, a size unlike the sample's in both axes: a swapped axis, a
    // row flip or a tile offset taken from the wrong size shows at almost every texel.
    const CoordinateMap map = makeBlockCoordinateMap(12, 10, 8, 6, 1, 7);
    osg::ref_ptr<Material> remapped = remapMaterial(*material, map);
    EXPECT_EQ(remapped->methodName(), material->methodName());
    EXPECT_EQ(remapped->width(), 12);
    EXPECT_EQ(remapped->height(), 10);
    for (const std::string& shared : sharedTextures(info.name))
        EXPECT_NE(material->toFittedMaterial().findTexture(shared), nullptr)
            << "declareSharedTextures names '" << shared << "', which the method lacks";

    // Measured and unmeasured directions (interpolated between measured ones).
    const std::vector<std::pair<Direction, Direction>> pairs = {
        {sample().views()[4], sample().lights()[11]},
        {{31.7f, 77}, {52, 200}},
        {{8, 11}, {68, 301}}};
    for (const auto& [view, light] : pairs)
        for (int y = 0; y < map.height; ++y)
            for (int x = 0; x < map.width; ++x) {
                const glm::vec3 expected = material->evaluate(map.sampleX(x, y), map.sampleY(x, y),
                                                              view.toVector(), light.toVector());
                const glm::vec3 got = remapped->evaluate(x, y, view.toVector(), light.toVector());
                // Exact: the same arithmetic on the same stored values.
                ASSERT_EQ(got, expected)
                    << "texel " << x << "," << y << " view " << view.theta << "/" << view.phi;
            }
    // The measured-direction path too (methods override it to skip interpolation).
    const std::size_t values = sample().views().size() * sample().lights().size() * 3;
    std::vector<float> expected(values), got(values);
    for (int y = 0; y < map.height; y += 3)
        for (int x = 0; x < map.width; x += 5) {
            material->evaluateMeasured(map.sampleTexel(x, y), expected.data());
            remapped->evaluateMeasured(std::size_t(y) * map.width + x, got.data());
            ASSERT_EQ(got, expected) << "texel " << x << "," << y;
        }
}

INSTANTIATE_TEST_SUITE_P(EveryMethod, CoordinateMapRemap, ::testing::ValuesIn(methodNames()),
                         testName);

TEST(CoordinateMapRemap, ThroughTheMapBlendsTheFourEntriesAroundACoordinate) {
    // evaluateThroughMap, the CPU reference of a render through a map: an entry's centre shows
    // its sample texel, half-way between two entries their mean, u = 0 and u = 1 (left of the
    // first centre, across the wrap) the mean of the map's last and first column, the corner the
    // mean of the four corner entries. An 8 x 4 map: entry positions and weights exact in float.
    const MethodInfo& info = findMethod("pca");
    osg::ref_ptr<Material> material = info.fit(sample(), FitOptions::parse(info.quickFitOptions));
    const CoordinateMap map = makeBlockCoordinateMap(8, 4, 8, 6, 1, 3);
    const glm::vec3 view = Direction{31.7f, 77}.toVector(), light = Direction{52, 200}.toVector();
    const auto entry = [&](int x, int y) {
        return material->evaluate(map.sampleX(x, y), map.sampleY(x, y), view, light);
    };
    const auto through = [&](float u, float v) {
        return evaluateThroughMap(*material, map, u, v, view, light);
    };
    const float scale = glm::length(entry(1, 2));
    ASSERT_GT(scale, 1e-3f);
    ASSERT_GT(glm::length(entry(1, 2) - entry(2, 2)), 1e-3f * scale) << "the entries differ";
    ASSERT_GT(glm::length(entry(7, 2) - entry(0, 2)), 1e-3f * scale);
    const auto expectNear = [&](const glm::vec3& got, const glm::vec3& expected) {
        EXPECT_LE(glm::length(got - expected), 1e-6f * scale)
            << got.x << " " << got.y << " " << got.z << " against " << expected.x << " "
            << expected.y << " " << expected.z;
    };
    expectNear(through(1.5f / 8, 2.5f / 4), entry(1, 2));
    expectNear(through(2.0f / 8, 2.5f / 4), 0.5f * (entry(1, 2) + entry(2, 2)));
    for (float u : {0.0f, 1.0f, 3.0f})
        expectNear(through(u, 2.5f / 4), 0.5f * (entry(7, 2) + entry(0, 2)));
    expectNear(through(0.0f, 0.0f),
               0.25f * (entry(7, 3) + entry(0, 3) + entry(7, 0) + entry(0, 0)));
}

TEST(CoordinateMapChain, LevelsNameTheSampleLevelTexelOfTheirFirstEntryWorkedByHand) {
    // A 4 x 4 sample's atlas (MipLayout): level 0 at (0, 0), level 1 (2 x 2) at (4, 0), level 2
    // (1 x 1) at (4, 2); 6 x 4 texels.
    CoordinateMap map(4, 2, 4, 4);
    const int entries[2][4][2] = {{{3, 1}, {0, 2}, {2, 3}, {1, 0}},
                                  {{0, 0}, {1, 1}, {2, 2}, {3, 3}}};
    for (int y = 0; y < 2; ++y)
        for (int x = 0; x < 4; ++x) {
            map.sampleX(x, y) = entries[y][x][0];
            map.sampleY(x, y) = entries[y][x][1];
        }
    const std::vector<CoordinateMap> chain = coordinateMapChain(map, MipLayout::forBase(4, 4));
    ASSERT_EQ(chain.size(), 3u);  // 4 x 2, 2 x 1, 1 x 1
    EXPECT_EQ(chain[0].coordinates, map.coordinates);
    EXPECT_EQ(chain[1].width, 2);
    EXPECT_EQ(chain[1].height, 1);
    EXPECT_EQ(chain[1].sampleWidth, 6);
    EXPECT_EQ(chain[1].sampleHeight, 4);
    // Level 1: base entries (0, 0) -> (3, 1) and (2, 0) -> (2, 3), halved, at (4, 0).
    EXPECT_EQ(chain[1].coordinates, (std::vector<std::int32_t>{5, 0, 5, 1}));
    // Level 2: base entry (0, 0) -> (3, 1), quartered: (0, 0) at (4, 2).
    EXPECT_EQ(chain[2].width, 1);
    EXPECT_EQ(chain[2].height, 1);
    EXPECT_EQ(chain[2].coordinates, (std::vector<std::int32_t>{4, 2}));

    // A map with more levels than its sample: the coarse ones name the sample's last level
    // (a 2 x 2 sample: level 1 is 1 x 1 at (2, 0)).
    CoordinateMap wide(8, 1, 2, 2);
    const std::vector<CoordinateMap> long_ = coordinateMapChain(wide, MipLayout::forBase(2, 2));
    ASSERT_EQ(long_.size(), 4u);  // 8, 4, 2, 1 entries wide
    for (std::size_t l = 1; l < long_.size(); ++l)
        for (int x = 0; x < long_[l].width; ++x) {
            EXPECT_EQ(long_[l].sampleX(x, 0), 2) << "level " << l;
            EXPECT_EQ(long_[l].sampleY(x, 0), 0) << "level " << l;
        }
    // A material without levels: the map alone.
    EXPECT_EQ(coordinateMapChain(map, MipLayout()).size(), 1u);
}

TEST(CoordinateMapChain, IdentityMapThroughTheChainIsTheMaterialsOwnTrilinearFilter) {
    // The identity map of a mip-mapped material: level l of its chain names level l's own texels,
    // so a lookup through it at any level of detail is the material's own filtered lookup, texel
    // for texel and weight for weight (the same float arithmetic: exactly equal).
    SampleOptions options;
    options.width = options.height = 8;
    options.views = options.lights = fewDirections();
    const MethodInfo& info = findMethod("pca");
    const osg::ref_ptr<Material> material =
        fitMipMapped(info, makeSampleBtf(options), FitOptions::parse(info.quickFitOptions));
    ASSERT_EQ(material->mipLayout().levelCount(), 4);
    CoordinateMap identity(8, 8, 8, 8);
    for (int y = 0; y < 8; ++y)
        for (int x = 0; x < 8; ++x) {
            identity.sampleX(x, y) = x;
            identity.sampleY(x, y) = y;
        }
    checkCoordinateMapMatches(*material, identity, "identity");  // the base's size, not the atlas's
    const std::vector<CoordinateMap> chain = coordinateMapChain(identity, material->mipLayout());
    ASSERT_EQ(chain.size(), 4u);
    const glm::vec3 view = Direction{31.7f, 77}.toVector(), light = Direction{52, 200}.toVector();
    int compared = 0;
    for (float lod : {-1.0f, 0.0f, 0.4f, 1.0f, 1.7f, 2.5f, 3.0f, 9.0f})
        for (float u : {0.03f, 0.31f, 0.5f, 0.97f, 1.6f})
            for (float v : {0.0f, 0.22f, 0.74f}) {
                const glm::vec3 own = material->evaluateFiltered(u, v, lod, view, light);
                const glm::vec3 through =
                    evaluateThroughMap(*material, chain, u, v, lod, view, light);
                EXPECT_EQ(own, through) << "lod " << lod << " at " << u << ", " << v;
                ++compared;
            }
    // The levels differ (the test would see a chain that stays at level 0).
    EXPECT_NE(evaluateThroughMap(*material, chain, 0.31f, 0.22f, 0.0f, view, light),
              evaluateThroughMap(*material, chain, 0.31f, 0.22f, 2.0f, view, light));
    EXPECT_EQ(compared, 120);
}

TEST(CoordinateMapRemap, FitOfTheMaterialisedBtfEqualsTheRemappedFit) {
    // lambert fits each texel from that texel's data alone, so fitting the synthesised BTF
    // (core's materialiseCoordinateMap of the measured data) and remapping the sample's fit must
    // give the same material, bit for bit: the two materialisations agree.
    const CoordinateMap map = makeBlockCoordinateMap(12, 10, 8, 6, 2, 3);
    const MethodInfo& lambert = findMethod("lambert");
    const FittedMaterial ofMaterialised =
        lambert.fit(materialiseCoordinateMap(sample(), map), {})->toFittedMaterial();
    const FittedMaterial remapped =
        remapMaterial(*lambert.fit(sample(), {}), map)->toFittedMaterial();
    ASSERT_EQ(ofMaterialised.textures.size(), remapped.textures.size());
    for (std::size_t i = 0; i < remapped.textures.size(); ++i)
        EXPECT_EQ(ofMaterialised.textures[i].data, remapped.textures[i].data)
            << remapped.textures[i].name;
}

TEST(CoordinateMapRemapErrors, MapForAnotherSampleSize) {
    const MethodInfo& lambert = findMethod("lambert");
    osg::ref_ptr<Material> material = lambert.fit(sample(), {});
    const CoordinateMap map = makeBlockCoordinateMap(4, 4, 8, 16, 1, 1);  // the material is 8x6
    try {
        remapMaterial(*material, map);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(),
                     "coordinate map: made for a 8x16 sample, but material 'lambert' is 8x6");
    }
    try {
        remapFittedMaterial(material->toFittedMaterial(), map);
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(),
                     "coordinate map: made for a 8x16 sample, but fitted material 'lambert' is "
                     "8x6");
    }
    material->sourceFile = "wool.btfmat";  // a loaded material is named by its file
    try {
        checkCoordinateMapMatches(*material, map, "map.exr");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(),
                     "map.exr: made for a 8x16 sample, but material 'wool.btfmat' is 8x6");
    }
}

TEST(CoordinateMapRemapErrors, MipMappedMaterialIsMatchedByItsBaseLevel) {
    // A mip-mapped 8 x 8 material's textures are a 12 x 8 atlas; a map names base texels.
    SampleOptions options;
    options.width = options.height = 8;
    options.views = options.lights = fewDirections();
    const osg::ref_ptr<Material> material =
        fitMipMapped(findMethod("lambert"), makeSampleBtf(options), {});
    ASSERT_EQ(material->width(), 12);
    EXPECT_NO_THROW(checkCoordinateMapMatches(*material, CoordinateMap(16, 16, 8, 8), "map.exr"));
    try {
        checkCoordinateMapMatches(*material, CoordinateMap(16, 16, 12, 8), "map.exr");
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(), "map.exr: made for a 12x8 sample, but material 'lambert' is 8x8");
    }
}

TEST(CoordinateMapRemapErrors, PerTexelTextureThatIsNoGridOfTiles) {
    // A table shared by all texels that its method forgot to declare: refused, not scrambled.
    FittedMaterial file = findMethod("lambert").fit(sample(), {})->toFittedMaterial();
    MaterialTexture table{"table", 7, 6, 1, 1, MaterialTexture::Float, {}};
    table.data.assign(table.valueCount(), 0.5f);
    file.textures.push_back(table);
    try {
        remapFittedMaterial(file, makeBlockCoordinateMap(4, 4, 8, 6, 1, 1));
        FAIL() << "no error";
    } catch (const Error& e) {
        EXPECT_STREQ(e.what(),
                     "fitted material 'lambert': texture 'table' (7x6) is not a grid of 8x6 "
                     "texel tiles (a method declares the tables all texels share with "
                     "declareSharedTextures)");
    }
}

TEST(CoordinateMapProgram, VariantAddsTheDefineAndThePlainProgramIsUnchanged) {
    const std::string plain = shaderSource("lambert.frag");
    const osg::Program* program = methodProgram("lambert").get();
    const osg::Program* mapped = coordinateMapProgram("lambert").get();
    ASSERT_NE(program, mapped);
    EXPECT_EQ(coordinateMapProgram("lambert").get(), mapped);  // cached per variant
    EXPECT_EQ(methodProgram("lambert").get(), program);
    const auto fragment = [](const osg::Program* p) {
        for (unsigned i = 0; i < p->getNumShaders(); ++i)
            if (p->getShader(i)->getType() == osg::Shader::FRAGMENT)
                return p->getShader(i)->getShaderSource();
        return std::string();
    };
    EXPECT_EQ(fragment(program), plain);
    const std::string variant = fragment(mapped);
    const std::string define = std::string("#define ") + shader::kCoordinateMapDefine + " 1\n";
    // Right after the #version line, which GLSL wants first.
    EXPECT_EQ(variant,
              plain.substr(0, plain.find('\n') + 1) + define + plain.substr(plain.find('\n') + 1));
    EXPECT_NE(plain.find(std::string("#ifdef ") + shader::kCoordinateMapDefine), std::string::npos);
    EXPECT_NE(plain.find(std::string("isampler2D ") + shader::kCoordinateMap), std::string::npos);
}

TEST(CoordinateMapProgram, AddShaderDefine) {
    EXPECT_EQ(addShaderDefine("#version 330\nvoid main() {}\n", "X"),
              "#version 330\n#define X 1\nvoid main() {}\n");
    EXPECT_EQ(addShaderDefine("\n  #version 330 compatibility\nint a;", "X"),
              "\n  #version 330 compatibility\n#define X 1\nint a;");
    EXPECT_EQ(addShaderDefine("void main() {}\n", "X"), "#define X 1\nvoid main() {}\n");
    EXPECT_EQ(addShaderDefine("#version 330", "X"), "#version 330\n#define X 1\n");
}

TEST(BlockMap, BlocksAreWindowsOfTheSampleAndDeterministic) {
    const CoordinateMap a = makeBlockCoordinateMap(10, 7, 6, 5, 4, 3);
    EXPECT_EQ(a.coordinates, makeBlockCoordinateMap(10, 7, 6, 5, 4, 3).coordinates);
    EXPECT_NE(a.coordinates, makeBlockCoordinateMap(10, 7, 6, 5, 4, 4).coordinates);
    validateCoordinateMap(a, "block map");
    // Inside a block, neighbours are neighbours in the sample (wrapping around).
    for (int y = 0; y < a.height; ++y)
        for (int x = 0; x + 1 < a.width; ++x)
            if ((x + 1) % 4 != 0) {
                EXPECT_EQ(a.sampleX(x + 1, y), (a.sampleX(x, y) + 1) % 6);
            }
}

}  // namespace OSGBTF_TEST_FILE
