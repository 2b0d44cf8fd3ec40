#include "streaming/TileStreamer.h"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>
#include <list>
#include <map>
#include <set>
#include <sstream>

#include <osg/GL>
#include <osg/GLExtensions>
#include <osg/Notify>
#include <osg/State>
#include <osg/Texture2DArray>

#include "core/Error.h"
#include "core/Notify.h"
#include "materials/MaterialState.h"
#include "materials/fmf/Fmf.h"
#include "streaming/TileFetcher.h"
#include "streaming/TileSet.h"

#ifndef GL_HALF_FLOAT
#define GL_HALF_FLOAT 0x140B
#endif
#ifndef GL_RGBA16UI
#define GL_RGBA16UI 0x8D76
#endif
#ifndef GL_RGBA_INTEGER
#define GL_RGBA_INTEGER 0x8D99
#endif

namespace osgBTF {

namespace {

using HalfTile = std::vector<Imath::half>;
constexpr std::uint64_t kPacketKey = std::uint64_t(1) << 48;
/** Fetch priority of what everything else waits for: the level-0 tiles and U packet 0. */
constexpr double kFirst = 1e30;

}  // namespace

/** The cache texture's content, uploaded by the draw thread of each context that applies it.
 *  Every context has its own texture object, so the callback keeps each slot's current tile and,
 *  per context, the slots that context has not uploaded yet: a context that creates the texture
 *  later (a second view's, or one whose objects were released) gets every slot, not only what
 *  arrived since. The tiles are the ones the streamer keeps decoded for its resident slots. */
struct TileStreamer::CacheUploads : osg::Texture2D::SubloadCallback {
    int size = 0, padded = 0, slotsPerRow = 0;
    mutable std::mutex mutex;
    std::map<int, std::shared_ptr<const HalfTile>> slots;  ///< what each slot holds now
    mutable std::map<unsigned, std::set<int>> stale;       ///< per context ID

    void load(const osg::Texture2D&, osg::State& state) const override {
        // Undefined texels are never read: the LUTs point at uploaded slots only.
        glTexImage2D(GL_TEXTURE_2D, 0, GL_RGBA16F_ARB, size, size, 0, GL_RGBA, GL_HALF_FLOAT,
                     nullptr);
        {
            std::lock_guard<std::mutex> lock(mutex);
            std::set<int>& all = stale[state.getContextID()];
            all.clear();
            for (const auto& slot : slots) all.insert(slot.first);
        }
        flush(state.getContextID());
    }
    void subload(const osg::Texture2D&, osg::State& state) const override {
        flush(state.getContextID());
    }
    void flush(unsigned context) const {
        std::vector<std::pair<int, std::shared_ptr<const HalfTile>>> uploads;
        {
            std::lock_guard<std::mutex> lock(mutex);
            const auto it = stale.find(context);
            if (it == stale.end() || it->second.empty()) return;
            for (int slot : it->second) uploads.emplace_back(slot, slots.at(slot));
            it->second.clear();
        }
        glPixelStorei(GL_UNPACK_ALIGNMENT, 4);
        glPixelStorei(GL_UNPACK_ROW_LENGTH, 0);
        for (const auto& upload : uploads) {
            const int x = (upload.first % slotsPerRow) * padded;
            const int y = (upload.first / slotsPerRow) * padded;
            glTexSubImage2D(GL_TEXTURE_2D, 0, x, y, padded, padded, GL_RGBA, GL_HALF_FLOAT,
                            upload.second->data());
        }
    }
    void queue(int slot, std::shared_ptr<const HalfTile> tile) {
        std::lock_guard<std::mutex> lock(mutex);
        slots[slot] = std::move(tile);
        for (auto& context : stale) context.second.insert(slot);
    }
};

struct TileStreamer::Stream {
    enum class State : std::uint8_t { None, Requested, Fetched, Decoded, Failed };
    osg::ref_ptr<StreamedFmfMaterial> material;
    std::string location;
    TileSetIndex index;
    std::unique_ptr<TileFetcher> fetcher;
    std::vector<float> u;  ///< the u texture's values (zeros for missing packets)
    std::vector<State> packet, tile;
    std::vector<std::shared_ptr<const HalfTile>> decoded;  ///< per tile
    std::vector<char> uploaded;  ///< per tile: resident and its data in its slot
    std::map<std::size_t, std::vector<std::uint8_t>> fetched;  ///< tiles awaiting decoding
    std::list<std::size_t> lru;  ///< decoded tiles not resident, most recent first
    osg::ref_ptr<osg::Texture2DArray> uTexture, lutTexture;
    std::uint64_t version = 0;
    mutable std::uint64_t snapshotVersion = std::numeric_limits<std::uint64_t>::max();
    mutable osg::ref_ptr<FmfMaterial> snapshot;

