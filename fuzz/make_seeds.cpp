// osgbtf_fuzz_seeds OUT: writes the seed corpora of the fuzz targets (OUT/<target>/) and the files
// the plugin-name and scene targets may name (OUT/fixtures/, committed as fuzz/fixtures/), all with
// osgBTF's own writers: the synthetic sample as UBO2003 zips, fits of every method saved as
// fitted materials, UBO2014 files of each signature and header variant, a coordinate map, .osgt
// scenes with MaterialNodes. Tiny on purpose: libFuzzer mutates small inputs many times faster.
#include <unistd.h>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <random>

#include <osg/Geode>
#include <osg/ShapeDrawable>
#include <osgDB/WriteFile>

#include "core/CoordinateMap.h"
#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/Progress.h"
#include "harness/sample/BlockMap.h"
#include "harness/sample/SampleBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "loaders/Ubo2014.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "scene/MaterialNode.h"
#include "streaming/TileBuilder.h"

namespace fs = std::filesystem;
using namespace osgBTF;

namespace {

void writeText(const fs::path& path, const std::string& text) {
    std::ofstream out(path, std::ios::binary);
    out << text;
    if (!out) throw Error(path.string() + ": cannot write");
}

FactorMatrix randomMatrix(Eigen::Index rows, Eigen::Index cols, std::mt19937& random) {
    std::uniform_real_distribution<float> value(-0.5f, 0.5f);
    FactorMatrix m(rows, cols);
    for (Eigen::Index r = 0; r < rows; ++r)
        for (Eigen::Index c = 0; c < cols; ++c) m(r, c) = value(random);
    return m;
}

/** A 2x2-texel UBO2014 file of 3 views x 2 lights with rank-2 factors. */
Ubo2014Factors smallFactors(FactorModel model, std::mt19937& random) {
    Ubo2014Factors f;
    f.model = model;
    f.width = 2;
    f.height = 2;
    f.views = DirectionSet("v", {{0, 0}, {30, 90}, {60, 270}});
    f.lights = DirectionSet("l", {{0, 0}, {45, 180}});
    f.measurementSetup = "fuzz seed";
    f.xml = "<xml/>";
    const int rows = int(f.views.size() * f.lights.size()) * (model == FactorModel::Fmf ? 3 : 1);
    for (int i = 0; i < (model == FactorModel::Fmf ? 1 : 3); ++i) {
        BtfFactor factor;
        factor.S = Eigen::VectorXf::Ones(2);
        factor.U = randomMatrix(rows, 2, random);
        factor.SxV = randomMatrix(4, 2, random);
        f.factors.push_back(factor);
    }
    f.maxComponents = 2;
    return f;
}

}  // namespace

