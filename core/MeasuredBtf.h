// osgBTF: a measured BTF in memory: texels x views x lights x RGB.
#pragma once

#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include <Imath/half.h>

#include "core/BtfSource.h"
#include "core/Directions.h"

namespace osgBTF {

enum class Storage { Float, Half };

/** Upper bound for any single allocation of measured data, checked before allocating. The default
 *  is 3/4 of physical memory; the OSGBTF_MEMORY_LIMIT environment variable (bytes, or with a
 *  K/M/G suffix) and the tools' --memory-limit option override it. */
std::uint64_t memoryLimit();
void setMemoryLimit(std::uint64_t bytes);
/** Throws Error("<what>: needs N bytes, more than the memory limit of M bytes ...") if
 *  bytes > memoryLimit(). */
void checkMemory(std::uint64_t bytes, const std::string& what);
std::string formatBytes(std::uint64_t bytes);
/** Parses "123", "4K", "16G", "1.5GiB" as bytes; throws Error on anything else. */
std::uint64_t parseBytes(const std::string& text);

/** Texel x = column (along +X), y = row counted from the bottom (+Y up, OSG's origin).
 *  Memory layout: image-major, [view][light][y][x][rgb]; one (view, light) image is contiguous so
 *  loaders fill it in one piece and per-view methods read it directly. */
class MeasuredBtf : public BtfSource {
public:
    MeasuredBtf() = default;
    /** Allocates zero-filled storage after checking memoryLimit(). */
    MeasuredBtf(int width, int height, DirectionSet views, DirectionSet lights,
                Storage storage = Storage::Float);

    static std::uint64_t bytesNeeded(int width, int height, std::size_t views, std::size_t lights,
                                     Storage storage);

    Storage storage() const { return _storage; }
    std::uint64_t memoryBytes() const;

    void readImages(std::size_t first, std::size_t count, float* out) const override;
    void readAbrdfs(const std::size_t* texels, std::size_t count, float* out) const override;
    std::size_t abrdfBlockTexels() const override { return 16; }
    std::size_t imageBlock() const override { return 1; }
    bool inMemory() const override { return true; }
    std::uint64_t residentBytes() const override { return memoryBytes(); }

    /** Index of one RGB triple in the flat storage. */
    std::size_t index(std::size_t view, std::size_t light, std::size_t texel) const {
        return ((view * _lights.size() + light) * texelCount() + texel) * 3;
    }

    float value(std::size_t view, std::size_t light, std::size_t texel, int channel) const {
        const std::size_t i = index(view, light, texel) + channel;
        return _storage == Storage::Float ? _float[i] : float(_half[i]);
    }
    void setValue(std::size_t view, std::size_t light, std::size_t texel, int channel, float v) {
        const std::size_t i = index(view, light, texel) + channel;
        if (_storage == Storage::Float)
            _float[i] = v;
        else
            _half[i] = Imath::half(v);
    }

    /** One (view, light) image, width*height*3 floats, rows bottom-up. */
    std::vector<float> image(std::size_t view, std::size_t light) const;
    void setImage(std::size_t view, std::size_t light, const float* rgb);

    /** One texel's apparent BRDF: views*lights*3 floats, [view][light][rgb]. */
    std::vector<float> abrdf(std::size_t texel) const;
    void abrdf(std::size_t texel, float* out) const;

    /** Direct access for the storage kind in use (nullptr for the other one). */
    float* floatData() { return _float.empty() ? nullptr : _float.data(); }
    const float* floatData() const { return _float.empty() ? nullptr : _float.data(); }
    Imath::half* halfData() { return _half.empty() ? nullptr : _half.data(); }
    const Imath::half* halfData() const { return _half.empty() ? nullptr : _half.data(); }

private:
    Storage _storage = Storage::Float;
    /** Leaves elements uninitialised on resize: the constructor zero-fills in parallel instead
     *  (first touch of gigabytes on one thread took half of a 6561-image load). */
    template <typename T>
    struct UninitialisedAllocator : std::allocator<T> {
        template <typename U>
        struct rebind {
            using other = UninitialisedAllocator<U>;
        };
        UninitialisedAllocator() = default;
        template <typename U>
        UninitialisedAllocator(const UninitialisedAllocator<U>&) {}
        template <typename U>
        void construct(U*) noexcept {}
        template <typename U, typename... Args>
        void construct(U* p, Args&&... args) {
            ::new (static_cast<void*>(p)) U(std::forward<Args>(args)...);
        }
    };
    std::vector<float, UninitialisedAllocator<float>> _float;
    std::vector<Imath::half, UninitialisedAllocator<Imath::half>> _half;
};

}  // namespace osgBTF
