#include "streaming/TileSet.h"

#include <zlib.h>

#include <cmath>
#include <cstring>
#include <fstream>
#include <iomanip>
#include <limits>
#include <set>
#include <sstream>

#include "core/Error.h"
#include "core/FittedMaterialFile.h"
#include "materials/ForeignFiles.h"
#include "materials/fmf/Fmf.h"

namespace osgBTF {

std::string TileSetIndex::tilePath(const TileId& t) {
    return "tiles/" + std::to_string(t.group) + "/" + std::to_string(t.level) + "/" +
           std::to_string(t.x) + "_" + std::to_string(t.y) + ".tile";
}

std::string TileSetIndex::uPacketPath(int group) {
    return "u/" + std::to_string(group) + ".half";
}

std::string TileSetIndex::serialize() const {
    std::ostringstream out;
    out << "osgBTF-bsvtf " << kVersion << "\n";
    out << "size " << layout.width() << " " << layout.height() << "\n";
    out << "tile " << layout.tileSize() << " " << layout.padding() << "\n";
    out << "groups " << layout.groups() << "\n";
    out << "components " << components << "\n";
    if (codec == "raw")
        out << "codec raw\n";
    else
        out << "codec dct " << codecSettings.quality << " " << floatText(codecSettings.unit)
            << "\n";
    for (const auto& [key, value] : parameters) out << "param " << key << " " << value << "\n";
    out << "views " << views.serialize() << "\n";
    out << "lights " << lights.serialize() << "\n";
    for (std::size_t g = 0; g < uPackets.size(); ++g)
        out << "u " << g << " " << uPackets[g].bytes << " " << uPackets[g].crc << "\n";
    for (std::size_t i = 0; i < tiles.size(); ++i) {
        const TileId t = layout.tileAt(i);
        const TileRecord& r = tiles[i];
        out << "t " << t.group << " " << t.level << " " << t.x << " " << t.y << " " << r.bytes
            << " " << r.crc << " " << floatText(r.weight) << " " << floatText(r.norm) << "\n";
    }
    out << "end\n";
    return out.str();
}

TileSetIndex TileSetIndex::parse(const std::string& text, const std::string& source) {
    TileSetIndex index;
    std::istringstream in(text);
    std::string line;
    int lineNumber = 0;
    auto problem = [&](const std::string& what) {
        fail(source, "line " + std::to_string(lineNumber) + ": " + what);
    };
    // Every number is read whole: "12x" or a trailing word is an error, not 12.
    auto words = [](const std::string& rest) {
        std::vector<std::string> out;
        std::istringstream s(rest);
        for (std::string w; s >> w;) out.push_back(w);
        return out;
    };
    auto integer = [&](const std::string& w, long long low, long long high) {
        std::size_t used = 0;
        long long v = 0;
        try {
            v = std::stoll(w, &used);
        } catch (const std::logic_error&) {
            used = 0;
        }
        if (used != w.size() || w.empty() || v < low || v > high)
            problem("'" + w + "' is not an integer in [" + std::to_string(low) + ", " +
                    std::to_string(high) + "]");
        return v;
    };
    auto number = [&](const std::string& w) {
        std::size_t used = 0;
        float v = 0;
        try {
            v = std::stof(w, &used);
        } catch (const std::logic_error&) {
            used = 0;
        }
        if (used != w.size() || w.empty() || !std::isfinite(v))
            problem("'" + w + "' is not a finite number");
        return v;
    };
    auto expectWords = [&](const std::vector<std::string>& w, std::size_t n, const char* key) {
        if (w.size() != n)
            problem(std::string("'") + key + "' takes " + std::to_string(n) + " values, got " +
                    std::to_string(w.size()));
    };

    if (!std::getline(in, line) || line != "osgBTF-bsvtf " + std::to_string(kVersion)) {
        lineNumber = 1;
        problem("not an osgBTF BSVTF index of version " + std::to_string(kVersion) +
                " (first line must be 'osgBTF-bsvtf " + std::to_string(kVersion) + "')");
    }
    lineNumber = 1;
    int width = 0, height = 0, tileSize = 0, padding = -1, groups = 0;
    bool haveLayout = false, haveViews = false, haveLights = false, haveCodec = false, end = false;
    std::vector<char> tileSeen, packetSeen;
    const long long kMaxSide = 1 << 16;
    auto makeLayout = [&] {
        if (haveLayout) return;
        if (width == 0 || tileSize == 0 || padding < 0 || groups == 0)
            problem("'size', 'tile' and 'groups' must come before the first 'u' or 't' line");
        try {
            index.layout = TileLayout(width, height, groups, tileSize, padding);
        } catch (const Error& e) {
            problem(e.what());
        }
        if (index.layout.tileCount() > 50'000'000) problem("too many tiles");
        index.tiles.assign(index.layout.tileCount(), TileRecord{});
        index.uPackets.assign(std::size_t(groups), UPacketRecord{});
        tileSeen.assign(index.layout.tileCount(), 0);
        packetSeen.assign(std::size_t(groups), 0);
        haveLayout = true;
    };
    while (std::getline(in, line)) {
        ++lineNumber;
        if (end) problem("text after the 'end' line");
        const std::size_t space = line.find(' ');
        const std::string key = line.substr(0, space);
        const std::string rest = space == std::string::npos ? "" : line.substr(space + 1);
        const std::vector<std::string> w = words(rest);
        if (key == "end") {
            expectWords(w, 0, "end");
            end = true;
        } else if (key == "size") {
            expectWords(w, 2, "size");
            if (haveLayout) problem("'size' after the first tile");
            width = int(integer(w[0], 1, kMaxSide));
            height = int(integer(w[1], 1, kMaxSide));
        } else if (key == "tile") {
            expectWords(w, 2, "tile");
            if (haveLayout) problem("'tile' after the first tile");
            tileSize = int(integer(w[0], 8, 4096));
            padding = int(integer(w[1], 0, 4096));
        } else if (key == "groups") {
            expectWords(w, 1, "groups");
            if (haveLayout) problem("'groups' after the first tile");
            groups = int(integer(w[0], 1, 2048));
        } else if (key == "components") {
            expectWords(w, 1, "components");
            index.components = int(integer(w[0], 1, 8192));
        } else if (key == "codec") {
            if (w.empty()) problem("'codec' needs a name");
            if (w[0] == "raw") {
                expectWords(w, 1, "codec raw");
            } else if (w[0] == "dct") {
                expectWords(w, 3, "codec dct");
                index.codecSettings.quality = int(integer(w[1], 1, 100));
                index.codecSettings.unit = number(w[2]);
                if (!(index.codecSettings.unit > 0.0f)) problem("the codec unit must be > 0");
            } else {
                problem("unknown codec '" + w[0] + "' (known: dct, raw)");
            }
            index.codec = w[0];
            haveCodec = true;
        } else if (key == "param") {
            const std::size_t gap = rest.find(' ');
            if (rest.empty() || gap == 0) problem("'param' needs a key");
            index.parameters[rest.substr(0, gap)] =
                gap == std::string::npos ? "" : rest.substr(gap + 1);
        } else if (key == "views" || key == "lights") {
            DirectionSet set;
            try {
                set = DirectionSet::deserialize(rest);
            } catch (const Error& e) {
                problem(e.what());
            }
            if (set.size() == 0 || set.size() > 4096)
                problem("'" + key + "' must list 1 to 4096 directions");
            (key == "views" ? index.views : index.lights) = set;
            (key == "views" ? haveViews : haveLights) = true;
        } else if (key == "u") {
            expectWords(w, 3, "u");
            makeLayout();
            const std::size_t g = std::size_t(integer(w[0], 0, groups - 1));
            if (packetSeen[g]) problem("U packet " + w[0] + " listed twice");
            packetSeen[g] = 1;
            index.uPackets[g] = {std::uint32_t(integer(w[1], 0, 0xffffffffLL)),
                                 std::uint32_t(integer(w[2], 0, 0xffffffffLL))};
        } else if (key == "t") {
            expectWords(w, 8, "t");
            makeLayout();
            const TileId t{int(integer(w[0], 0, groups - 1)), int(integer(w[1], 0, 64)),
                           int(integer(w[2], 0, kMaxSide)), int(integer(w[3], 0, kMaxSide))};
            if (!index.layout.contains(t)) problem("tile outside the layout");
            const std::size_t i = index.layout.index(t);
            if (tileSeen[i]) problem("tile listed twice");
            tileSeen[i] = 1;
            TileRecord& r = index.tiles[i];
            r.bytes = std::uint32_t(integer(w[4], 0, 0xffffffffLL));
            r.crc = std::uint32_t(integer(w[5], 0, 0xffffffffLL));
            r.weight = number(w[6]);
            r.norm = number(w[7]);
            if (r.weight < 0 || r.norm < 0) problem("tile weight and norm must be >= 0");
        } else {
            problem("unknown key '" + key + "'");
        }
    }
    ++lineNumber;
    if (!end) problem("no 'end' line: the index is truncated");
    makeLayout();
    if (!haveCodec || !haveViews || !haveLights || index.components == 0)
        problem("the index needs 'codec', 'views', 'lights' and 'components'");
    if ((index.components + 3) / 4 != groups)
        problem("components " + std::to_string(index.components) + " need " +
                std::to_string((index.components + 3) / 4) + " groups, not " +
                std::to_string(groups));
    for (std::size_t g = 0; g < packetSeen.size(); ++g)
        if (!packetSeen[g]) problem("U packet " + std::to_string(g) + " is missing");
    for (std::size_t i = 0; i < tileSeen.size(); ++i)
        if (!tileSeen[i]) {
            const TileId t = index.layout.tileAt(i);
            problem("tile " + tilePath(t) + " is missing");
        }
    const std::uint64_t packetBytes = index.uPacketValues() * 2;
    for (std::size_t g = 0; g < index.uPackets.size(); ++g)
        if (index.uPackets[g].bytes != packetBytes)
            problem("U packet " + std::to_string(g) + " must have " + std::to_string(packetBytes) +
                    " bytes, the index says " + std::to_string(index.uPackets[g].bytes));
    if (index.codec == "raw")
        for (std::size_t i = 0; i < index.tiles.size(); ++i)
            if (index.tiles[i].bytes != index.layout.tileBytes())
                problem("raw tile " + tilePath(index.layout.tileAt(i)) + " must have " +
                        std::to_string(index.layout.tileBytes()) + " bytes");
    return index;
}

void predictFromParent(const TileLayout& layout, const TileId& child, const Imath::half* parent,
                       Imath::half* out) {
    const int side = layout.paddedTileSize(), T = layout.tileSize(), P = layout.padding();
    const TileId up = TileLayout::parent(child);
    for (int py = 0; py < side; ++py) {
        // Level coordinates of the child's padded texel, then the parent level's, relative to
        // the parent tile's padded origin: always inside it (see TileLayout.h).
        const int y = child.y * T - P + py;
        const int qy = (y >> 1) - (up.y * T - P);
        for (int px = 0; px < side; ++px) {
            const int x = child.x * T - P + px;
            const int qx = (x >> 1) - (up.x * T - P);
            std::memcpy(out + (std::size_t(py) * side + px) * 4,
                        parent + (std::size_t(qy) * side + qx) * 4, 4 * sizeof(Imath::half));
        }
    }
}

std::vector<Imath::half> TileSetIndex::decodeTile(const TileId& tile,
                                                  const std::vector<std::uint8_t>& data,
                                                  const Imath::half* parent,
                                                  const std::string& source) const {
    const TileRecord& record = tiles.at(layout.index(tile));
    if (data.size() != record.bytes)
        fail(source, "tile has " + std::to_string(data.size()) + " bytes, the index says " +
                         std::to_string(record.bytes) + " (a truncated or wrong download?)");
    if (tileSetCrc(data) != record.crc)
        fail(source, "tile CRC-32 does not match the index (corrupted download?)");
    const int side = layout.paddedTileSize();
    const std::size_t values = std::size_t(side) * std::size_t(side) * 4;
    std::vector<Imath::half> out(values);
    if (codec == "raw") {
        for (std::size_t i = 0; i < values; ++i) out[i] = halfAt(data, i);
        return out;
    }
    std::vector<Imath::half> prediction;
    if (tile.level > 0) {
        if (!parent)
            fail(source,
                 "tile of level " + std::to_string(tile.level) + " decoded without its parent");
        prediction.resize(values);
        predictFromParent(layout, tile, parent, prediction.data());
    }
    osgBTF::decodeTile(data.data(), data.size(), prediction.empty() ? nullptr : prediction.data(),
                       side, codecSettings, out.data(), source);
    return out;
}

std::vector<float> TileSetIndex::decodeUPacket(int group, const std::vector<std::uint8_t>& data,
                                               const std::string& source) const {
    const UPacketRecord& record = uPackets.at(std::size_t(group));
    if (data.size() != record.bytes)
        fail(source, "U packet has " + std::to_string(data.size()) + " bytes, the index says " +
                         std::to_string(record.bytes) + " (a truncated or wrong download?)");
    if (tileSetCrc(data) != record.crc)
        fail(source, "U packet CRC-32 does not match the index (corrupted download?)");
    std::vector<float> out(data.size() / 2);
    for (std::size_t i = 0; i < out.size(); ++i) {
        const Imath::half h = halfAt(data, i);
        if (!h.isFinite()) fail(source, "U packet holds a non-finite value");
        out[i] = float(h);
    }
    return out;
}

osg::ref_ptr<FmfMaterial> TileSetIndex::material(std::vector<float> u, std::vector<float> sxv,
                                                 const std::string& source) const {
    FittedMaterial file;
    file.method = kFmfMethodName;
    file.parameters = parameters;
    file.views = views;
    file.lights = lights;
    file.source = source;
    const int groups = layout.groups();
    file.textures.push_back({"u", groups, int(lights.size() * 3), int(views.size()), 4,
                             MaterialTexture::Half, std::move(u)});
    file.textures.push_back(
        {"sxv", layout.width(), layout.height(), groups, 4, MaterialTexture::Half, std::move(sxv)});
    return FmfMaterial::fromFile(std::move(file));
}

std::uint32_t tileSetCrc(const std::vector<std::uint8_t>& data) {
    return std::uint32_t(crc32(crc32(0L, Z_NULL, 0), data.data(), uInt(data.size())));
}

std::vector<std::uint8_t> halfBytes(const Imath::half* values, std::size_t count) {
    std::vector<std::uint8_t> out(count * 2);
    for (std::size_t i = 0; i < count; ++i) {
        const std::uint16_t bits = values[i].bits();
        out[2 * i] = std::uint8_t(bits & 0xff);
        out[2 * i + 1] = std::uint8_t(bits >> 8);
    }
    return out;
}

std::vector<std::uint8_t> readFileBytes(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    if (!in) fail(path, "cannot open");
    std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
    if (in.bad()) fail(path, "cannot read");
    return data;
}

osg::ref_ptr<FmfMaterial> loadTileSetFinest(const std::string& folder) {
    const std::string indexPath = folder + "/" + TileSetIndex::kIndexName;
    const std::vector<std::uint8_t> indexBytes = readFileBytes(indexPath);
    const TileSetIndex index =
        TileSetIndex::parse(std::string(indexBytes.begin(), indexBytes.end()), indexPath);
    const TileLayout& layout = index.layout;
    const int groups = layout.groups(), nV = int(index.views.size());
    const std::size_t rows = index.lights.size() * 3;

    std::vector<float> u(std::size_t(groups) * rows * std::size_t(nV) * 4, 0.0f);
    for (int g = 0; g < groups; ++g) {
        const std::string path = folder + "/" + TileSetIndex::uPacketPath(g);
        const std::vector<float> packet = index.decodeUPacket(g, readFileBytes(path), path);
        for (std::size_t r = 0; r < rows * std::size_t(nV); ++r)
            for (int j = 0; j < 4; ++j)
                u[(r * std::size_t(groups) + std::size_t(g)) * 4 + std::size_t(j)] =
                    packet[r * 4 + std::size_t(j)];
    }

    const std::size_t W = std::size_t(layout.width()), H = std::size_t(layout.height());
    std::vector<float> sxv(W * H * std::size_t(groups) * 4, 0.0f);
    const int side = layout.paddedTileSize(), T = layout.tileSize(), P = layout.padding();
    for (int g = 0; g < groups; ++g) {
        std::map<std::pair<int, int>, std::vector<Imath::half>> previous, current;
        for (int level = 0; level <= layout.finestLevel(); ++level) {
            current.clear();
            for (int ty = 0; ty < layout.tilesY(level); ++ty)
                for (int tx = 0; tx < layout.tilesX(level); ++tx) {
                    const TileId t{g, level, tx, ty};
                    const std::string path = folder + "/" + TileSetIndex::tilePath(t);
                    const Imath::half* parent =
                        level > 0 ? previous.at({tx / 2, ty / 2}).data() : nullptr;
                    current[{tx, ty}] = index.decodeTile(t, readFileBytes(path), parent, path);
                }
            previous.swap(current);
        }
        for (const auto& [position, tile] : previous)
            for (int y = 0; y < T; ++y)
                for (int x = 0; x < T; ++x) {
                    const std::size_t X = std::size_t(position.first * T + x),
                                      Y = std::size_t(position.second * T + y);
                    if (X >= W || Y >= H) continue;
                    for (int c = 0; c < 4; ++c)
                        sxv[((std::size_t(g) * H + Y) * W + X) * 4 + std::size_t(c)] = float(
                            tile[(std::size_t(y + P) * std::size_t(side) + std::size_t(x + P)) * 4 +
                                 std::size_t(c)]);
                }
    }
    return index.material(std::move(u), std::move(sxv), indexPath);
}

}  // namespace osgBTF
