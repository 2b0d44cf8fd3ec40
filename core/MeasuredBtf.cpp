#include "core/MeasuredBtf.h"

#include <unistd.h>
#include <atomic>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <sstream>

#include <tbb/blocked_range.h>
#include <tbb/parallel_for.h>

#include "core/Error.h"

namespace osgBTF {

namespace {

std::uint64_t defaultMemoryLimit() {
    if (const char* env = std::getenv("OSGBTF_MEMORY_LIMIT")) {
        try {
            return parseBytes(env);
        } catch (const Error& e) {
            throw Error(std::string("OSGBTF_MEMORY_LIMIT: ") + e.what());
        }
    }
    const long pages = sysconf(_SC_PHYS_PAGES), pageSize = sysconf(_SC_PAGE_SIZE);
    if (pages <= 0 || pageSize <= 0) return std::uint64_t(8) << 30;
    return std::uint64_t(pages) * std::uint64_t(pageSize) / 4 * 3;
}

std::atomic<std::uint64_t> g_memoryLimit{0};

}  // namespace

std::uint64_t memoryLimit() {
    if (g_memoryLimit == 0) g_memoryLimit = defaultMemoryLimit();
    return g_memoryLimit;
}

void setMemoryLimit(std::uint64_t bytes) {
    g_memoryLimit = bytes;
}

std::string formatBytes(std::uint64_t bytes) {
    const char* units[] = {"B", "KiB", "MiB", "GiB", "TiB", "PiB", "EiB"};
    double value = double(bytes);
    int unit = 0;
    while (value >= 1024.0 && unit < 6) {
        value /= 1024.0;
        ++unit;
    }
    std::ostringstream out;
    out.precision(unit == 0 ? 0 : 1);
    out << std::fixed << value << ' ' << units[unit];
    return out.str();
}

std::uint64_t parseBytes(const std::string& text) {
    char* end = nullptr;
    const double value = std::strtod(text.c_str(), &end);
    std::string suffix(end ? end : "");
    while (!suffix.empty() && suffix.front() == ' ') suffix.erase(0, 1);
    double scale = 1.0;
    if (suffix.empty() || suffix == "B") {
    } else if (suffix == "K" || suffix == "KB" || suffix == "KiB") {
        scale = 1024.0;
    } else if (suffix == "M" || suffix == "MB" || suffix == "MiB") {
        scale = 1024.0 * 1024.0;
    } else if (suffix == "G" || suffix == "GB" || suffix == "GiB") {
        scale = 1024.0 * 1024.0 * 1024.0;
    } else if (suffix == "T" || suffix == "TB" || suffix == "TiB") {
        scale = 1024.0 * 1024.0 * 1024.0 * 1024.0;
    } else {
        throw Error("'" + text + "' is not a byte count (use e.g. 512M or 16G)");
    }
    if (end == text.c_str() || !std::isfinite(value) || value <= 0)
        throw Error("'" + text + "' is not a positive byte count (use e.g. 512M or 16G)");
    return std::uint64_t(value * scale);
}

void checkMemory(std::uint64_t bytes, const std::string& what) {
    if (bytes > memoryLimit())
        throw Error(what + ": needs " + formatBytes(bytes) + ", more than the memory limit of " +
                    formatBytes(memoryLimit()) +
                    " (raise it with --memory-limit or OSGBTF_MEMORY_LIMIT)");
}

std::uint64_t MeasuredBtf::bytesNeeded(int width, int height, std::size_t views, std::size_t lights,
                                       Storage storage) {
    // Computed in long double so absurd header values cannot wrap around before the check.
    const long double bytes =
        (long double)width * height * views * lights * 3 * (storage == Storage::Float ? 4 : 2);
    return bytes > 1.8e19L ? UINT64_MAX : std::uint64_t(bytes);
}

MeasuredBtf::MeasuredBtf(int width, int height, DirectionSet views, DirectionSet lights,
                         Storage storage)
    : BtfSource(width, height, std::move(views), std::move(lights)), _storage(storage) {
    if (width <= 0 || height <= 0 || _views.size() == 0 || _lights.size() == 0) {
        std::ostringstream what;
        what << "invalid BTF dimensions " << width << "x" << height << " texels, " << _views.size()
             << " views, " << _lights.size() << " lights";
        throw Error(what.str());
    }
    std::ostringstream what;
    what << "BTF of " << width << "x" << height << " texels x " << _views.size() << " views x "
         << _lights.size() << " lights";
    checkMemory(bytesNeeded(width, height, _views.size(), _lights.size(), storage), what.str());
    const std::size_t count = texelCount() * _views.size() * _lights.size() * 3;
    if (storage == Storage::Float)
        _float.resize(count);
    else
        _half.resize(count);
    // Parallel first touch: zero-filling gigabytes on one thread dominated load times.
    tbb::parallel_for(tbb::blocked_range<std::size_t>(0, count, 1 << 20), [&](const auto& r) {
        if (storage == Storage::Float)
            std::fill(_float.begin() + r.begin(), _float.begin() + r.end(), 0.0f);
        else
            std::fill(_half.begin() + r.begin(), _half.begin() + r.end(), Imath::half(0.0f));
    });
}

std::uint64_t MeasuredBtf::memoryBytes() const {
    return _float.size() * sizeof(float) + _half.size() * sizeof(Imath::half);
}

std::vector<float> MeasuredBtf::image(std::size_t view, std::size_t light) const {
    std::vector<float> out(texelCount() * 3);
    const std::size_t base = index(view, light, 0);
    if (_storage == Storage::Float)
        std::memcpy(out.data(), _float.data() + base, out.size() * sizeof(float));
    else
        for (std::size_t i = 0; i < out.size(); ++i) out[i] = float(_half[base + i]);
    return out;
}

void MeasuredBtf::setImage(std::size_t view, std::size_t light, const float* rgb) {
    const std::size_t base = index(view, light, 0), count = texelCount() * 3;
    if (_storage == Storage::Float)
        std::memcpy(_float.data() + base, rgb, count * sizeof(float));
    else
        for (std::size_t i = 0; i < count; ++i) _half[base + i] = Imath::half(rgb[i]);
}

std::vector<float> MeasuredBtf::abrdf(std::size_t texel) const {
    std::vector<float> out(_views.size() * _lights.size() * 3);
    abrdf(texel, out.data());
    return out;
}

void MeasuredBtf::abrdf(std::size_t texel, float* out) const {
    const std::size_t pairs = _views.size() * _lights.size(), stride = texelCount() * 3;
    std::size_t i = texel * 3;
    for (std::size_t pair = 0; pair < pairs; ++pair, i += stride) {
        for (int c = 0; c < 3; ++c)
            *out++ = _storage == Storage::Float ? _float[i + c] : float(_half[i + c]);
    }
}

void MeasuredBtf::readImages(std::size_t first, std::size_t count, float* out) const {
    const std::size_t values = texelCount() * 3;
    for (std::size_t j = 0; j < count; ++j) {
        const std::size_t base = (first + j) * values;
        float* dst = out + j * values;
        if (_storage == Storage::Float)
            std::memcpy(dst, _float.data() + base, values * sizeof(float));
        else
            for (std::size_t i = 0; i < values; ++i) dst[i] = float(_half[base + i]);
    }
}

void MeasuredBtf::readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const {
    // Image-outer: the storage is image-major, so each image's rows are touched once per block.
    const std::size_t pairs = imageCount(), stride = texelCount() * 3, abrdfValues = pairs * 3;
    for (std::size_t pair = 0; pair < pairs; ++pair) {
        const std::size_t base = pair * stride;
        for (std::size_t j = 0; j < count; ++j) {
            const std::size_t i = base + texels[j] * 3;
            float* dst = out + j * abrdfValues + pair * 3;
            if (_storage == Storage::Float)
                dst[0] = _float[i], dst[1] = _float[i + 1], dst[2] = _float[i + 2];
            else
                dst[0] = float(_half[i]), dst[1] = float(_half[i + 1]),
                dst[2] = float(_half[i + 2]);
        }
    }
}

}  // namespace osgBTF
