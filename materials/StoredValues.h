// osgBTF: one of a model's arrays held at the precision its file and the GPU store it.
//
// A method's CPU evaluator and fitter think in floats, but its file stores most arrays as half
// floats or 8-bit fixed point. Holding those as floats doubles (or quadruples) what a loaded
// material takes in host memory; holding them as they are stored keeps a material's memory at its
// file's size, and makes "the CPU evaluates exactly what the GPU gets" a property of the type:
// every write rounds as the file does.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

#include <Imath/half.h>

#include "core/FittedMaterialFile.h"

namespace osgBTF {

class StoredValues {
public:
    using Kind = MaterialTexture::PixelKind;

    /** No values, float storage. */
    StoredValues() = default;
    /** `count` copies of `value` (rounded to `kind`). */
    StoredValues(Kind kind, std::size_t count, float value = 0.0f);

    /** Rounds as a value of `kind` is stored: UNorm8 to k / 255 (k = 0..255, clamped to [0, 1]),
     *  Half to the nearest half (clamped to its finite range), Float unchanged. NaN stays NaN for
     *  Half and Float (UNorm8 has no NaN: 0). */
    static float round(Kind kind, float value);

    Kind kind() const { return _kind; }
    std::size_t size() const;
    bool empty() const { return size() == 0; }
    /** Bytes the values take (what the file and the GPU hold). */
    std::size_t bytes() const;

    float operator[](std::size_t i) const {
        switch (_kind) {
            case MaterialTexture::UNorm8:
                return float(_bytes[i]) / 255.0f;
            case MaterialTexture::Half:
                return float(_halves[i]);
            case MaterialTexture::Float:
                break;
        }
        return _floats[i];
    }
    /** Stores round(kind(), value) at i. */
    void set(std::size_t i, float value);
    /** Values [first, first + count) into `out`. */
    void read(std::size_t first, std::size_t count, float* out) const;
    /** Every value, as floats (a copy). */
    std::vector<float> floats() const;
    /** set() of `count` values from `values` at [first, first + count). */
    void write(std::size_t first, const float* values, std::size_t count);
    /** True when no value is infinite or NaN (UNorm8 values always are finite). */
    bool allFinite() const;

    /** A file texture of these values (a copy, in the same representation). Throws Error if the
     *  shape does not hold size() values. */
    MaterialTexture texture(const std::string& name, int width, int height, int depth,
                            int channels) const;
    /** Takes the values of a file's texture as values of `kind`: without a copy when the texture
     *  holds them as `kind` stores them (`bytes` of a UNorm8 texture, `halves` of a Half one,
     *  `data` of a Float one), otherwise converted value by value (rounded to `kind`). The
     *  texture is left without values. */
    static StoredValues take(MaterialTexture& texture, Kind kind);

    /** Same kind and the same stored values (bitwise for halves: NaN == NaN); any two empty
     *  arrays are equal. */
    bool operator==(const StoredValues& other) const;
    bool operator!=(const StoredValues& other) const { return !(*this == other); }

private:
    Kind _kind = MaterialTexture::Float;
    // Exactly one of them holds the values, the one of _kind.
    std::vector<std::uint8_t> _bytes;
    std::vector<Imath::half> _halves;
    std::vector<float> _floats;
};

}  // namespace osgBTF
