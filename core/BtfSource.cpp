#include "core/BtfSource.h"

#include <algorithm>
#include <numeric>
#include <random>

#include "core/Error.h"
#include "core/MeasuredBtf.h"

namespace osgBTF {

void BtfSource::readAbrdfRange(std::size_t first, std::size_t count, float* out) const {
    std::vector<std::size_t> texels(count);
    std::iota(texels.begin(), texels.end(), first);
    readAbrdfs(texels.data(), count, out);
}

std::vector<std::size_t> randomTexels(const BtfSource& source, std::size_t count, unsigned seed) {
    const std::size_t texels = source.texelCount();
    std::vector<std::size_t> all(texels);
    std::iota(all.begin(), all.end(), std::size_t(0));
    if (count >= texels) return all;
    // A partial Fisher-Yates shuffle with a fixed generator: the same subsample on every run
    // and every platform (std::uniform_int_distribution is not portable across libraries).
    std::mt19937_64 random(seed);
    for (std::size_t i = 0; i < count; ++i) std::swap(all[i], all[i + random() % (texels - i)]);
    all.resize(count);
    std::sort(all.begin(), all.end());
    return all;
}

void checkMemoryBeside(const BtfSource& held, std::uint64_t bytes, const std::string& what) {
    checkMemory(bytes, what);
    const std::uint64_t resident = held.residentBytes(), limit = memoryLimit();
    if (resident > limit || bytes > limit - resident)
        throw Error(what + ": needs " + formatBytes(bytes) + " beside the " +
                    formatBytes(resident) + " of measured values held in memory, more than the " +
                    "memory limit of " + formatBytes(limit) +
                    " together (raise it with --memory-limit or OSGBTF_MEMORY_LIMIT, or keep an "
                    "RTI capture on disk with --storage disk)");
}

std::size_t errorTexelCount(const BtfSource& source, long long requested) {
    const std::size_t texels = source.texelCount();
    if (requested < 0) requested = source.inMemory() ? 0 : 4096;
    return requested == 0 ? texels : std::min(texels, std::size_t(requested));
}

}  // namespace osgBTF
