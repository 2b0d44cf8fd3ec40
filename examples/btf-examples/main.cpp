// btf-examples: writes osgBTF's example scenes into a folder, reproducibly: the built-in sample
// BTF (core/SampleBtf), fitted with a few methods, and three side-by-side scenes that refer to
// the fitted files by relative name. `btf-examples --help` lists the options; examples/README.md
// describes the scenes.
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <iostream>
#include <sstream>

#include <CLI/CLI.hpp>
#include <osg/ProxyNode>
#include <osgDB/Options>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/Progress.h"
#include "examples/ExampleScenes.h"
#include "examples/btf-examples/Gallery.h"
#include "examples/btf-examples/SceneBench.h"
#include "fit/MipMapping.h"
#include "harness/sample/BlockMap.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/pca/Pca.h"
#include "scene/OwnPlugins.h"

namespace {

using namespace osgBTF;
using namespace osgBTF::examples;

std::vector<std::string> splitList(const std::string& text) {
    std::vector<std::string> items;
    std::stringstream stream(text);
    std::string item;
    while (std::getline(stream, item, ','))
        if (!item.empty()) items.push_back(item);
    return items;
}

struct Options {
    std::string outputDir;
    std::string galleryDir;
    int size = 32;
    std::string methods = "lambert,laf,pca";
    int blockMap = 0;  // 0: none
    bool mipmap = false;
    bool benchFps = false;
    std::string benchResolution = "1920x1080", benchLights = "1,8", benchTarget = "rgba8";
    SceneBenchOptions bench;
};

/** "WxH" with positive integers. */
void parseSize(const std::string& text, int& width, int& height) {
    const auto x = text.find('x');
    try {
        std::size_t used = 0, usedH = 0;
        if (x != std::string::npos) {
            width = std::stoi(text.substr(0, x), &used);
            height = std::stoi(text.substr(x + 1), &usedH);
            if (used == x && usedH == text.size() - x - 1 && width > 0 && height > 0) return;
        }
    } catch (const std::exception&) {
    }
    throw Error("--bench-resolution: '" + text + "' is not WxH (positive integers)");
}

/** Writes `text` to a temporary name beside `path`, then renames it. */
void writeTextAtomically(const std::string& text, const std::filesystem::path& path) {
    const std::filesystem::path temporary =
        path.parent_path() /
        ("." + path.filename().string() + ".tmp-" + std::to_string(::getpid()));
    {
        std::ofstream out(temporary);
        out << text;
        if (!out.flush()) fail(temporary.string(), "cannot write");
    }
    std::error_code error;
    std::filesystem::rename(temporary, path, error);
    if (error) {
        std::filesystem::remove(temporary, error);
        fail(path.string(), "cannot rename the temporary file into place");
    }
}

void run(Options options) {
    namespace fs = std::filesystem;
    const std::vector<std::string> methods = splitList(options.methods);
    if (methods.empty()) throw Error("--methods: no method given");
    for (const std::string& method : methods) findMethod(method);  // unknown names fail first
    if (options.benchFps) {  // bad benchmark options fail before anything is written
        parseSize(options.benchResolution, options.bench.width, options.bench.height);
        options.bench.lights.clear();
        for (const std::string& l : splitList(options.benchLights)) {
            std::size_t used = 0;
            int count = 0;
            try {
                count = std::stoi(l, &used);
            } catch (const std::exception&) {
            }
            if (used != l.size() || count < 1 || count > 8)
                throw Error("--bench-lights: '" + l + "' is not a light count in 1..8");
            options.bench.lights.push_back(count);
        }
        if (options.bench.lights.empty()) throw Error("--bench-lights: no light count given");
        try {
            options.bench.target = passTarget(options.benchTarget);
        } catch (const Error& e) {
            throw Error(std::string("--bench-target: ") + e.what());
        }
    }

    const fs::path dir(options.outputDir);
    std::error_code error;
    fs::create_directories(dir, error);
    if (error || !fs::is_directory(dir))
        fail(options.outputDir,
             "cannot create the folder" + (error ? ": " + error.message() : std::string()));

    // 1. The materials: the sample, fitted with each method.
    SampleOptions sampleOptions;
    sampleOptions.width = sampleOptions.height = options.size;
    const MeasuredBtf sample = makeSampleBtf(sampleOptions);
    std::vector<SceneItem> items;
    for (const std::string& method : methods) {
        const auto start = std::chrono::steady_clock::now();
        osg::ref_ptr<Material> material =
            options.mipmap ? fitMipMapped(findMethod(method), sample, FitOptions())
                           : findMethod(method).fit(sample, FitOptions());
        const std::string file = "sample-" + method + ".btfmat";
        saveMaterial(*material, (dir / file).string());
        std::cout << "fitted " << method << " in "
                  << std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count()
                  << " s -> " << (dir / file).string() << "\n";
        items.push_back({file, method});
    }

    // A stand-in for a synthesised map (btf synthesize) until one is at hand: blocks of a quarter
    // of the sample, each from a random place in it.
    if (options.blockMap > 0) {
        const std::string file = "blocks-map.exr";
        writeCoordinateMap(makeBlockCoordinateMap(options.blockMap, options.blockMap, options.size,
                                                  options.size, std::max(1, options.size / 4), 1),
                           (dir / file).string());
        std::cout << "wrote " << (dir / file).string() << " (" << options.blockMap << "x"
                  << options.blockMap << " coordinate map into the " << options.size << "x"
                  << options.size << " sample)\n";
    }

    // 2. The model file (plain OSG geometry, usable with the pseudo-loader), then the scenes.
    osg::ref_ptr<osg::Node> vase = createVaseModel();
    writeNodeAtomically(*vase, (dir / "vase.osgt").string());
    // Material names resolve against the output folder while building, as they will against
    // the scene's folder when it is read.
    osg::ref_ptr<osgDB::Options> readOptions = new osgDB::Options;
    readOptions->getDatabasePathList().push_back(dir.string());

    struct SceneSpec {
        std::string file;
        osg::ref_ptr<osg::Node> model;
        float spacing, textureScale;
    };
    // The vase scene refers to vase.osgt through a ProxyNode (a model kept in its own file, as
    // scenes built from OSG's data usually are); the other two embed their geometry once, shared
    // by all of their MaterialNodes.
    osg::ref_ptr<osg::ProxyNode> vaseReference = new osg::ProxyNode;
    vaseReference->setFileName(0, "vase.osgt");
    vaseReference->addChild(vase.get());
    const std::vector<SceneSpec> scenes = {
        {"spheres.osgt", createSphereModel(), 2.3f, 6.0f},
        {"cloth.osgt", createClothModel(), 2.2f, 4.0f},
        {"vases.osgt", vaseReference, 1.3f, 6.0f},
    };
    for (const SceneSpec& spec : scenes) {
        osg::ref_ptr<osg::Group> scene = createSideBySideScene(
            spec.model.get(), items, spec.spacing, spec.textureScale, readOptions.get());
        writeNodeAtomically(*scene, (dir / spec.file).string());
        std::cout << "wrote " << (dir / spec.file).string() << "\n";
    }
    // 3. The shadowed cloth (Sattler et al. 2003: cast shadows and the smooth terminator) with the
    // pca fit
    //    when there is one, and the procedural sky it is lit like (for environment lighting).
    const auto shadowed = std::find_if(items.begin(), items.end(), [](const SceneItem& item) {
        return item.label == kPcaMethodName;
    });
    const std::string clothMaterial =
        (shadowed != items.end() ? *shadowed : items.front()).materialFile;
    writeNodeAtomically(*createShadowedClothScene(clothMaterial, 4.0f, readOptions.get()),
                        (dir / "cloth-shadows.osgt").string());
    std::cout << "wrote " << (dir / "cloth-shadows.osgt").string() << " (" << clothMaterial
              << ")\n";
    writeFloatImage(createSkyEnvironment(), (dir / "sky.hdr").string());
    std::cout << "wrote " << (dir / "sky.hdr").string() << " (procedural sky, CC0)\n";
    // 4. The same cloth lit by that sky, self-shadowed (Sattler et al. 2003 section 5), in any
    // viewer.
    writeNodeAtomically(
        *createEnvironmentLitClothScene(clothMaterial, "sky.hdr", 4.0f, readOptions.get()),
        (dir / "cloth-sky.osgt").string());
    std::cout << "wrote " << (dir / "cloth-sky.osgt").string() << " (" << clothMaterial
              << " under sky.hdr)\n";
    if (!options.benchFps) return;

    // 5. Frames per second of each scene with each method on every object.
    std::vector<BenchScene> benchScenes;
    for (const SceneSpec& spec : scenes)
        benchScenes.push_back({fs::path(spec.file).stem().string(),
                               [&spec, &readOptions](const std::vector<SceneItem>& sceneItems) {
                                   return createSideBySideScene(spec.model.get(), sceneItems,
                                                                spec.spacing, spec.textureScale,
                                                                readOptions.get());
                               }});
    Progress progress("scene fps", benchScenes.size() * items.size() * options.bench.lights.size());
    std::string renderer;
    const std::vector<SceneFps> results = benchmarkScenes(
        benchScenes, items, options.bench, [&] { progress.advance(); }, &renderer);
    const std::string markdown = sceneFpsMarkdown(results, options.bench, renderer);
    writeTextAtomically(markdown, dir / "bench-fps.md");
    writeTextAtomically(sceneFpsCsv(results), dir / "bench-fps.csv");
    std::cout << markdown << "wrote " << (dir / "bench-fps.md").string() << "\n";
}

}  // namespace