int main(int argc, char** argv) {
    if (argc != 2) {
        std::fprintf(stderr, "usage: osgbtf_fuzz_seeds OUT\n");
        return 2;
    }
    try {
        Progress::setEnabled(false);
        const fs::path out = fs::absolute(argv[1]);
        for (const char* folder :
             {"ubo2003_zip", "ubo2014", "fitted_material", "coordinate_map", "btfmat_plugin",
              "plugin_names", "scene_file", "bsvtf_tiles", "rti_files", "fixtures"})
            fs::create_directories(out / folder);

        // UBO2003: 2 views x 2 lights of 2x2 texels in every image format.
        SampleOptions tiny;
        tiny.width = tiny.height = 2;
        tiny.views = tiny.lights = DirectionSet("d", {{0, 0}, {45, 90}});
        const MeasuredBtf tinyBtf = makeSampleBtf(tiny);
        const std::pair<Ubo2003ImageFormat, const char*> formats[] = {
            {Ubo2003ImageFormat::Jpeg, "jpg"},
            {Ubo2003ImageFormat::Png, "png"},
            {Ubo2003ImageFormat::Hdr, "hdr"},
            {Ubo2003ImageFormat::Exr, "exr"}};
        for (const auto& [format, name] : formats)
            writeUbo2003Zip(tinyBtf,
                            (out / "ubo2003_zip" / (std::string("seed-") + name + ".zip")).string(),
                            format);

        // UBO2014: each signature and header variant.
        std::mt19937 random(2003);
        auto write2014 = [&](Ubo2014Factors f, const std::string& name) {
            writeUbo2014(f, (out / "ubo2014" / name).string());
        };
        Ubo2014Factors dfmf = smallFactors(FactorModel::Dfmf, random);
        write2014(dfmf, "seed-dfmf-rgb-float.btf");
        dfmf.colorModel = 11;
        dfmf.scalarSize = 2;
        dfmf.hasRotations = true;
        dfmf.rotations.push_back({1, 0, 0, 0, 1, 0, 0, 0, 1});
        dfmf.cosine = true;
        write2014(dfmf, "seed-dfmf-expyuv-half-rotations.btf");
        dfmf.colorModel = 3;
        dfmf.metaVersion = 2;
        dfmf.hasRotations = false;
        write2014(dfmf, "seed-dfmf-pca-meta2.btf");
        Ubo2014Factors fmf = smallFactors(FactorModel::Fmf, random);
        fmf.headerVersion = 1;
        fmf.dynamicRangeReduction = 1;
        fmf.cosine = true;
        fmf.scalarSize = 2;
        write2014(fmf, "seed-fmf12-drr-cosine-half.btf");
        fmf.headerVersion = 2;
        fmf.heightMapWidth = fmf.heightMapHeight = 2;
        fmf.heightMap = {0.0f, 0.25f, 0.5f, 1.0f};
        fmf.scalarSize = 8;
        write2014(fmf, "seed-fmf12-heightmap-double.btf");
        fmf.extendedHeader = false;
        fmf.headerVersion = 0;
        fmf.dynamicRangeReduction = 0;
        fmf.scalarSize = 4;
        fmf.hasRotations = true;
        fmf.rotations.push_back({0, 1, 0, 1, 0, 0, 0, 0, 1});
        fmf.metaVersion = 1;
        write2014(fmf, "seed-fmf06-rotations-meta1.btf");
        writeText(out / "ubo2014" / "seed-pvf.btf", std::string("!PVF08FC\x10\x01\0\0", 12));
        writeText(out / "ubo2014" / "seed-bdi.btf", std::string("!BDIF06R\x10\x01\0\0", 12));

        // The fixtures: a 4x4 sample of 6 x 6 directions, its fits, a map, a model.
        const fs::path fixtures = out / "fixtures";
        SampleOptions small;
        small.width = small.height = 4;
        small.views = small.lights =
            DirectionSet("d6", {{0, 0}, {30, 0}, {30, 120}, {30, 240}, {60, 60}, {60, 300}});
        const MeasuredBtf sample = makeSampleBtf(small);
        writeUbo2003Zip(sample, (fixtures / "s.zip").string(), Ubo2003ImageFormat::Png);
        Ubo2014Factors stored = smallFactors(FactorModel::Fmf, random);
        stored.headerVersion = 1;
        writeUbo2014(stored, (fixtures / "m.btf").string());
        const CoordinateMap map = makeBlockCoordinateMap(8, 8, 4, 4, 2, 7);
        writeCoordinateMap(map, (fixtures / "map.exr").string());
        fs::copy_file(fixtures / "map.exr", out / "coordinate_map" / "seed-map.exr",
                      fs::copy_options::overwrite_existing);
        osg::ref_ptr<osg::Geode> model = new osg::Geode;
        model->addDrawable(new osg::ShapeDrawable(new osg::Box(osg::Vec3(), 1.0f)));
        if (!osgDB::writeNodeFile(*model, (fixtures / "model.osgt").string()))
            throw Error((fixtures / "model.osgt").string() + ": cannot write (osgdb_osg?)");

        // Every method fitted on the sample (quick options), as fitted-material seeds.
        osg::ref_ptr<Material> lambert;
        for (const std::string& name : methodNamesInOrder()) {
            const MethodInfo& method = findMethod(name);
            try {
                osg::ref_ptr<Material> material =
                    method.fit(sample, FitOptions::parse(method.quickFitOptions));
                const std::string file = "seed-" + name + ".btfmat";
                saveMaterial(*material, (out / "fitted_material" / file).string());
                fs::copy_file(out / "fitted_material" / file, out / "btfmat_plugin" / file,
                              fs::copy_options::overwrite_existing);
                if (name == "lambert") lambert = material;
            } catch (const Error& e) {
                std::fprintf(stderr, "osgbtf_fuzz_seeds: %s skipped: %s\n", name.c_str(), e.what());
            }
        }
        if (!lambert) throw Error("lambert did not fit");
        // The RTI field's files: PTM RGB and LRGB, HSH of every order, from the sample.
        for (const char* options : {"colour=rgb", "colour=luminance"})
            saveMaterial(
                *findMethod("ptm").fit(sample, FitOptions::parse(options)),
                (out / "rti_files" / ("seed-" + std::string(options + 7) + ".ptm")).string());
        for (const char* order : {"2", "3", "4"})
            saveMaterial(
                *findMethod("hsh").fit(sample, FitOptions::parse(std::string("order=") + order)),
                (out / "rti_files" / ("seed-order" + std::string(order) + ".rti")).string());
        // The JPEG-compressed RTI files of the tests (tests/data/rti-files/, written by its
        // make_fixtures.py): the .ptm variants as they are, each relight folder packed into one
        // input (FuzzEntries.cpp rtiFiles: info.json, then "\n--plane--\n" before each plane).
        const fs::path rtiData = fs::path(OSGBTF_SOURCE_DIR) / "tests" / "data" / "rti-files";
        for (const char* name : {"jpeg-lrgb.ptm", "jpeg-rgb.ptm"})
            fs::copy_file(rtiData / name, out / "rti_files" / (std::string("seed-") + name),
                          fs::copy_options::overwrite_existing);
        for (const char* folder :
             {"relight-ptm-lrgb", "relight-ptm-rgb", "relight-hsh-rgb", "relight-hsh-lrgb",
              "relight-rbf-mrgb", "relight-bilinear-mrgb", "relight-rbf-mycc"}) {
            std::string packed = readWholeFile((rtiData / folder / "info.json").string());
            for (int j = 0; fs::exists(rtiData / folder / ("plane_" + std::to_string(j) + ".jpg"));
                 ++j)
                packed +=
                    "\n--plane--\n" +
                    readWholeFile(
                        (rtiData / folder / ("plane_" + std::to_string(j) + ".jpg")).string());
            writeTextAtomically((out / "rti_files" / (std::string("seed-") + folder)).string(),
                                packed);
        }
        saveMaterial(*lambert, (fixtures / "m.btfmat").string());

        // Scenes: a MaterialNode naming m.btfmat (resolved in the fixtures folder), and one
        // with the material embedded.
        if (::chdir(fixtures.c_str()) != 0) throw Error(fixtures.string() + ": cannot enter");
        osg::ref_ptr<MaterialNode> named = new MaterialNode;
        if (!named->setMaterialFile("m.btfmat"))
            throw Error("m.btfmat: " + named->getMaterialError());
        named->setTextureScale(2.0f);
        named->setCoordinateMapFile("map.exr");
        named->addChild(model.get());
        osg::ref_ptr<Material> inMemory = findMethod("lambert").fit(sample, FitOptions::parse(""));
        osg::ref_ptr<MaterialNode> embedded = new MaterialNode(inMemory.get());
        embedded->addChild(model.get());
        if (!osgDB::writeNodeFile(*named, (out / "scene_file" / "seed-named.osgt").string()) ||
            !osgDB::writeNodeFile(*embedded, (out / "scene_file" / "seed-embedded.osgt").string()))
            throw Error("cannot write the .osgt scene seeds");

        // Plugin names and option strings: line 1 the name, the rest the -O string.
        const char* names[][2] = {
            {"seed-pseudo.txt", "model.osgt.(m.btfmat,scale=2).btfmaterial\n"},
            {"seed-pseudo-map.txt", "model.osgt.(m.btfmat,scale=4,map=map.exr).btfmaterial\n"},
            {"seed-pseudo-fit.txt", "model.osgt.(s.zip,method=lambert).btfmaterial\nscale=2"},
            {"seed-btf-stored.txt", "m.btf\nstorage=float"},
            {"seed-btf-fit.txt", "m.btf\nmethod=pca components=2"},
            {"seed-zip-laf.txt", "s.zip\nmethod=laf lobes=1 scale=3"},
            {"seed-btfmat-map.txt", "m.btfmat\nmap=map.exr scale=0.5"},
        };
        for (const auto& [file, text] : names) writeText(out / "plugin_names" / file, text);
        // BSVTF: the index and every dct tile (T = 8, P = 4, what the target decodes) of a
        // 20 x 12 fmf material with 3 levels.
        {
            SampleOptions small;
            small.width = 20;
            small.height = 12;
            small.views = small.lights = DirectionSet("d", {{0, 0}, {45, 90}, {30, 200}});
            const osg::ref_ptr<Material> fmf =
                factorMethod().fit(makeSampleBtf(small), FitOptions::parse("components=4"));
            TileBuildOptions build;
            build.tileSize = 8;
            build.quality = 75;
            const fs::path tiles = out / "bsvtf_tiles" / "set";
            buildTileSet(*fmf, tiles.string(), build);
            fs::copy_file(tiles / "index.bsvtf", out / "bsvtf_tiles" / "seed-index.bsvtf");
            int n = 0;
            for (const char* tile : {"0/0/0_0", "0/1/1_0", "0/2/2_1"})
                fs::copy_file(tiles / "tiles" / (std::string(tile) + ".tile"),
                              out / "bsvtf_tiles" / ("seed-tile-" + std::to_string(n++)));
            fs::remove_all(tiles);
        }
        std::printf("osgbtf_fuzz_seeds: wrote %s\n", out.string().c_str());
        return 0;
    } catch (const std::exception& e) {
        std::fprintf(stderr, "osgbtf_fuzz_seeds: %s\n", e.what());
        return 1;
    }
}