    std::string describe(const std::string& path) const { return location + "/" + path; }
};

TileStreamer::TileStreamer(TileStreamerOptions options) : _options(options), _scheduler(1) {
    _uploads = new CacheUploads;
    _cache = new osg::Texture2D;
    _cache->setName("bsvtfCache");
    _cache->setInternalFormat(GL_RGBA16F_ARB);
    _cache->setSourceFormat(GL_RGBA);
    _cache->setSourceType(GL_HALF_FLOAT);
    // bsvtf.frag's filtered lookups (textureLod inside a slot, from its padding) blend the four
    // texels around the coordinate; its nearest lookups are texelFetch, which ignores the filter.
    _cache->setFilter(osg::Texture::MIN_FILTER, osg::Texture::LINEAR);
    _cache->setFilter(osg::Texture::MAG_FILTER, osg::Texture::LINEAR);
    _cache->setResizeNonPowerOfTwoHint(false);
    _cache->setUseHardwareMipMapGeneration(false);
    _cache->setSubloadCallback(_uploads.get());
    _cache->setDataVariance(osg::Object::DYNAMIC);
    if (options.tileSize > 0) configure(options.tileSize, options.padding);
}

void TileStreamer::configure(int tileSize, int padding) {
    const int padded = tileSize + 2 * padding, slotsPerRow = _options.cacheSize / padded;
    if (slotsPerRow < 1)
        throw Error("tile streamer: a cache of " + std::to_string(_options.cacheSize) +
                    " texels holds no tile of " + std::to_string(padded) + " texels");
    // The LUT's fourth 16-bit channel numbers the parent's slot (writeLut).
    if (slotsPerRow > 256)
        throw Error("tile streamer: a cache of " + std::to_string(_options.cacheSize) +
                    " texels holds " + std::to_string(slotsPerRow) + " x " +
                    std::to_string(slotsPerRow) + " tiles of " + std::to_string(padded) +
                    " texels; the lookup tables number at most 256 x 256");
    _options.tileSize = tileSize;
    _options.padding = padding;
    _padded = padded;
    _slotsPerRow = slotsPerRow;
    _scheduler = TileScheduler(slotsPerRow * slotsPerRow);
    _uploads->size = slotsPerRow * padded;
    _uploads->padded = padded;
    _uploads->slotsPerRow = slotsPerRow;
    _cache->setTextureSize(_uploads->size, _uploads->size);
}

TileStreamer::~TileStreamer() = default;

int TileStreamer::materialCount() const {
    return int(_streams.size());
}

StreamedFmfMaterial* TileStreamer::material(int index) const {
    return _streams.at(std::size_t(index))->material.get();
}

TileVotes TileStreamer::makeVotes() const {
    return _scheduler.makeVotes();
}

osg::ref_ptr<StreamedFmfMaterial> TileStreamer::open(const std::string& location) {
    auto stream = std::make_unique<Stream>();
    stream->location = location;
    while (!stream->location.empty() && stream->location.back() == '/') stream->location.pop_back();
    std::unique_ptr<TileSource> source = openTileSource(stream->location);
    const FetchResult indexFile = source->fetch(TileSetIndex::kIndexName);
    const std::string indexName = source->describe(TileSetIndex::kIndexName);
    if (!indexFile.ok) throw Error(indexFile.error);
    stream->index =
        TileSetIndex::parse(std::string(indexFile.data.begin(), indexFile.data.end()), indexName);
    _stats.bytesReceived += indexFile.data.size();
    TileSetIndex& index = stream->index;
    const TileLayout& layout = index.layout;
    if (_padded == 0) configure(layout.tileSize(), layout.padding());
    if (layout.tileSize() != _options.tileSize || layout.padding() != _options.padding)
        fail(indexName,
             "tiles of " + std::to_string(layout.tileSize()) + " + " +
                 std::to_string(layout.padding()) + " padding; this streamer's cache holds " +
                 std::to_string(_options.tileSize) + " + " + std::to_string(_options.padding));
    const auto parameter = [&](const std::string& key) {
        const auto it = index.parameters.find(key);
        if (it == index.parameters.end()) fail(indexName, "parameter '" + key + "' is missing");
        return it->second;
    };
    if (parameter("model") != kFmfPlainModel)
        fail(indexName, "model '" + parameter("model") + "': BSVTF streams fmf materials");

    std::vector<float> weights(layout.tileCount()), norms(layout.tileCount());
    for (std::size_t i = 0; i < layout.tileCount(); ++i) {
        weights[i] = index.tiles[i].weight;
        norms[i] = index.tiles[i].norm;
    }
    const int schedulerIndex = _scheduler.addMaterial(layout, weights, norms);
    const int streamIndex = int(_streams.size());

    const std::size_t groups = std::size_t(layout.groups());
    stream->packet.assign(groups, Stream::State::None);
    stream->tile.assign(layout.tileCount(), Stream::State::None);
    stream->decoded.assign(layout.tileCount(), nullptr);
    stream->uploaded.assign(layout.tileCount(), 0);
    const int rows = int(index.lights.size() * 3), views = int(index.views.size());
    stream->u.assign(groups * std::size_t(rows) * std::size_t(views) * 4, 0.0f);
    stream->uTexture = createFloatTextureArray(
        {"u", int(groups), rows, views, 4, MaterialTexture::Half, stream->u});

    const int lutW = layout.tilesX(layout.finestLevel()),
              lutH = layout.tilesY(layout.finestLevel());
    stream->lutTexture = newTexture2DArray();
    stream->lutTexture->setTextureSize(lutW, lutH, int(groups));
    for (int g = 0; g < int(groups); ++g) {
        osg::ref_ptr<osg::Image> image = new osg::Image;
        image->allocateImage(lutW, lutH, 1, GL_RGBA_INTEGER, GL_UNSIGNED_SHORT);
        image->setInternalTextureFormat(GL_RGBA16UI);
        std::memset(image->data(), 0, image->getTotalSizeInBytes());
        stream->lutTexture->setImage(g, image.get());
    }
    stream->lutTexture->setInternalFormat(GL_RGBA16UI);
    stream->lutTexture->setSourceFormat(GL_RGBA_INTEGER);
    stream->lutTexture->setSourceType(GL_UNSIGNED_SHORT);
    stream->lutTexture->setFilter(osg::Texture::MIN_FILTER, osg::Texture::NEAREST);
    stream->lutTexture->setFilter(osg::Texture::MAG_FILTER, osg::Texture::NEAREST);
    stream->lutTexture->setResizeNonPowerOfTwoHint(false);
    stream->lutTexture->setUseHardwareMipMapGeneration(false);
    stream->lutTexture->setDataVariance(osg::Object::DYNAMIC);

    osg::ref_ptr<StreamedFmfMaterial> material = new StreamedFmfMaterial;
    material->setGeometry(layout.width(), layout.height(), index.views, index.lights);
    material->_streamer = this;
    material->_index = streamIndex;
    material->_location = stream->location;
    // The name a MaterialNode of it writes into a scene file; a StreamingGroup's serializer
    // gives the material back to the nodes naming it (plugins/osgbtf).
    material->sourceFile = stream->location + "/index.bsvtf";
    material->_viewLookup = DirectionLookup(index.views);
    material->_lightLookup = DirectionLookup(index.lights);
    stream->material = material;

    TileFetcherOptions fetching;
    fetching.threads = std::max(1, _options.fetchThreads);
    fetching.tries = _options.fetchTries;
    fetching.retryDelay = _options.retryDelay;
    stream->fetcher =
        std::make_unique<TileFetcher>(std::shared_ptr<TileSource>(std::move(source)), fetching);
    // The level-0 tiles are resident from now on: zeros in their slots until their data
    // arrive, which are fetched first, with U packet 0.
    static const auto zeros =
        std::make_shared<const HalfTile>(std::size_t(_padded) * std::size_t(_padded) * 4);
    for (int g = 0; g < int(groups); ++g) {
        const TileId root{g, 0, 0, 0};
        _uploads->queue(_scheduler.slotOf(schedulerIndex, root), zeros);
        stream->fetcher->request(layout.index(root), TileSetIndex::tilePath(root), kFirst);
        stream->tile[layout.index(root)] = Stream::State::Requested;
    }
    // U packet 0 now; the others once their groups show (requestWanted).
    stream->fetcher->request(kPacketKey, TileSetIndex::uPacketPath(0), kFirst);
    stream->packet[0] = Stream::State::Requested;
    _stats.uPackets += int(groups);
    {
        std::lock_guard<std::mutex> lock(_mutex);
        _streams.push_back(std::move(stream));
    }
    writeLut(streamIndex);
    _scheduler.clearLutDirty(schedulerIndex);
    _lastOperations = 1;
    return material;
}

void TileStreamer::receive() {
    int budget = _options.decodesPerUpdate;
    for (std::size_t s = 0; s < _streams.size(); ++s) {
        Stream& stream = *_streams[s];
        const TileLayout& layout = stream.index.layout;
        for (FetchedItem& item : stream.fetcher->takeCompleted()) {
            const bool isPacket = item.key >= kPacketKey;
            const std::size_t i = std::size_t(isPacket ? item.key - kPacketKey : item.key);
            if (!item.result.ok) {
                // The fetcher has reported it (once per URL); the material renders without it.
                ++_stats.failures;
                (isPacket ? stream.packet : stream.tile)[i] = Stream::State::Failed;
                continue;
            }
            _stats.bytesReceived += item.result.data.size();
            if (!isPacket) {
                stream.fetched[i] = std::move(item.result.data);
                stream.tile[i] = Stream::State::Fetched;
                continue;
            }
            const std::string name = stream.describe(item.path);
            try {
                const std::vector<float> values =
                    stream.index.decodeUPacket(int(i), item.result.data, name);
                const std::size_t groups = std::size_t(layout.groups());
                const std::size_t rows = values.size() / 4;
                for (std::size_t r = 0; r < rows; ++r)
                    for (std::size_t j = 0; j < 4; ++j)
                        stream.u[(r * groups + i) * 4 + j] = values[r * 4 + j];
                const std::size_t perView = rows / stream.index.views.size();
                for (unsigned v = 0; v < stream.uTexture->getNumImages(); ++v) {
                    osg::Image* image = stream.uTexture->getImage(v);
                    auto* data = reinterpret_cast<float*>(image->data());
                    std::copy(stream.u.begin() + std::ptrdiff_t(v * perView * groups * 4),
                              stream.u.begin() + std::ptrdiff_t((v + 1) * perView * groups * 4),
                              data);
                    image->dirty();
                }
                stream.packet[i] = Stream::State::Decoded;
                ++_stats.uPacketsReceived;
                ++stream.version;
            } catch (const Error& e) {
                OSGBTF_NOTIFY(osg::WARN, "osgBTF: " << e.what());
                stream.packet[i] = Stream::State::Failed;
                ++_stats.failures;
            }
        }
        // Decode what has its parent (coarse levels first: the map's order is level-major).
        for (auto it = stream.fetched.begin(); it != stream.fetched.end() && budget > 0;) {
            const std::size_t i = it->first;
            const TileId t = layout.tileAt(i);
            const Imath::half* parent = nullptr;
            if (t.level > 0) {
                const std::size_t p = layout.index(TileLayout::parent(t));
                if (!stream.decoded[p]) {
                    // The parent left the RAM cache (or failed): fetch it again first.
                    if (stream.tile[p] == Stream::State::None) {
                        stream.fetcher->request(p, TileSetIndex::tilePath(layout.tileAt(p)),
                                                kFirst);
                        stream.tile[p] = Stream::State::Requested;
                    }
                    if (stream.tile[p] == Stream::State::Failed) {
                        stream.tile[i] = Stream::State::Failed;
                        it = stream.fetched.erase(it);
                        continue;
                    }
                    ++it;
                    continue;
                }
                parent = stream.decoded[p]->data();
            }
            const std::string name = stream.describe(TileSetIndex::tilePath(t));
            try {
                stream.decoded[i] = std::make_shared<const HalfTile>(
                    stream.index.decodeTile(t, it->second, parent, name));
                stream.tile[i] = Stream::State::Decoded;
                ++_stats.tilesDecoded;
                const int slot = _scheduler.slotOf(int(s), t);
                if (slot >= 0) {
                    // A resident tile without its data (a level-0 tile): upload them now.
                    _uploads->queue(slot, stream.decoded[i]);
                    stream.uploaded[i] = 1;
                    ++_stats.uploads;
                    ++stream.version;
                } else {
                    stream.lru.push_front(i);
                }
            } catch (const Error& e) {
                OSGBTF_NOTIFY(osg::WARN, "osgBTF: " << e.what());
                stream.tile[i] = Stream::State::Failed;
                ++_stats.failures;
            }
            --budget;
            it = stream.fetched.erase(it);
        }
    }
}

void TileStreamer::applyOperations(const std::vector<TileOperation>& operations) {
    for (const TileOperation& op : operations) {
        Stream& stream = *_streams[std::size_t(op.material)];
        const std::size_t i = stream.index.layout.index(op.tile);
        ++stream.version;
        if (op.kind == TileOperation::Kind::Add) {
            stream.lru.remove(i);
            _uploads->queue(op.slot, stream.decoded[i]);
            stream.uploaded[i] = 1;
            ++_stats.uploads;
        } else {
            stream.uploaded[i] = 0;
            if (stream.decoded[i]) stream.lru.push_front(i);
        }
    }
    // The RAM cache: drop the least recently used decoded tiles that are not resident.
    const std::size_t tileBytes = std::size_t(_padded) * std::size_t(_padded) * 4 * 2;
    std::size_t held = 0;
    for (const auto& stream : _streams) held += stream->lru.size() * tileBytes;
    for (auto& stream : _streams)
        while (held > _options.ramBytes && !stream->lru.empty()) {
            const std::size_t i = stream->lru.back();
            stream->lru.pop_back();
            stream->decoded[i] = nullptr;
            stream->tile[i] = Stream::State::None;
            stream->fetcher->forget(i);
            held -= tileBytes;
        }
    for (std::size_t s = 0; s < _streams.size(); ++s)
        if (_scheduler.lutDirty(int(s))) {
            writeLut(int(s));
            _scheduler.clearLutDirty(int(s));
        }
}

void TileStreamer::writeLut(int index) {
    Stream& stream = *_streams[std::size_t(index)];
    for (int g = 0; g < stream.index.layout.groups(); ++g) {
        const std::vector<LutEntry>& lut = _scheduler.lut(index, g);
        osg::Image* image = stream.lutTexture->getImage(g);
        auto* texels = reinterpret_cast<std::uint16_t*>(image->data());
        for (std::size_t e = 0; e < lut.size(); ++e) {
            texels[4 * e + 0] = std::uint16_t(lut[e].slot % _slotsPerRow);
            texels[4 * e + 1] = std::uint16_t(lut[e].slot / _slotsPerRow);
            texels[4 * e + 2] = std::uint16_t(lut[e].level);
            // The parent's slot as one number: the LUT has four channels. At level 0 (no
            // parent, never blended in) the tile's own, so that every entry names a valid slot.
            texels[4 * e + 3] =
                std::uint16_t(lut[e].parentSlot >= 0 ? lut[e].parentSlot : lut[e].slot);
        }
        image->dirty();
    }
}

void TileStreamer::requestWanted(const TileVotes& votes) {
    // What each fetcher has not been asked for yet competes for this update's request budget,
    // tiles by P = w v, U packets by Schwartz et al. 2013's group priority (sum of v ||T||^2 over
    // the group's resident tiles: a packet is worth nothing before its Eigen-Textures show).
    // Requests still waiting only get their new priority.
    struct Fresh {
        double priority;
        std::size_t stream, index;
        bool packet;
    };
    std::vector<Fresh> fresh;
    const std::size_t ahead = std::size_t(std::max(1, _options.requestsAhead)) *
                              std::max<std::size_t>(1, _streams.size());
    // A tile whose file failed, or whose parent's did (it cannot be decoded), is never wanted
    // again: it would keep its place in the window and starve the tiles behind it.
    const auto failed = [this](int m, const TileId& t) {
        const Stream& stream = *_streams[std::size_t(m)];
        const TileLayout& layout = stream.index.layout;
        return stream.tile[layout.index(t)] == Stream::State::Failed ||
               (t.level > 0 &&
                stream.tile[layout.index(TileLayout::parent(t))] == Stream::State::Failed);
    };
    for (const auto& [m, t] : _scheduler.wanted(votes, ahead, failed)) {
        Stream& stream = *_streams[std::size_t(m)];
        const std::size_t i = stream.index.layout.index(t);
        const double priority = _scheduler.priority(m, t, votes);
        if (stream.tile[i] == Stream::State::Requested)
            stream.fetcher->request(i, TileSetIndex::tilePath(t), priority);
        else if (stream.tile[i] == Stream::State::None)
            fresh.push_back({priority, std::size_t(m), i, false});
    }
    for (std::size_t s = 0; s < _streams.size(); ++s) {
        Stream& stream = *_streams[s];
        for (int g = 0; g < stream.index.layout.groups(); ++g) {
            const Stream::State state = stream.packet[std::size_t(g)];
            if (state != Stream::State::None && state != Stream::State::Requested) continue;
            const double priority = g == 0 ? kFirst : _scheduler.groupPriority(int(s), g, votes);
            if (state == Stream::State::Requested)
                stream.fetcher->request(kPacketKey + std::uint64_t(g), TileSetIndex::uPacketPath(g),
                                        priority);
            else if (priority > 0)
                fresh.push_back({priority, s, std::size_t(g), true});
        }
    }
    std::sort(fresh.begin(), fresh.end(),
              [](const Fresh& a, const Fresh& b) { return a.priority > b.priority; });
    const std::size_t budget = _options.requestsPerUpdate > 0
                                   ? std::min(fresh.size(), std::size_t(_options.requestsPerUpdate))
                                   : fresh.size();
    for (std::size_t k = 0; k < budget; ++k) {
        const Fresh& f = fresh[k];
        Stream& stream = *_streams[f.stream];
        if (f.packet) {
            stream.fetcher->request(kPacketKey + f.index, TileSetIndex::uPacketPath(int(f.index)),
                                    f.priority);
            stream.packet[f.index] = Stream::State::Requested;
        } else {
            stream.fetcher->request(
                f.index, TileSetIndex::tilePath(stream.index.layout.tileAt(f.index)), f.priority);
            stream.tile[f.index] = Stream::State::Requested;
        }
        ++_stats.requests;
    }
}

std::size_t TileStreamer::update(const TileVotes& votes) {
    std::vector<TileOperation> operations;
    {
        // snapshot() (evaluate, from any thread) reads what receive() and the operations change.
        std::lock_guard<std::mutex> lock(_mutex);
        receive();
        operations = _scheduler.step(
            votes,
            [this](int m, const TileId& t) {
                return bool(_streams[std::size_t(m)]
                                ->decoded[_streams[std::size_t(m)]->index.layout.index(t)]);
            },
            _options.uploadsPerUpdate);
        applyOperations(operations);
    }
    requestWanted(votes);
    _stats.operations += operations.size();
    _lastOperations = operations.size();
    return operations.size();
}

bool TileStreamer::settled() const {
    if (_lastOperations != 0) return false;
    // Requested and not yet taken in: pending, in flight, or delivered to the completed list.
    const auto waiting = [](const std::vector<Stream::State>& states) {
        return std::find(states.begin(), states.end(), Stream::State::Requested) != states.end();
    };
    for (const auto& stream : _streams)
        if (!stream->fetched.empty() || waiting(stream->tile) || waiting(stream->packet))
            return false;
    return true;
}

StreamingStats TileStreamer::stats() const {
    StreamingStats s = _stats;
    s.residentTiles = _scheduler.used();
    return s;
}

std::uint64_t TileStreamer::materialGpuBytes(int index) const {
    const Stream& stream = *_streams.at(std::size_t(index));
    const TileLayout& layout = stream.index.layout;
    const std::uint64_t lut = std::uint64_t(layout.tilesX(layout.finestLevel())) *
                              std::uint64_t(layout.tilesY(layout.finestLevel())) *
                              std::uint64_t(layout.groups()) * 8;
    return std::uint64_t(stream.u.size()) * 2 + lut;
}

std::uint64_t TileStreamer::plainFmfGpuBytes(int index) const {
    const Stream& stream = *_streams.at(std::size_t(index));
    const TileLayout& layout = stream.index.layout;
    return std::uint64_t(stream.u.size()) * 2 + std::uint64_t(layout.width()) *
                                                    std::uint64_t(layout.height()) *
                                                    std::uint64_t(layout.groups()) * 8;
}

std::uint64_t TileStreamer::gpuBytes() const {
    std::uint64_t bytes = std::uint64_t(_uploads->size) * std::uint64_t(_uploads->size) * 8;
    for (int i = 0; i < materialCount(); ++i) bytes += materialGpuBytes(i);
    return bytes;
}

osg::ref_ptr<FmfMaterial> TileStreamer::snapshot(int index) const {
    std::lock_guard<std::mutex> lock(_mutex);
    const Stream& stream = *_streams.at(std::size_t(index));
    if (stream.snapshot && stream.snapshotVersion == stream.version) return stream.snapshot;
    const TileLayout& layout = stream.index.layout;
    const int W = layout.width(), H = layout.height(), T = layout.tileSize(), P = layout.padding(),
              side = layout.paddedTileSize(), L = layout.finestLevel();
    std::vector<float> sxv(std::size_t(W) * std::size_t(H) * std::size_t(layout.groups()) * 4,
                           0.0f);
    for (int g = 0; g < layout.groups(); ++g) {
        const std::vector<LutEntry>& lut = _scheduler.lut(index, g);
        const int lutW = layout.tilesX(L);
        for (int y = 0; y < H; ++y)
            for (int x = 0; x < W; ++x) {
                // What bsvtf.frag's fmfEigenTexture reads for this texel.
                const LutEntry e = lut[std::size_t(y / T) * std::size_t(lutW) + std::size_t(x / T)];
                const int lx = x >> (L - e.level), ly = y >> (L - e.level);
                const TileId t{g, e.level, lx / T, ly / T};
                const std::size_t i = layout.index(t);
                if (!stream.uploaded[i]) continue;
                const Imath::half* v =
                    stream.decoded[i]->data() + (std::size_t(ly - t.y * T + P) * std::size_t(side) +
                                                 std::size_t(lx - t.x * T + P)) *
                                                    4;
                float* out = sxv.data() +
                             ((std::size_t(g) * std::size_t(H) + std::size_t(y)) * std::size_t(W) +
                              std::size_t(x)) *
                                 4;
                for (int c = 0; c < 4; ++c) out[c] = float(v[c]);
            }
    }
    stream.snapshot = stream.index.material(stream.u, std::move(sxv), stream.location);
    stream.snapshotVersion = stream.version;
    return stream.snapshot;
}

std::vector<float> TileStreamer::filteredEigenTextures(int index, float u, float v,
                                                       float lod) const {
    std::lock_guard<std::mutex> lock(_mutex);
    const Stream& stream = *_streams.at(std::size_t(index));
    const TileLayout& layout = stream.index.layout;
    const int W = layout.width(), H = layout.height(), T = layout.tileSize(), P = layout.padding(),
              side = layout.paddedTileSize(), L = layout.finestLevel();
    if (P < 1) throw Error("tile streamer: tiles without padding are not filtered from the cache");
    // surface_frame.glsl's btfLevelTexel(uv, 0): the finest texel that picks the LUT entry.
    const float fu = u - std::floor(u), fv = v - std::floor(v);
    const int x = std::clamp(int(std::floor(fu * float(W))), 0, W - 1);
    const int y = std::clamp(int(std::floor(fv * float(H))), 0, H - 1);
    // bsvtfSample: GL_LINEAR at the fragment's coordinate in `level`, inside the padded tile
    // containing texel (x, y) of the finest level (its footprint never leaves the padding).
    const auto sample = [&](int group, int level, float out[4]) {
        const int shift = L - level;
        const TileId t{group, level, (x >> shift) / T, (y >> shift) / T};
        const std::size_t i = layout.index(t);
        const float scale = float(1 << shift);
        const float sx = fu * float(W) / scale - float(t.x * T) + float(P) - 0.5f;
        const float sy = fv * float(H) / scale - float(t.y * T) + float(P) - 0.5f;
        const int x0 = int(std::floor(sx)), y0 = int(std::floor(sy));
        const float a = sx - float(x0), b = sy - float(y0);
        for (int c = 0; c < 4; ++c) out[c] = 0.0f;
        if (!stream.uploaded[i]) return;
        if (x0 < 0 || y0 < 0 || x0 + 1 >= side || y0 + 1 >= side)
            throw Error("tile streamer: a filtered lookup left its tile's padding");
        const Imath::half* data = stream.decoded[i]->data();
        const auto at = [&](int px, int py, int c) {
            return float(
                data[(std::size_t(py) * std::size_t(side) + std::size_t(px)) * 4 + std::size_t(c)]);
        };
        for (int c = 0; c < 4; ++c)
            out[c] = (1 - a) * (1 - b) * at(x0, y0, c) + a * (1 - b) * at(x0 + 1, y0, c) +
                     (1 - a) * b * at(x0, y0 + 1, c) + a * b * at(x0 + 1, y0 + 1, c);
    };
    std::vector<float> values(std::size_t(layout.groups()) * 4, 0.0f);
    for (int g = 0; g < layout.groups(); ++g) {
        const LutEntry e = _scheduler.lookup(index, g, x / T, y / T);
        float* out = values.data() + std::size_t(g) * 4;
        sample(g, e.level, out);
        // The parent level's share: the level of detail beyond the deepest level, at most 1.
        const float excess = lod - float(L - e.level);
        const float coarser = e.level > 0 && excess > 0.0f ? std::min(excess, 1.0f) : 0.0f;
        if (!(coarser > 0.0f)) continue;
        float parent[4];
        sample(g, e.level - 1, parent);
        for (int c = 0; c < 4; ++c) out[c] = out[c] * (1.0f - coarser) + parent[c] * coarser;
    }
    return values;
}

osg::ref_ptr<osg::StateSet> TileStreamer::createStateSet(
    const StreamedFmfMaterial& material) const {
    const Stream& stream = *_streams.at(std::size_t(material.streamIndex()));
    const TileSetIndex& index = stream.index;
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    // The LUT and U change while it renders: the viewer must not update them during a draw.
    stateSet->setDataVariance(osg::Object::DYNAMIC);
    addCommonState(*stateSet, material);
    addTexture(*stateSet, stream.uTexture.get(), "fmfU", 0);
    addTexture(*stateSet, _cache.get(), "bsvtfCache", 1);
    material._viewLookup.addToStateSet(*stateSet, "fmfViewTable", 2);
    material._lightLookup.addToStateSet(*stateSet, "fmfLightTable", 3);
    addTexture(*stateSet, stream.lutTexture.get(), "bsvtfLut", 4);
    const auto number = [&](const std::string& key) {
        const auto it = index.parameters.find(key);
        if (it == index.parameters.end()) return 0.0f;
        std::istringstream in(it->second);
        float v = 0;
        in >> v;
        return v;
    };
    stateSet->addUniform(new osg::Uniform("fmfShared", 1));
    stateSet->addUniform(new osg::Uniform("fmfGroups", index.layout.groups(), 0, 0));
    stateSet->addUniform(new osg::Uniform("fmfLayerOffset", 0, 0, 0));
    stateSet->addUniform(new osg::Uniform("fmfColorModel", 0));
    stateSet->addUniform(new osg::Uniform("fmfDrr", number("dynamicRangeReduction") != 0 ? 1 : 0));
    stateSet->addUniform(new osg::Uniform("fmfEps", number("eps")));
    stateSet->addUniform(new osg::Uniform("fmfCosine", number("cosine") != 0 ? 1 : 0));
    stateSet->addUniform(new osg::Uniform("bsvtfTile", index.layout.tileSize(),
                                          index.layout.padding(), index.layout.finestLevel()));
    stateSet->addUniform(new osg::Uniform("bsvtfMaterialId", material.streamIndex()));
    return stateSet;
}

// ---- StreamedFmfMaterial -----------------------------------------------------------------------

osg::ref_ptr<FmfMaterial> StreamedFmfMaterial::snapshot() const {
    osg::ref_ptr<TileStreamer> streamer;
    if (!_streamer.lock(streamer))
        fail(_location, "the tile streamer of this streamed material no longer exists");
    return streamer->snapshot(_index);
}

glm::vec3 StreamedFmfMaterial::evaluate(int x, int y, const glm::vec3& view,
                                        const glm::vec3& light) const {
    return snapshot()->evaluate(x, y, view, light);
}

bool StreamedFmfMaterial::linearInParameters() const {
    osg::ref_ptr<TileStreamer> streamer;
    return _streamer.lock(streamer) && streamer->options().padding > 0;
}

glm::vec3 StreamedFmfMaterial::evaluateLinear(int x, int y, const glm::vec3& view,
                                              const glm::vec3& light) const {
    return snapshot()->evaluateLinear(x, y, view, light);
}

glm::vec3 StreamedFmfMaterial::evaluateResidentFiltered(float u, float v, float lod,
                                                        const glm::vec3& view,
                                                        const glm::vec3& light) const {
    // Without padding the shader blends the values of the four texels, each at its deepest
    // level: Material's filter over the snapshot does the same.
    if (!linearInParameters()) return evaluateFiltered(u, v, lod, view, light);
    osg::ref_ptr<TileStreamer> streamer;
    if (!_streamer.lock(streamer))
        fail(_location, "the tile streamer of this streamed material no longer exists");
    const std::vector<float> sxv = streamer->filteredEigenTextures(_index, u, v, lod);
    const osg::ref_ptr<FmfMaterial> fmf = snapshot();
    std::array<std::size_t, 9> images;
    std::array<float, 9> weights;
    const int count = fmf->directionCombinations(view, light, images, weights);
    // FmfMaterial::factorSums with the filtered values in place of a texel's SxV row: the U rows
    // blended per group of 4 components, then one dot product (fmf_eval.glsl's order).
    const int k = fmf->factors().components(0);
    std::vector<float> rows(std::size_t(count) * std::size_t(k));
    float sums[3];
    for (int c = 0; c < 3; ++c) {
        for (int i = 0; i < count; ++i)
            fmf->uRow(images[std::size_t(i)], c, rows.data() + std::size_t(i) * std::size_t(k));
        float sum = 0.0f;
        for (int g = 0; g < k; g += 4) {
            float blended[4] = {0, 0, 0, 0};
            const int n = std::min(4, k - g);
            for (int i = 0; i < count; ++i) {
                const float* row = rows.data() + std::size_t(i) * std::size_t(k) + std::size_t(g);
                for (int j = 0; j < n; ++j) blended[j] += weights[std::size_t(i)] * row[j];
            }
            for (int j = 0; j < n; ++j) sum += blended[j] * sxv[std::size_t(g + j)];
        }
        sums[c] = sum;
    }
    return fmf->finishLinear(glm::vec3(sums[0], sums[1], sums[2]), view, light);
}

glm::vec3 StreamedFmfMaterial::finishLinear(const glm::vec3& linear, const glm::vec3& view,
                                            const glm::vec3& light) const {
    return snapshot()->finishLinear(linear, view, light);
}

void StreamedFmfMaterial::evaluateMeasured(std::size_t texel, float* abrdf) const {
    snapshot()->evaluateMeasured(texel, abrdf);
}

MemoryFootprint StreamedFmfMaterial::memory() const {
    osg::ref_ptr<TileStreamer> streamer;
    if (!_streamer.lock(streamer)) return {};
    const std::uint64_t bytes = streamer->materialGpuBytes(_index);
    return {0.0, double(bytes) / double(std::max<std::size_t>(1, texelCount())), bytes, bytes};
}

FittedMaterial StreamedFmfMaterial::toFittedMaterial() const {
    return snapshot()->toFittedMaterial();
}

osg::ref_ptr<osg::StateSet> StreamedFmfMaterial::createStateSet() const {
    osg::ref_ptr<TileStreamer> streamer;
    if (!_streamer.lock(streamer))
        fail(_location, "the tile streamer of this streamed material no longer exists");
    return streamer->createStateSet(*this);
}

}  // namespace osgBTF