int main(int argc, char** argv) {
    osgBTF::useOwnPlugins();
    CLI::App app{
        "btf-examples: writes osgBTF's example scenes into a folder.\n"
        "Makes the built-in sample BTF (`btf sample`'s woven cloth) at --size x --size texels, "
        "fits it with each of --methods (sample-METHOD.btfmat), writes the model vase.osgt and "
        "three scenes with one object per method side by side under two lights: spheres.osgt, "
        "cloth.osgt (a draped tablecloth) and vases.osgt (vase.osgt through a ProxyNode); "
        "cloth-shadows.osgt (the cloth in an osgShadow::ShadowedScene: cast shadows and seed "
        "004's smooth terminator, pca material), sky.hdr (a procedural HDR sky, CC0) and "
        "cloth-sky.osgt (the cloth lit by sky.hdr with self-shadowing, computed by the scene's "
        "osgBTF::EnvironmentLitGroup when a viewer first shows it). The "
        "scenes name the materials relative to themselves, so the folder can be moved.\n"
        "View them with `btfviewer DIR/spheres.osgt` or, with OSG_LIBRARY_PATH set to osgBTF's "
        "lib folder, stock `osgviewer DIR/spheres.osgt`."};
    Options options;
    app.add_option("-o,--out", options.outputDir, "Output folder (created if missing)");
    app.add_option("--gallery", options.galleryDir,
                   "Instead of the scenes: a gallery in this folder (replaced as a whole): every "
                   "method of --methods (default: all that `btf compare --methods all` runs) "
                   "fitted by `btf compare` and rendered headless in a close-up, a grazing view, "
                   "a floor into the distance, environment lighting and cast shadows, as "
                   "pictures/METHOD-VIEW.png, and index.html showing them side by side with each "
                   "method's error, bytes per texel and pass time");
    app.add_option("--size", options.size, "Texels per side of the sample")
        ->check(CLI::Range(4, 512))
        ->capture_default_str();
    app.add_option("--methods", options.methods,
                   "Comma-separated fit methods (`btf fit --help` lists all; default options)")
        ->capture_default_str();
    app.add_option("--block-map", options.blockMap,
                   "Also write blocks-map.exr: an N x N coordinate map into the sample made of "
                   "blocks of a quarter of the sample from random places (a stand-in for `btf "
                   "synthesize`'s output; btfviewer --map)")
        ->check(CLI::Range(1, 16384));
    app.add_flag("--mipmap", options.mipmap,
                 "Fit mip-mapped materials (`btf fit --mipmap`): distant and grazing surfaces "
                 "show the average of what a pixel covers instead of aliasing; such materials "
                 "cannot be drawn through --block-map's coordinate map");
    app.add_flag("--bench-fps", options.benchFps,
                 "After writing the scenes, time them headless (EGL: the GPU where there is one, "
                 "else llvmpipe): for each scene, each method on every object and each light "
                 "count, the median frame time and frames per second; writes DIR/bench-fps.md "
                 "and DIR/bench-fps.csv");
    app.add_option("--bench-resolution", options.benchResolution, "Viewport of --bench-fps, WxH")
        ->capture_default_str();
    app.add_option("--bench-lights", options.benchLights,
                   "Comma-separated light counts of --bench-fps (1..8: the scene's key light, "
                   "its fill light, then white directional lights)")
        ->capture_default_str();
    app.add_option("--bench-frames", options.bench.frames, "Timed frames per measurement")
        ->check(CLI::PositiveNumber)
        ->capture_default_str();
    app.add_option("--bench-warmup", options.bench.warmupFrames,
                   "Untimed frames before each measurement")
        ->check(CLI::NonNegativeNumber)
        ->capture_default_str();
    app.add_option("--bench-target", options.benchTarget,
                   "Colour target of --bench-fps: rgba8 (a window), rgba16f or rgba32f")
        ->capture_default_str();
    bool progress = ::isatty(STDERR_FILENO) != 0;
    app.add_flag("--progress,!--no-progress", progress, "Progress bars while fitting");
    try {
        app.parse(argc, argv);
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    }
    osgBTF::Progress::setEnabled(progress);
    try {
        if (!options.galleryDir.empty()) {
            osgBTF::examples::GalleryOptions gallery;
            gallery.outputDir = options.galleryDir;
            gallery.size = options.size;
            if (app.count("--methods") > 0) gallery.methods = splitList(options.methods);
            std::cout << "wrote " << osgBTF::examples::writeGallery(gallery) << "\n";
            return 0;
        }
        if (options.outputDir.empty()) throw osgBTF::Error("--out or --gallery is required");
        run(options);
    } catch (const std::exception& e) {
        std::cerr << "btf-examples: " << e.what() << "\n";
        return 1;
    }
    return 0;
}
