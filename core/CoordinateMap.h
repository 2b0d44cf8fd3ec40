// osgBTF: coordinate maps, the output of BTF synthesis (Boßerhoff and Nicoll 2003 section 5): for
// every texel of a large surface, the texel of the small measured sample whose appearance it shows.
// Rendering through a map costs dependent fetches (four, filtered) and stores nothing per view or
// light.
//
// File format (version 1): a single-part scanline OpenEXR file, ZIP-compressed, width x height =
// the output size, two FLOAT channels "R" (sample x, the column) and "G" (sample y, the row
// counted from the bottom, MeasuredBtf's convention) holding integers; int attributes
// "osgBTF.coordinateMap" (= 1, the version), "osgBTF.sampleWidth" and "osgBTF.sampleHeight". Rows
// are stored top row first like every EXR, so a viewer shows the map upright (R, G as a gradient
// image of the sample positions).
#pragma once

#include <cstdint>
#include <string>
#include <vector>

namespace osgBTF {

class MeasuredBtf;

/** Version written into "osgBTF.coordinateMap"; readCoordinateMap refuses any other. */
constexpr int kCoordinateMapVersion = 1;

struct CoordinateMap {
    int width = 0;  // output texels
    int height = 0;
    int sampleWidth = 0;  // texels of the sample the map points into
    int sampleHeight = 0;
    /** [y][x] with rows bottom-up (y = 0 is the bottom row, as in MeasuredBtf):
     *  (sampleX, sampleY) of output texel (x, y) at entries 2 * (y * width + x) and + 1. */
    std::vector<std::int32_t> coordinates;

    CoordinateMap() = default;
    /** A map whose every entry is (0, 0); checks the memory limit. */
    CoordinateMap(int width, int height, int sampleWidth, int sampleHeight);

    std::int32_t& sampleX(int x, int y) { return coordinates[2 * (std::size_t(y) * width + x)]; }
    std::int32_t& sampleY(int x, int y) {
        return coordinates[2 * (std::size_t(y) * width + x) + 1];
    }
    std::int32_t sampleX(int x, int y) const {
        return coordinates[2 * (std::size_t(y) * width + x)];
    }
    std::int32_t sampleY(int x, int y) const {
        return coordinates[2 * (std::size_t(y) * width + x) + 1];
    }
    /** Sample texel index (sampleY * sampleWidth + sampleX) of output texel (x, y). */
    std::size_t sampleTexel(int x, int y) const {
        return std::size_t(sampleY(x, y)) * std::size_t(sampleWidth) + std::size_t(sampleX(x, y));
    }
};

/** Throws Error "WHAT: problem" unless sizes are positive and every entry lies in the sample. */
void validateCoordinateMap(const CoordinateMap& map, const std::string& what);

/** Writes the map atomically (writeFileAtomically). Throws Error "PATH: problem". */
void writeCoordinateMap(const CoordinateMap& map, const std::string& path);

/** Reads and validates a map. Throws Error "PATH: problem" for a missing, corrupt or truncated
 *  file, a file that is not a coordinate map (no osgBTF.coordinateMap attribute), another
 *  version, missing R/G channels, non-integer, non-finite or out-of-sample entries, or a map over
 *  the memory limit. */
CoordinateMap readCoordinateMap(const std::string& path);

/** The BTF a map stands for: texel (x, y) of the result is texel map(x, y) of `sample`, for every
 *  view and light (the reference that rendering through the map must equal). Throws Error when
 *  the map's sample size differs from the sample's, or the result exceeds the memory limit. */
MeasuredBtf materialiseCoordinateMap(const MeasuredBtf& sample, const CoordinateMap& map);

}  // namespace osgBTF
