// osgBTF: the RF model's stored precisions and its lobe, in float as the shader computes them,
// shared by the model (Rf.cpp) and its fitter (RfFit.cpp, libosgBTFFit), which rounds to exactly
// what the file and the GPU hold.
#pragma once

#include <algorithm>
#include <cmath>

#include <Imath/half.h>
#include <glm/vec3.hpp>

namespace osgBTF::rf {

/** Exactly what the file stores and loadFittedMaterial returns for UNorm8 (k / 255.0f). */
inline float toUNorm8(float v) {
    return std::round(std::clamp(v, 0.0f, 1.0f) * 255.0f) / 255.0f;
}

inline float toHalf(float v) {
    return float(Imath::half(std::clamp(v, -65504.0f, 65504.0f)));
}

/** One lobe, in float and in the order the shader computes it (rf.frag). */
inline float lobeValue(const float* p, const glm::vec3& l) {
    const float base = p[0] * l.x + p[1] * l.y + p[2] * l.z;
    return base > 0.0f ? std::pow(base, p[3]) : 0.0f;
}

}  // namespace osgBTF::rf
