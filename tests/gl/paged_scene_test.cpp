// A paged scene (harness/PagedScene.h) as large OSG scenes are built: 6 x 6 osg::PagedLOD tiles,
// each a .osgt file holding a MaterialNode that names a .btfmat, loaded and removed by the
// viewer's DatabasePager as the camera flies over them row by row. Checked: every tile arrives
// with its material's textures already in the context (compiled ahead by the pager's
// IncrementalCompileOperation, which sees the material's StateSet through MaterialNode::traverse),
// tiles out of range are removed, and once every tile is gone and the materials are released,
// the context holds exactly the textures and buffers it held before; no GL error throughout.
// bench_paged flies over 1,000 tiles for ten minutes (bench/README.md).
#include <algorithm>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include <gtest/gtest.h>

#include <osg/MatrixTransform>
#include <osg/PagedLOD>
#include <osgDB/DatabasePager>
#include <osgUtil/IncrementalCompileOperation>
#include <osgViewer/Viewer>

#include "harness/PagedScene.h"
#include "harness/SoakSampling.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "scene/MaterialNode.h"
#include "scene/OpenMaterial.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"
#include "tests/gl/GlErrorWatch.h"
#include "tests/gl/GlTestEnv.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

/** Whether every texture of the material under a loaded tile has a texture object in
 *  `context` (the tile: PagedLOD -> MatrixTransform -> MaterialNode). */
bool materialCompiled(const osg::PagedLOD& tile, unsigned context) {
    const auto* place = dynamic_cast<const osg::MatrixTransform*>(tile.getChild(0));
    const auto* node = place ? dynamic_cast<const MaterialNode*>(place->getChild(0)) : nullptr;
    if (!node || !node->getMaterial()) return false;
    const osg::StateSet* state = node->getMaterial()->sharedStateSet();
    int textures = 0;
    for (unsigned unit = 0; unit < state->getTextureAttributeList().size(); ++unit) {
        const auto* texture = dynamic_cast<const osg::Texture*>(
            state->getTextureAttribute(unit, osg::StateAttribute::TEXTURE));
        if (!texture) continue;
        ++textures;
        if (!texture->getTextureObject(context)) return false;
    }
    return textures > 0;
}

}  // namespace

TEST(PagedScene, TilesArriveCompiledAndLeaveNoGLObjectsBehind) {
    TempDir dir;
    const MeasuredBtf sample = smallSampleBtf(8);
    std::vector<std::string> materials;
    for (const std::string method : {"lambert", "pca"}) {
        const MethodInfo& info = findMethod(method);
        materials.push_back(dir.file(method + ".btfmat"));
        saveMaterial(*info.fit(sample, FitOptions::parse(info.quickFitOptions)), materials.back());
    }
    const PagedGrid grid{6, 6, 2.0f};
    const double height = 1.5;  // tiles within ~1.3 of the point below the eye are in range
    const std::string folder = dir.file("tiles");
    writePagedTiles(folder, materials, grid);
    const osg::ref_ptr<osg::Group> scene = pagedScene(folder, grid);
    const int tiles = int(scene->getNumChildren());

    HeadlessRenderer& renderer = sharedRenderer();
    GlErrorWatch errors;
    const osg::Vec2d away(-20.0, -20.0);  // nothing in range
    renderer.render(scene.get(), cameraAbove(away, height, 64));
    osgViewer::Viewer& viewer = renderer.viewer();
    viewer.setIncrementalCompileOperation(new osgUtil::IncrementalCompileOperation);
    osgDB::DatabasePager* pager = viewer.getDatabasePager();
    pager->setDoPreCompile(true);
    pager->setTargetMaximumNumberOfPageLOD(0);  // a tile out of range is removed at once
    osg::ref_ptr<CountGlObjects> count = new CountGlObjects;
    renderer.camera().setPostDrawCallback(count.get());
    const unsigned context = renderer.camera().getGraphicsContext()->getState()->getContextID();
    count->wanted = true;
    viewer.frame();
    const SoakSample before = count->counts;

    std::vector<bool> loaded(std::size_t(tiles), false), everLoaded(std::size_t(tiles), false);
    int merges = 0, mostLoaded = 0;
    std::vector<int> notCompiled;
    // One frame, the tiles merged by the update traversal checked before the draw.
    const auto step = [&] {
        viewer.advance();
        viewer.eventTraversal();
        viewer.updateTraversal();
        for (int i = 0; i < tiles; ++i) {
            const auto& tile = static_cast<const osg::PagedLOD&>(*scene->getChild(unsigned(i)));
            const bool has = tile.getNumChildren() > 0;
            if (has && !loaded[std::size_t(i)]) {
                ++merges;
                everLoaded[std::size_t(i)] = true;
                if (!materialCompiled(tile, context)) notCompiled.push_back(i);
            }
            loaded[std::size_t(i)] = has;
        }
        mostLoaded = std::max(mostLoaded, loadedTiles(*scene));
        viewer.renderingTraversals();
    };
    // Frames until the pager has nothing in flight (loads, compiles, merges) and the tiles left
    // behind are removed: the pager removes a tile not drawn for 0.1 s (DatabasePager::
    // removeExpiredSubgraphs), so at least 0.15 s of frames pass.
    const auto settle = [&] {
        const auto start = std::chrono::steady_clock::now();
        for (int i = 0; i < 4000; ++i) {
            step();
            const bool waited =
                std::chrono::steady_clock::now() - start > std::chrono::milliseconds(150);
            if (waited && !pager->getRequestsInProgress()) return true;
            std::this_thread::sleep_for(std::chrono::milliseconds(2));
        }
        return false;
    };
    int mostLoadedSettled = 0;
    for (double distance = 0; distance <= grid.columns * grid.rows; distance += 1.0) {
        renderer.setCamera(cameraAbove(flightPosition(grid, distance), height, 64));
        ASSERT_TRUE(settle()) << "the pager did not settle at " << distance;
        mostLoadedSettled = std::max(mostLoadedSettled, loadedTiles(*scene));
    }
    EXPECT_EQ(std::count(everLoaded.begin(), everLoaded.end(), true), tiles);
    EXPECT_GE(merges, tiles);
    EXPECT_EQ(notCompiled, std::vector<int>{}) << "tiles merged before their material compiled";
    // In range of one point: at most the 3 x 3 tiles around it (the ground radius is 1.3).
    EXPECT_LE(mostLoadedSettled, 9) << "tiles out of range were not removed";
    EXPECT_LT(mostLoaded, tiles / 2);

    // Away from the grid: every tile is removed; once the materials are released too, the
    // context holds what it held before the flight (deletion happens on the pager's thread and
    // at the next frames' flush, so a few frames pass first).
    renderer.setCamera(cameraAbove(away, height, 64));
    ASSERT_TRUE(settle());
    EXPECT_EQ(loadedTiles(*scene), 0);
    SoakSample after;
    for (int i = 0; i < 100; ++i) {
        releaseUnusedSharedObjects();
        count->wanted = true;
        step();
        after = count->counts;
        if (after.textures == before.textures && after.buffers == before.buffers) break;
        std::this_thread::sleep_for(std::chrono::milliseconds(10));
    }
    EXPECT_EQ(after.textures, before.textures);
    EXPECT_EQ(after.buffers, before.buffers);
    EXPECT_EQ(errors.take(), "");

    renderer.camera().setPostDrawCallback(nullptr);
    renderer.setScene(nullptr);
    pager->clear();
    viewer.setIncrementalCompileOperation(nullptr);
}

}  // namespace OSGBTF_TEST_FILE
