// osgBTF: the RF model's lobe, in float as the shader computes it, shared by the model (Rf.cpp)
// and its fitter (RfFit.cpp, libosgBTFFit). The stored precisions are StoredValues::round's.
#pragma once

#include <algorithm>
#include <cmath>

#include <glm/vec3.hpp>

namespace osgBTF::rf {

/** One lobe, in float and in the order the shader computes it (rf.frag). */
inline float lobeValue(const float* p, const glm::vec3& l) {
    const float base = p[0] * l.x + p[1] * l.y + p[2] * l.z;
    return base > 0.0f ? std::pow(base, p[3]) : 0.0f;
}

}  // namespace osgBTF::rf
