// A paged scene built the way large OSG scenes are: a grid of osg::PagedLOD tiles, each a file
// (.osgt) holding a MaterialNode over a unit patch, which the viewer's DatabasePager loads when
// the camera comes within range (its GL objects compiled ahead by the pager's
// IncrementalCompileOperation) and removes when the tile has been out of range, deleting its GL
// objects. tests/gl/paged_scene_test.cpp checks it; bench_paged (runPagedSoak) flies over 1,000
// tiles for ten minutes and samples memory, GL objects and frame times.
#pragma once

#include <string>
#include <vector>

#include <osg/Group>
#include <osg/Vec2d>

#include "harness/Soak.h"
#include "harness/headless/HeadlessRenderer.h"

namespace osgBTF {

struct PagedGrid {
    int columns = 8, rows = 8;
    /** A tile's file is loaded while the eye is within this distance of its centre. */
    float range = 3.0f;
};

/** Writes tile_<x>_<y>.osgt into `folder` (created) for every tile of `grid`: a unit patch from
 *  (x, y) to (x + 1, y + 1) in the z = 0 plane under a MaterialNode of
 *  materialFiles[(x + y) % n], which the file names (osgBTF's serializers). Throws Error when a
 *  file cannot be written or the list is empty. */
void writePagedTiles(const std::string& folder, const std::vector<std::string>& materialFiles,
                     const PagedGrid& grid);

/** The grid of PagedLODs naming those files, none loaded. */
osg::ref_ptr<osg::Group> pagedScene(const std::string& folder, const PagedGrid& grid);

/** Tiles whose file is loaded now (PagedLODs of `scene` with a child). */
int loadedTiles(const osg::Group& scene);

/** Looking straight down at `ground` from `height` above it (60 degree field of view), a
 *  `size` x `size` viewport. */
CameraSetup cameraAbove(const osg::Vec2d& ground, double height, int size);

/** Where the flight over `grid` is after `distance` tiles: row by row (y = row + 0.5), left to
 *  right on even rows and back on odd ones, then again from the first row. */
osg::Vec2d flightPosition(const PagedGrid& grid, double distance);

struct PagedSoakOptions {
    PagedGrid grid{40, 25, 3.0f};  ///< 1,000 tiles
    double seconds = 600;
    double tilesPerSecond = 4;  ///< flight speed
    double height = 2.0;        ///< eye above the ground
    int size = 256;             ///< viewport side
    double sampleSeconds = 10;
    /** Samples before this are reported, not judged (default: one pass over the grid's rows). */
    double warmupSeconds = -1;
    /** DatabasePager::setTargetMaximumNumberOfPageLOD: tiles kept loaded out of range. */
    unsigned keepTiles = 16;
    double rssToleranceMiB = 8.0;
    /** GL objects may exceed the largest warm-up count by this many (the tiles loaded at once
     *  vary with where the camera is over the grid). */
    int glObjectTolerance = 8;
};

struct PagedSoakSample : SoakSample {
    double seconds = 0;
    int loadedTiles = 0;
    double medianFrameMs = 0, maxFrameMs = 0;  ///< over the frames since the previous sample
};

struct PagedSoakResult {
    std::vector<PagedSoakSample> samples;
    int frames = 0;
    std::size_t tileLoads = 0;  ///< tiles merged into the scene, in all
    int mostLoaded = 0;         ///< tiles loaded at once, at most
    double seconds = 0, maxFrameMs = 0, warmupSeconds = 0;
    std::string growth;  ///< empty when flat after warm-up
};

/** Flies over the tiles of `folder` (writePagedTiles with options.grid) for options.seconds
 *  under renderer's viewer, with its DatabasePager and an IncrementalCompileOperation, sampling
 *  every sampleSeconds. Leaves the renderer without a scene, pager requests or compile
 *  operation. */
PagedSoakResult runPagedSoak(HeadlessRenderer& renderer, const std::string& folder,
                             const PagedSoakOptions& options);

/** One line per sample and a verdict, for people. */
std::string formatPagedSoak(const PagedSoakResult& result);

}  // namespace osgBTF
