// osgBTF BSVTF runtime (Schwartz et al. 2013 sections 3, 5, 6): one tile cache texture shared by
// every streamed material, the scheduler that fills it, and the fetchers that bring the files.
//
// Per update (StreamingGroup calls update() in the update traversal with the feedback's votes):
//   1. fetched files in: U packets go straight into the material's U texture; tiles are checked
//      (size, CRC) and decoded against their decoded parent (within a per-update budget) into
//      RAM, where they stay while resident and in an LRU of the others;
//   2. one scheduler step (streaming/TileScheduler.h): adds and drops; the added tiles' data are
//      queued for upload (at most uploadsPerUpdate) and the changed LUTs rewritten;
//   3. requests out: the scheduler's most wanted tiles whose data are not in RAM (their parents'
//      first when those were dropped), and the U packets by Schwartz et al. 2013's group priority
//      (packet 0 at once, the others once their group shows), highest priority first over all
//      materials, each through its material's fetcher (a folder or HTTP, streaming/TileFetcher.h).
// A fetch that fails (404, 500, timeout, a truncated or corrupted file) is reported once and
// not retried; the material keeps rendering from what it has. The GL side: the cache texture
// uploads the queued tiles when it is applied (one graphics context).
#pragma once

#include <chrono>

#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <vector>

#include <osg/Referenced>
#include <osg/Texture2D>
#include <osg/ref_ptr>

#include "streaming/StreamedMaterial.h"
#include "streaming/TileScheduler.h"

namespace osgBTF {

struct TileStreamerOptions {
    /** Every tile set this streamer opens must have this tile size and padding (the cache's
     *  slots are (T + 2 P)^2 texels); tileSize 0: those of the first tile set opened. */
    int tileSize = 0;
    int padding = 0;
    /** Texels per side of the RGBA16F cache (Schwartz et al. 2013: 4032 = 56 slots of 72, 124 MiB).
     */
    int cacheSize = 4032;
    int uploadsPerUpdate = 32;  ///< tiles added to the cache per update (the upload budget)
    int decodesPerUpdate = 64;  ///< tiles decoded per update
    int requestsAhead = 64;     ///< wanted tiles considered per update, per material
    /** New files requested per update, highest priority first over every material (0: no
     *  limit). A limit paces the requests like a slow link would, so that what arrives first
     *  is what matters most (Schwartz et al. 2013 section 6). */
    int requestsPerUpdate = 0;
    int fetchThreads = 2;  ///< per material
    /** Tries of a file that fails transiently, and the delay before the second try (doubling
     *  after that): TileFetcherOptions::tries and retryDelay. */
    int fetchTries = 5;
    std::chrono::milliseconds retryDelay{500};
    std::size_t ramBytes = std::size_t(512) << 20;  ///< decoded tiles kept that are not resident
};

struct StreamingStats {
    std::uint64_t bytesReceived = 0;  ///< tiles, packets and indexes, as fetched
    std::uint64_t tilesDecoded = 0, uploads = 0, operations = 0, requests = 0, failures = 0;
    int residentTiles = 0;
    int uPacketsReceived = 0, uPackets = 0;
};

class TileStreamer : public osg::Referenced {
public:
    /** Throws Error when the cache holds no tile (cacheSize < the padded tile side; with
     *  tileSize 0 open() checks that). */
    explicit TileStreamer(TileStreamerOptions options = {});

    /** Opens the tile set at `location` (a folder, or an http:// or https:// URL of the folder):
     *  reads its index now (throws Error naming it and the problem, e.g. a missing index or a
     *  tile size other than the streamer's), registers the material with the scheduler (its
     *  level-0 tiles resident at once) and requests its first data. */
    osg::ref_ptr<StreamedFmfMaterial> open(const std::string& location);
    int materialCount() const;
    StreamedFmfMaterial* material(int index) const;

    TileVotes makeVotes() const;
    /** One update (see the top of this file); returns the scheduler's operation count. */
    std::size_t update(const TileVotes& votes);
    /** True when the last update changed nothing and nothing is in flight or waits for
     *  decoding: for a static camera, the streamed scene has converged. */
    bool settled() const;

    osg::Texture2D* cacheTexture() const { return _cache.get(); }
    int cacheSlotsPerRow() const { return _slotsPerRow; }
    const TileScheduler& scheduler() const { return _scheduler; }
    const TileStreamerOptions& options() const { return _options; }
    StreamingStats stats() const;
    /** GPU bytes: the cache plus every material's U and LUT textures. */
    std::uint64_t gpuBytes() const;

    /** StreamedFmfMaterial's data, by material index (see there). */
    osg::ref_ptr<FmfMaterial> snapshot(int index) const;
    /** What bsvtf.frag's fmfEigenTexture returns now for a filtered fragment (padding > 0) at
     *  texture coordinate (u, v) and level of detail `lod` (log2 of finest texels per pixel):
     *  four values per group, group by group, in the shader's float arithmetic, zeros for data
     *  not uploaded. StreamedFmfMaterial::evaluateResidentFiltered's Eigen-Texture side. */
    std::vector<float> filteredEigenTextures(int index, float u, float v, float lod) const;
    osg::ref_ptr<osg::StateSet> createStateSet(const StreamedFmfMaterial& material) const;
    std::uint64_t materialGpuBytes(int index) const;
    /** What the same material takes on the GPU as a plain fmf material: half U and SxV, the
     *  textures FmfMaterial uploads (Schwartz et al. 2013 Table 2's FMF column). */
    std::uint64_t plainFmfGpuBytes(int index) const;

    struct Stream;  // TileStreamer.cpp

protected:
    ~TileStreamer() override;

private:
    void applyOperations(const std::vector<TileOperation>& operations);
    void receive();
    void requestWanted(const TileVotes& votes);
    void writeLut(int index);
    /** Sizes the cache's slots and the scheduler for tiles of T + 2 P texels. */
    void configure(int tileSize, int padding);

    TileStreamerOptions _options;
    int _padded = 0, _slotsPerRow = 0;
    TileScheduler _scheduler;
    osg::ref_ptr<osg::Texture2D> _cache;
    struct CacheUploads;
    osg::ref_ptr<CacheUploads> _uploads;
    std::vector<std::unique_ptr<Stream>> _streams;
    std::size_t _lastOperations = 1;
    StreamingStats _stats;
    mutable std::mutex _mutex;  // _streams' snapshots (evaluate may run beside an update)
};

}  // namespace osgBTF
