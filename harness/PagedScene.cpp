#include "harness/PagedScene.h"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <filesystem>
#include <iomanip>
#include <sstream>

#include <osg/MatrixTransform>
#include <osg/PagedLOD>
#include <osgDB/DatabasePager>
#include <osgDB/WriteFile>
#include <osgUtil/IncrementalCompileOperation>
#include <osgViewer/Viewer>

#include "core/Error.h"
#include "harness/SoakSampling.h"
#include "scene/MaterialNode.h"
#include "scene/OpenMaterial.h"

namespace fs = std::filesystem;

namespace osgBTF {

namespace {

std::string tileFile(const std::string& folder, int x, int y) {
    return (fs::path(folder) / ("tile_" + std::to_string(x) + "_" + std::to_string(y) + ".osgt"))
        .string();
}

}  // namespace

void writePagedTiles(const std::string& folder, const std::vector<std::string>& materialFiles,
                     const PagedGrid& grid) {
    if (materialFiles.empty()) throw Error(folder + ": paged tiles need material files");
    if (grid.columns < 1 || grid.rows < 1) throw Error(folder + ": the grid has no tiles");
    std::error_code ec;
    fs::create_directories(folder, ec);
    if (ec) throw Error(folder + ": cannot create: " + ec.message());
    for (int y = 0; y < grid.rows; ++y)
        for (int x = 0; x < grid.columns; ++x) {
            osg::ref_ptr<MaterialNode> node = new MaterialNode;
            node->setMaterialFile(materialFiles[std::size_t(x + y) % materialFiles.size()]);
            node->addChild(createFullScreenQuad().get());
            osg::ref_ptr<osg::MatrixTransform> place =
                new osg::MatrixTransform(osg::Matrix::translate(x, y, 0));
            place->addChild(node.get());
            const std::string file = tileFile(folder, x, y);
            if (!osgDB::writeNodeFile(*place, file))
                throw Error(file + ": cannot write the tile (is osgDB's osg plugin installed?)");
        }
    releaseUnusedSharedObjects();  // the materials loaded for writing
}

osg::ref_ptr<osg::Group> pagedScene(const std::string& folder, const PagedGrid& grid) {
    osg::ref_ptr<osg::Group> scene = new osg::Group;
    for (int y = 0; y < grid.rows; ++y)
        for (int x = 0; x < grid.columns; ++x) {
            osg::ref_ptr<osg::PagedLOD> tile = new osg::PagedLOD;
            tile->setCenterMode(osg::LOD::USER_DEFINED_CENTER);
            tile->setCenter(osg::Vec3(float(x) + 0.5f, float(y) + 0.5f, 0.0f));
            tile->setRadius(0.75f);
            tile->setFileName(0, tileFile(folder, x, y));
            tile->setRange(0, 0.0f, grid.range);
            scene->addChild(tile.get());
        }
    return scene;
}

int loadedTiles(const osg::Group& scene) {
    int loaded = 0;
    for (unsigned i = 0; i < scene.getNumChildren(); ++i) {
        const auto* tile = dynamic_cast<const osg::PagedLOD*>(scene.getChild(i));
        loaded += tile && tile->getNumChildren() > 0 ? 1 : 0;
    }
    return loaded;
}

CameraSetup cameraAbove(const osg::Vec2d& ground, double height, int size) {
    CameraSetup setup;
    setup.view =
        osg::Matrixd::lookAt(osg::Vec3d(ground.x(), ground.y(), height),
                             osg::Vec3d(ground.x(), ground.y(), 0.0), osg::Vec3d(0.0, 1.0, 0.0));
    setup.projection = osg::Matrixd::perspective(60.0, 1.0, 0.05 * height, 4.0 * height);
    setup.width = setup.height = size;
    return setup;
}

osg::Vec2d flightPosition(const PagedGrid& grid, double distance) {
    const double along = std::fmod(std::max(0.0, distance), double(grid.columns * grid.rows));
    const int row = int(along / grid.columns);
    const double x = std::fmod(along, double(grid.columns));
    return {row % 2 == 0 ? x : grid.columns - x, row + 0.5};
}

PagedSoakResult runPagedSoak(HeadlessRenderer& renderer, const std::string& folder,
                             const PagedSoakOptions& options) {
    if (!(options.seconds > 0) || !(options.sampleSeconds > 0) || !(options.tilesPerSecond > 0))
        throw Error("paged soak: seconds, sample interval and speed must be positive");
    PagedSoakResult result;
    result.warmupSeconds =
        options.warmupSeconds >= 0
            ? options.warmupSeconds
            : double(options.grid.columns * options.grid.rows) / options.tilesPerSecond;
    const osg::ref_ptr<osg::Group> scene = pagedScene(folder, options.grid);
    renderer.render(scene.get(), cameraAbove(flightPosition(options.grid, 0), options.height,
                                             options.size));  // realizes the viewer
    osgViewer::Viewer& viewer = renderer.viewer();
    viewer.setIncrementalCompileOperation(new osgUtil::IncrementalCompileOperation);
    osgDB::DatabasePager* pager = viewer.getDatabasePager();
    pager->setDoPreCompile(true);
    pager->setTargetMaximumNumberOfPageLOD(options.keepTiles);
    osg::ref_ptr<CountGlObjects> count = new CountGlObjects;
    renderer.camera().setPostDrawCallback(count.get());

    using Clock = std::chrono::steady_clock;
    const auto start = Clock::now();
    double nextSample = options.sampleSeconds;
    std::vector<double> frameMs;
    std::vector<bool> loaded(scene->getNumChildren(), false);
    for (;;) {
        const double now = std::chrono::duration<double>(Clock::now() - start).count();
        if (now >= options.seconds) break;
        renderer.setCamera(cameraAbove(flightPosition(options.grid, now * options.tilesPerSecond),
                                       options.height, options.size));
        const bool sample = now >= nextSample;
        count->wanted = sample;
        const auto before = Clock::now();
        viewer.frame();
        const double ms = std::chrono::duration<double, std::milli>(Clock::now() - before).count();
        ++result.frames;
        for (unsigned i = 0; i < scene->getNumChildren(); ++i) {
            const bool has = static_cast<osg::Group*>(scene->getChild(i))->getNumChildren() > 0;
            if (has && !loaded[i]) ++result.tileLoads;
            loaded[i] = has;
        }
        result.mostLoaded = std::max(result.mostLoaded, loadedTiles(*scene));
        if (!sample) {  // the sample's own frame counts objects: not a frame time
            frameMs.push_back(ms);
            result.maxFrameMs = std::max(result.maxFrameMs, ms);
            continue;
        }
        PagedSoakSample s;
        static_cast<SoakSample&>(s) = count->counts;
        s.frame = result.frames;
        s.seconds = now;
        s.rssMiB = trimmedResidentMiB();
        s.loadedTiles = loadedTiles(*scene);
        if (!frameMs.empty()) {
            std::sort(frameMs.begin(), frameMs.end());
            s.medianFrameMs = frameMs[frameMs.size() / 2];
            s.maxFrameMs = frameMs.back();
        }
        frameMs.clear();
        result.samples.push_back(s);
        nextSample += options.sampleSeconds;
    }
    result.seconds = std::chrono::duration<double>(Clock::now() - start).count();
    renderer.camera().setPostDrawCallback(nullptr);
    renderer.setScene(nullptr);
    pager->clear();
    viewer.setIncrementalCompileOperation(nullptr);
    result.growth = growthAfterWarmup(
        result.samples, [&](const PagedSoakSample& s) { return s.seconds <= result.warmupSeconds; },
        options.rssToleranceMiB, options.glObjectTolerance);
    return result;
}

std::string formatPagedSoak(const PagedSoakResult& result) {
    std::ostringstream out;
    out << "    s  tiles   RSS MiB  textures  programs  buffers  frame ms (median, max)\n";
    for (const PagedSoakSample& s : result.samples)
        out << std::fixed << std::setprecision(0) << std::setw(5) << s.seconds << std::setw(7)
            << s.loadedTiles << std::setprecision(1) << std::setw(10) << s.rssMiB << std::setw(10)
            << s.textures << std::setw(10) << s.programs << std::setw(9) << s.buffers
            << std::setw(10) << s.medianFrameMs << std::setw(9) << s.maxFrameMs << "\n";
    out << std::setprecision(1) << result.seconds << " s, " << result.frames << " frames, "
        << result.tileLoads << " tile loads, at most " << result.mostLoaded
        << " tiles loaded at once, slowest frame " << result.maxFrameMs << " ms; warm-up "
        << result.warmupSeconds << " s\n"
        << (result.growth.empty() ? "flat after warm-up\n" : "GROWTH: " + result.growth + "\n");
    return out.str();
}

}  // namespace osgBTF
