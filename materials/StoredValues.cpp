#include "materials/StoredValues.h"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "core/Error.h"

namespace osgBTF {

namespace {

std::uint8_t toByte(float value) {
    // !(value > 0) also sends NaN to 0.
    const float clamped = !(value > 0.0f) ? 0.0f : value > 1.0f ? 1.0f : value;
    return std::uint8_t(std::lround(clamped * 255.0f));
}

Imath::half toHalf(float value) {
    return Imath::half(std::isnan(value) ? value : std::clamp(value, -65504.0f, 65504.0f));
}

}  // namespace

StoredValues::StoredValues(Kind kind, std::size_t count, float value) : _kind(kind) {
    switch (kind) {
        case MaterialTexture::UNorm8:
            _bytes.assign(count, toByte(value));
            break;
        case MaterialTexture::Half:
            _halves.assign(count, toHalf(value));
            break;
        case MaterialTexture::Float:
            _floats.assign(count, value);
            break;
    }
}

float StoredValues::round(Kind kind, float value) {
    switch (kind) {
        case MaterialTexture::UNorm8:
            return float(toByte(value)) / 255.0f;
        case MaterialTexture::Half:
            return float(toHalf(value));
        case MaterialTexture::Float:
            break;
    }
    return value;
}

std::size_t StoredValues::size() const {
    switch (_kind) {
        case MaterialTexture::UNorm8:
            return _bytes.size();
        case MaterialTexture::Half:
            return _halves.size();
        case MaterialTexture::Float:
            break;
    }
    return _floats.size();
}

std::size_t StoredValues::bytes() const {
    switch (_kind) {
        case MaterialTexture::UNorm8:
            return _bytes.size();
        case MaterialTexture::Half:
            return _halves.size() * sizeof(Imath::half);
        case MaterialTexture::Float:
            break;
    }
    return _floats.size() * sizeof(float);
}

void StoredValues::set(std::size_t i, float value) {
    switch (_kind) {
        case MaterialTexture::UNorm8:
            _bytes[i] = toByte(value);
            return;
        case MaterialTexture::Half:
            _halves[i] = toHalf(value);
            return;
        case MaterialTexture::Float:
            _floats[i] = value;
            return;
    }
}

void StoredValues::read(std::size_t first, std::size_t count, float* out) const {
    for (std::size_t i = 0; i < count; ++i) out[i] = (*this)[first + i];
}

std::vector<float> StoredValues::floats() const {
    std::vector<float> out(size());
    read(0, out.size(), out.data());
    return out;
}

void StoredValues::write(std::size_t first, const float* values, std::size_t count) {
    for (std::size_t i = 0; i < count; ++i) set(first + i, values[i]);
}

bool StoredValues::allFinite() const {
    switch (_kind) {
        case MaterialTexture::UNorm8:
            return true;
        case MaterialTexture::Half:
            return std::all_of(_halves.begin(), _halves.end(),
                               [](Imath::half h) { return h.isFinite(); });
        case MaterialTexture::Float:
            break;
    }
    return std::all_of(_floats.begin(), _floats.end(), [](float v) { return std::isfinite(v); });
}

MaterialTexture StoredValues::texture(const std::string& name, int width, int height, int depth,
                                      int channels) const {
    MaterialTexture t{name, width, height, depth, channels, _kind, {}};
    if (t.valueCount() != size())
        throw Error("texture '" + name + "': " + std::to_string(size()) +
                    " values do not fill its dimensions");
    switch (_kind) {
        case MaterialTexture::UNorm8:
            t.bytes = _bytes;
            break;
        case MaterialTexture::Half:
            t.halves = _halves;
            break;
        case MaterialTexture::Float:
            t.data = _floats;
            break;
    }
    return t;
}

StoredValues StoredValues::take(MaterialTexture& texture, Kind kind) {
    StoredValues values;
    values._kind = kind;
    const bool asStored = texture.kind == kind;
    if (asStored && kind == MaterialTexture::UNorm8 && !texture.bytes.empty()) {
        values._bytes = std::move(texture.bytes);
    } else if (asStored && kind == MaterialTexture::Half && !texture.halves.empty()) {
        values._halves = std::move(texture.halves);
    } else if (asStored && kind == MaterialTexture::Float && texture.bytes.empty() &&
               texture.halves.empty()) {
        values._floats = std::move(texture.data);
    } else {
        values = StoredValues(kind, texture.storedCount());
        for (std::size_t i = 0; i < texture.storedCount(); ++i) values.set(i, texture.value(i));
    }
    texture.data = {};
    texture.bytes = {};
    texture.halves = {};
    return values;
}

bool StoredValues::operator==(const StoredValues& other) const {
    if (empty() && other.empty()) return true;  // no values: nothing stored to differ
    if (_kind != other._kind || size() != other.size()) return false;
    switch (_kind) {
        case MaterialTexture::UNorm8:
            return _bytes == other._bytes;
        case MaterialTexture::Half:
            return std::memcmp(_halves.data(), other._halves.data(),
                               _halves.size() * sizeof(Imath::half)) == 0;
        case MaterialTexture::Float:
            break;
    }
    return _floats == other._floats;
}

}  // namespace osgBTF
