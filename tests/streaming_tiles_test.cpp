// BSVTF tile sets (streaming/TileLayout.h, TileSet.h, TileBuilder.h): the pyramid's geometry
// worked out by hand, the index read from hand-written text, and tiles, weights and padding
// checked against values computed here from the texture's formula, not from the builder.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <iostream>

#include "core/ImageSimilarity.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/fmf/Fmf.h"
#include "streaming/TileBuilder.h"
#include "streaming/TileLayout.h"
#include "streaming/TileSet.h"
#include "tests/RandomFactors.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::errorOf;

namespace {

// Failure cases first, with their exact messages.
TEST(TileLayout, RefusesSizesTheCodecOrThePyramidCannotHold) {
    EXPECT_EQ(errorOf([] { TileLayout(0, 5, 1); }),
              "tile layout: the texture must have at least 1 x 1 texels, got 0x5");
    EXPECT_EQ(errorOf([] { TileLayout(4, 4, 0); }),
              "tile layout: at least one group of components is needed, got 0");
    EXPECT_EQ(errorOf([] { TileLayout(64, 64, 1, 12); }),
              "tile layout: the tile size must be a positive multiple of 8 (the codec's DCT "
              "blocks), got 12");
    EXPECT_EQ(errorOf([] { TileLayout(64, 64, 1, 64, 3); }),
              "tile layout: the padding must be at most the tile size and make T + 2 P a "
              "multiple of 8, got 3");
}

TEST(TileLayout, LevelsAndTilesOfA400TexelMaterialAsWorkedOutByHand) {
    // 400 / 2^3 = 50 <= 64 < 400 / 2^2 = 100: four levels of 50, 100, 200, 400 texels, with
    // 1, 2, 4 and 7 (400 / 64 = 6.25) tiles per side: 1 + 4 + 16 + 49 = 70 tiles per group.
    const TileLayout layout(400, 400, 3);
    EXPECT_EQ(layout.levels(), 4);
    EXPECT_EQ(layout.tileBytes(), 41472u);  // 72 x 72 x 4 halfs (Schwartz et al. 2013: 40.5 KB)
    const int sides[] = {50, 100, 200, 400}, tiles[] = {1, 2, 4, 7};
    for (int l = 0; l < 4; ++l) {
        EXPECT_EQ(layout.levelWidth(l), sides[l]);
        EXPECT_EQ(layout.tilesX(l), tiles[l]);
        EXPECT_EQ(layout.tilesY(l), tiles[l]);
    }
    EXPECT_EQ(layout.tilesPerGroup(), 70u);
    EXPECT_EQ(layout.tileCount(), 210u);
    // Tile (3, 3) of level 2 covers level-3 tiles 6..7: only 6 exists.
    const std::vector<TileId> children = layout.children({1, 2, 3, 3});
    ASSERT_EQ(children.size(), 1u);
    EXPECT_EQ(children[0], (TileId{1, 3, 6, 6}));
    EXPECT_EQ(layout.children({0, 1, 1, 0}).size(), 4u);
    EXPECT_TRUE(layout.children({0, 3, 0, 0}).empty());
    EXPECT_EQ(TileLayout::parent({2, 3, 6, 5}), (TileId{2, 2, 3, 2}));
    // Finest texel 399 is texel 99 of level 1 (399 >> 2), in its tile 1.
    EXPECT_EQ(layout.tileOfTexel(0, 1, 399, 0), (TileId{0, 1, 1, 0}));
    for (std::size_t i = 0; i < layout.tileCount(); ++i) {
        const TileId t = layout.tileAt(i);
        ASSERT_TRUE(layout.contains(t));
        ASSERT_EQ(layout.index(t), i);
    }
    EXPECT_FALSE(layout.contains({0, 3, 7, 0}));

    // Odd and tiny sizes: 65 x 64 needs a second level (33 x 32, one tile); 1 x 1 is one tile.
    const TileLayout odd(65, 64, 1);
    EXPECT_EQ(odd.levels(), 2);
    EXPECT_EQ(odd.levelWidth(0), 33);
    EXPECT_EQ(odd.levelHeight(0), 32);
    EXPECT_EQ(odd.tilesX(1), 2);
    EXPECT_EQ(odd.tilesY(1), 1);
    EXPECT_EQ(TileLayout(1, 1, 1).tileCount(), 1u);
}

const char* kIndex =
    "osgBTF-bsvtf 1\n"
    "size 8 8\n"
    "tile 8 4\n"
    "groups 1\n"
    "components 3\n"
    "codec raw\n"
    "param model fmf\n"
    "views v;0,0\n"
    "lights l;0,0;45,90\n"
    "u 0 48 123\n"
    "t 0 0 0 0 2048 77 0.5 0.25\n"
    "end\n";

std::string replaced(const std::string& text, const std::string& from, const std::string& to) {
    std::string out = text;
    out.replace(out.find(from), from.size(), to);
    return out;
}

TEST(TileSetIndex, RefusesIncompleteOrMalformedIndexesWithTheLine) {
    const std::string good = kIndex;
    const auto parse = [](const std::string& text) {
        return errorOf([&] { TileSetIndex::parse(text, "idx"); });
    };
    EXPECT_EQ(parse("PK\x03\x04"),
              "idx: line 1: not an osgBTF BSVTF index of version 1 (first "
              "line must be 'osgBTF-bsvtf 1')");
    EXPECT_EQ(parse(replaced(good, "end\n", "")),
              "idx: line 12: no 'end' line: the index is truncated");
    EXPECT_EQ(parse(replaced(good, "t 0 0 0 0 2048 77 0.5 0.25\n", "")),
              "idx: line 12: tile tiles/0/0/0_0.tile is missing");
    EXPECT_EQ(parse(replaced(good, "end\n", "t 0 0 0 0 2048 77 0.5 0.25\nend\n")),
              "idx: line 12: tile listed twice");
    EXPECT_EQ(parse(replaced(good, "2048 77", "2048x 77")),
              "idx: line 11: '2048x' is not an integer in [0, 4294967295]");
    EXPECT_EQ(parse(replaced(good, "2048 77", "2047 77")),
              "idx: line 13: raw tile tiles/0/0/0_0.tile must have 2048 bytes");
    EXPECT_EQ(parse(replaced(good, "u 0 48", "u 0 47")),
              "idx: line 13: U packet 0 must have 48 bytes, the index says 47");
    EXPECT_EQ(parse(replaced(good, "t 0 0 0 0", "t 0 1 0 0")),
              "idx: line 11: tile outside the layout");
    EXPECT_EQ(parse(replaced(good, "codec raw", "codec jpeg")),
              "idx: line 6: unknown codec 'jpeg' (known: dct, raw)");
    EXPECT_EQ(parse(replaced(good, "components 3", "components 5")),
              "idx: line 13: components 5 need 2 groups, not 1");
    EXPECT_EQ(parse(replaced(good, "size 8 8\n", "size 8 8\nfrobnicate 1\n")),
              "idx: line 3: unknown key 'frobnicate'");
    EXPECT_EQ(parse(good + "t 0\n"), "idx: line 13: text after the 'end' line");
    EXPECT_EQ(parse(replaced(good, "0.5 0.25", "nan 0.25")),
              "idx: line 11: 'nan' is not a finite number");
}

TEST(TileSetIndex, ReadsAHandWrittenIndex) {
    const TileSetIndex index = TileSetIndex::parse(kIndex, "idx");
    EXPECT_EQ(index.layout.width(), 8);
    EXPECT_EQ(index.layout.levels(), 1);
    EXPECT_EQ(index.layout.paddedTileSize(), 16);
    EXPECT_EQ(index.codec, "raw");
    EXPECT_EQ(index.components, 3);
    EXPECT_EQ(index.parameters.at("model"), "fmf");
    EXPECT_EQ(index.views.size(), 1u);
    EXPECT_EQ(index.lights.size(), 2u);
    EXPECT_FLOAT_EQ(index.lights[1].theta, 45.0f);
    EXPECT_EQ(index.uPacketValues(), 24u);
    // A U packet: 4 components x 3 colours x views x lights half floats. Schwartz et al. 2013's 151
    // x 151 directions give its "packets of 534 KB" (547,224 bytes = 534.4 KiB); the Bonn 81 x 81,
    // 157,464 bytes.
    TileSetIndex ubo = index, bonn = index;
    ubo.views = ubo.lights = DirectionSet::ubo2014();
    bonn.views = bonn.lights = DirectionSet::bonn81();
    EXPECT_EQ(ubo.uPacketValues() * 2, 547224u);
    EXPECT_EQ(bonn.uPacketValues() * 2, 157464u);
    ASSERT_EQ(index.tiles.size(), 1u);
    EXPECT_EQ(index.tiles[0].bytes, 2048u);
    EXPECT_EQ(index.tiles[0].crc, 77u);
    EXPECT_FLOAT_EQ(index.tiles[0].weight, 0.5f);
    EXPECT_FLOAT_EQ(index.tiles[0].norm, 0.25f);
    // What serialize writes reads back as the same index.
    const TileSetIndex again = TileSetIndex::parse(index.serialize(), "again");
    EXPECT_EQ(again.serialize(), index.serialize());
}

/** A 20 x 12 fmf material with 4 components whose Eigen-Texture is a known formula. */
float formula(int x, int y, int k) {
    return float(x + 32 * y) / 64.0f + float(k);
}

osg::ref_ptr<FmfMaterial> formulaMaterial() {
    FactoredBtf f = test::randomFactors(FactorModel::Fmf, {4, 0, 0}, 20, 12, 3);
    for (int y = 0; y < 12; ++y)
        for (int x = 0; x < 20; ++x)
            for (int k = 0; k < 4; ++k)
                f.factors[0].SxV(Eigen::Index(f.factorRow(x, y)), k) = formula(x, y, k);
    return FmfMaterial::fromFactors(f);
}

/** Texel (X, Y) of level l (shift s = L - l): the box mean of the finest texels under it. */
double levelValue(int X, int Y, int k, int shift) {
    double sum = 0;
    const int n = 1 << shift;
    for (int dy = 0; dy < n; ++dy)
        for (int dx = 0; dx < n; ++dx) sum += formula(X * n + dx, Y * n + dy, k);
    return sum / (n * n);
}

std::vector<float> tileValues(const std::string& path) {
    const std::vector<std::uint8_t> bytes = readFileBytes(path);
    std::vector<float> values(bytes.size() / 2);
    for (std::size_t i = 0; i < values.size(); ++i) {
        Imath::half h;
        h.setBits(std::uint16_t(bytes[2 * i] | (bytes[2 * i + 1] << 8)));
        values[i] = float(h);
    }
    return values;
}

TEST(TileBuilder, RefusesDfmfMaterials) {
    test::TempDir dir;
    const auto dfmf =
        FmfMaterial::fromFactors(test::randomFactors(FactorModel::Dfmf, {4, 4, 4}, 8, 8, 1));
    dfmf->sourceFile = "d.btf";
    EXPECT_EQ(errorOf([&] { buildTileSet(*dfmf, dir.file("t")); }),
              "d.btf: BSVTF streams FMF materials (one factorisation, the colour in U's rows); "
              "this is DFMF (one factorisation per colour channel): fit an fmf material first, "
              "e.g. `btf fit IN -m fmf --no-mipmap -o M.btfmat`");
    EXPECT_FALSE(std::filesystem::exists(dir.file("t")));
    EXPECT_EQ(errorOf([&] { buildTileSet(*formulaMaterial(), dir.file("no/such/t")); }),
              dir.file("no/such/t") + ": folder '" + dir.file("no/such") + "' does not exist");
}

TEST(TileBuilder, RawTilesHoldTheBoxFilteredLevelsWithWrapAroundPaddingAndTheirWeights) {
    test::TempDir dir;
    TileBuildOptions options;
    options.codec = "raw";
    options.tileSize = 8;
    const TileBuildReport report = buildTileSet(*formulaMaterial(), dir.file("t"), options);
    // 20 x 12 at T = 8: levels 5 x 3, 10 x 6, 20 x 12 with 1, 2 x 1 and 3 x 2 tiles.
    EXPECT_EQ(report.levels, 3);
    EXPECT_EQ(report.tiles, 9u);
    EXPECT_EQ(report.storedTileBytes, 9u * 16 * 16 * 4 * 2);
    const std::vector<std::string> names = {"index.bsvtf", "u/0.half", "tiles/0/0/0_0.tile",
                                            "tiles/0/2/2_1.tile"};
    for (const std::string& name : names)
        EXPECT_TRUE(std::filesystem::exists(dir.file("t/" + name))) << name;
    const TileSetIndex index =
        TileSetIndex::parse(test::readTextFile(dir.file("t/index.bsvtf")), "index");

    const int widths[] = {5, 10, 20}, heights[] = {3, 6, 12};
    for (std::size_t i = 0; i < index.layout.tileCount(); ++i) {
        const TileId t = index.layout.tileAt(i);
        const int shift = 2 - t.level, W = widths[t.level], H = heights[t.level];
        const std::vector<float> got = tileValues(dir.file("t/" + TileSetIndex::tilePath(t)));
        ASSERT_EQ(got.size(), 16u * 16 * 4);
        double diff = 0, n = 0;
        for (int py = 0; py < 16; ++py)
            for (int px = 0; px < 16; ++px) {
                // Padded texel -> level texel, wrapped around the level (the material repeats).
                const int x = t.x * 8 - 4 + px, y = t.y * 8 - 4 + py;
                const int wx = (x % W + W) % W, wy = (y % H + H) % H;
                for (int k = 0; k < 4; ++k)
                    ASSERT_EQ(got[(std::size_t(py) * 16 + px) * 4 + k],
                              float(Imath::half(float(levelValue(wx, wy, k, shift)))))
                        << "tile " << t.level << "/" << t.x << "_" << t.y << " texel " << px << ","
                        << py << " component " << k;
                if (px < 4 || px >= 12 || py < 4 || py >= 12 || x >= W || y >= H) continue;
                for (int k = 0; k < 4; ++k) {
                    const double up = t.level > 0 ? levelValue(x >> 1, y >> 1, k, shift + 1) : 0.0;
                    const double d = levelValue(x, y, k, shift) - up;
                    diff += d * d;
                }
                ++n;
            }
        EXPECT_NEAR(index.tiles[i].weight, diff / n, 1e-5 * (1 + diff / n))
            << "tile " << t.level << "/" << t.x << "_" << t.y;
    }
    // The hand-checked weight of a corner: a level-2 texel minus its level-1 parent differs by
    // (x - 2 (x >> 1) - 0.5 + 32 (y - 2 (y >> 1) - 0.5)) / 64, whose square averages to
    // (0.25 + 32^2 x 0.25) / 64^2 per component over whole 2 x 2 blocks: x 4 components.
    EXPECT_NEAR(index.tiles[index.layout.index({0, 2, 0, 0})].weight,
                4 * (0.25 + 1024 * 0.25) / 4096.0, 1e-6);
}

TEST(TileBuilder, AllFinestRawTilesRenderExactlyTheFmfMaterial) {
    test::TempDir dir;
    TileBuildOptions options;
    options.codec = "raw";
    options.tileSize = 8;
    const osg::ref_ptr<FmfMaterial> original = formulaMaterial();
    buildTileSet(*original, dir.file("t"), options);
    const osg::ref_ptr<FmfMaterial> streamed = loadTileSetFinest(dir.file("t"));
    const std::size_t values = original->factors().imageCount() * 3;
    std::vector<float> a(values), b(values);
    for (std::size_t texel = 0; texel < 20 * 12; ++texel) {
        original->evaluateMeasured(texel, a.data());
        streamed->evaluateMeasured(texel, b.data());
        ASSERT_EQ(a, b) << "texel " << texel;
    }
}

TEST(ImageSimilarity, RefusesMismatchedImagesAndMatchesTheFormulaOnConstantImages) {
    EXPECT_EQ(errorOf([] {
                  structuralSimilarity({1, 2}, {1}, 2, 1, 1, 1.0);
              }),
              "SSIM: the images must both hold 2 x 1 x 1 values");
    const std::vector<float> noise = {0.1f, 0.7f, 0.3f, 0.9f, 0.2f, 0.5f, 0.8f, 0.4f, 0.6f};
    EXPECT_DOUBLE_EQ(structuralSimilarity(noise, noise, 3, 3, 1, 1.0), 1.0);
    // Constant images have no variance: SSIM = (2 ma mb + C1) / (ma^2 + mb^2 + C1) with
    // C1 = (0.01 x range)^2 = 1e-4: (0.16 + 1e-4) / (0.2 + 1e-4).
    const std::vector<float> a(16 * 16, 0.2f), b(16 * 16, 0.4f);
    EXPECT_NEAR(structuralSimilarity(a, b, 16, 16, 1, 1.0), 0.1601 / 0.2001, 1e-6);
}

TEST(TileBuilder, DctTilesOfTheSampleAreFourTimesSmallerAndRenderWithSsimAbove099) {
    // The built-in sample's fmf fit, 3 levels of 16-texel tiles (Schwartz et al. 2013: 6:1 "with no
    // perceivable artifacts"; the issue asks >= 4:1 at SSIM >= 0.99 against uncompressed tiles).
    const MeasuredBtf btf = test::smallSampleBtf(64);
    const osg::ref_ptr<FmfMaterial> fmf = FmfMaterial::fit(btf, FitOptions::parse("components=8"));
    test::TempDir dir;
    TileBuildOptions raw, dct;
    raw.codec = "raw";
    raw.tileSize = dct.tileSize = 16;
    const TileBuildReport rawReport = buildTileSet(*fmf, dir.file("raw"), raw);
    const TileBuildReport dctReport = buildTileSet(*fmf, dir.file("dct"), dct);
    const double ratio = double(rawReport.storedTileBytes) / double(dctReport.storedTileBytes);
    std::cout << "quality " << dct.quality << ": " << rawReport.storedTileBytes << " -> "
              << dctReport.storedTileBytes << " bytes of tiles (" << ratio
              << ":1), largest tile error " << dctReport.largestTileError << "\n";
    EXPECT_GE(ratio, 4.0);
    // No drift: every decoded texel of every level within the codec's bound of its own tile.
    const TileSetIndex index =
        TileSetIndex::parse(test::readTextFile(dir.file("dct/index.bsvtf")), "index");
    EXPECT_LE(dctReport.largestTileError,
              tileCodecErrorBound(index.codecSettings, 255.0f * index.codecSettings.unit));

    const osg::ref_ptr<FmfMaterial> exact = loadTileSetFinest(dir.file("raw"));
    const osg::ref_ptr<FmfMaterial> coded = loadTileSetFinest(dir.file("dct"));
    const std::size_t pairs[][2] = {{0, 0}, {4, 6}, {8, 2}};  // of the 9 x 9 directions
    for (const auto& pair : pairs) {
        const glm::vec3 view = btf.views().vector(pair[0]), light = btf.lights().vector(pair[1]);
        std::vector<float> a, b;
        float peak = 0;
        for (int y = 0; y < 64; ++y)
            for (int x = 0; x < 64; ++x) {
                const glm::vec3 va = exact->evaluate(x, y, view, light);
                const glm::vec3 vb = coded->evaluate(x, y, view, light);
                for (int c = 0; c < 3; ++c) {
                    a.push_back(va[c]);
                    b.push_back(vb[c]);
                    peak = std::max(peak, va[c]);
                }
            }
        const double ssim = structuralSimilarity(a, b, 64, 64, 3, peak);
        std::cout << "view " << pair[0] << ", light " << pair[1] << ": SSIM " << ssim << "\n";
        EXPECT_GE(ssim, 0.99) << "view " << pair[0] << ", light " << pair[1];
    }
}

TEST(TilesCommand, RefusesOtherMethodsAndWritesTheSetOfAnFmfMaterial) {
    test::TempDir dir;
    const std::string lambert = dir.file("l.btfmat"), fmf = dir.file("f.btfmat");
    saveMaterial(*findMethod("lambert").fit(test::smallSampleBtf(8), FitOptions()), lambert);
    saveMaterial(*formulaMaterial(), fmf);
    const std::string tool = test::builtTool("btf") + " --no-progress tiles ";
    test::CommandResult r = test::runCommand(tool + lambert + " -o " + dir.file("out"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.output, "btf: error: " + lambert +
                            ": is a 'lambert' material; BSVTF tiles an fmf material (`btf fit IN "
                            "-m fmf -o M.btfmat`, or a UBO2014 FMF .btf)\n");
    EXPECT_FALSE(std::filesystem::exists(dir.file("out")));
    const std::string zip = dir.file("s.zip");
    r = test::runCommand(tool + zip + " -o " + dir.file("out"));
    EXPECT_EQ(r.exitCode, 1);
    EXPECT_EQ(r.output, "btf: error: " + zip +
                            ": is a measured BTF; tile an fmf fit of it (`btf fit " + zip +
                            " -m fmf -o M.btfmat`, then `btf tiles M.btfmat`)\n");
    r = test::runCommand(tool + fmf + " -o " + dir.file("out") + " --tile-size 8 --codec raw");
    EXPECT_EQ(r.exitCode, 0) << r.output;
    EXPECT_NE(r.output.find("1 groups x 3 levels, 9 tiles"), std::string::npos) << r.output;
    EXPECT_EQ(errorOf([&] { loadTileSetFinest(dir.file("out")); }), "no error");
}

}  // namespace

}  // namespace OSGBTF_TEST_FILE
