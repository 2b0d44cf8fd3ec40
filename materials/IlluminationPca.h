// osgBTF: illumination PCA for rotating environments (Sattler et al. 2003 section 5.3).
//
// Per-vertex environment data (the projected g or the folded gamma* of every vertex, one long
// vector U) depend on the environment's rotation about the up axis. They are precomputed for A
// rotations (default 30, 12 degrees apart), and the A vectors are compressed by PCA to a mean and
// e components (default 5): U_a ~ mean + sum_k c_ak B_k. Any rotation is rebuilt at run time from
// the coefficients interpolated linearly (periodically) between the two neighbouring samples, a
// cost of e multiply-adds per value (well under a frame for ~10^7 values).
//
// The PCA is computed from the A x A Gram matrix of the centred samples (A is small, the vectors
// are long), so memory is that of the samples themselves.
#pragma once

#include <functional>
#include <vector>

namespace osgBTF {

class IlluminationPca {
public:
    /** Calls `compute(degrees)` for rotations 0, 360/A, ... and keeps `components` principal
     *  components (clamped to A). Every call must return vectors of one length. Throws Error for
     *  rotations < 2, components < 1 or vectors of different lengths. `progress(done, A)` is
     *  called after each rotation when given. */
    static IlluminationPca build(const std::function<std::vector<float>(float)>& compute,
                                 int rotations = 30, int components = 5,
                                 const std::function<void(int, int)>& progress = {});

    /** The data at any rotation (degrees, any value: periodic). */
    std::vector<float> reconstruct(float degrees) const;
    /** The same into `out` (length() floats), e.g. a texture's image, without allocating. */
    void reconstructInto(float degrees, float* out) const;
    /** Sample a's coefficients applied to the basis (no interpolation). */
    std::vector<float> reconstructSample(int a) const;

    int rotations() const { return _rotations; }
    int components() const { return _components; }
    std::size_t length() const { return _mean.size(); }

private:
    int _rotations = 0, _components = 0;
    std::vector<float> _mean;
    std::vector<std::vector<float>> _basis;          ///< components x length
    std::vector<std::vector<double>> _coefficients;  ///< rotations x components
};

}  // namespace osgBTF
