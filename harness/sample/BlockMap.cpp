#include "harness/sample/BlockMap.h"

#include <algorithm>
#include <random>

#include "core/Error.h"

namespace osgBTF {

CoordinateMap makeBlockCoordinateMap(int width, int height, int sampleWidth, int sampleHeight,
                                     int block, std::uint32_t seed) {
    if (block < 1) throw Error("block map: the block size must be at least 1");
    if (sampleWidth < 1 || sampleHeight < 1) throw Error("block map: invalid sample size");
    CoordinateMap map(width, height, sampleWidth, sampleHeight);
    std::mt19937 random(seed);
    // Raw engine output, not std::uniform_int_distribution: its algorithm is the library's, so
    // the map would differ between standard libraries.
    const auto below = [&](int n) { return int(random() % std::uint32_t(n)); };
    for (int by = 0; by < height; by += block)
        for (int bx = 0; bx < width; bx += block) {
            const int ox = below(sampleWidth), oy = below(sampleHeight);
            for (int y = by; y < std::min(by + block, height); ++y)
                for (int x = bx; x < std::min(bx + block, width); ++x) {
                    map.sampleX(x, y) = (ox + x - bx) % sampleWidth;
                    map.sampleY(x, y) = (oy + y - by) % sampleHeight;
                }
        }
    validateCoordinateMap(map, "block map");
    return map;
}

}  // namespace osgBTF
