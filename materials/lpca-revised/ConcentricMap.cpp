#include "materials/lpca-revised/ConcentricMap.h"

#include <algorithm>
#include <cmath>

#include <glm/geometric.hpp>

namespace osgBTF {

namespace {
constexpr double kQuarterPi = 0.78539816339744830962;
}

glm::dvec2 concentricSquareToDisc(const glm::dvec2& st) {
    const double a = 2.0 * st.x - 1.0, b = 2.0 * st.y - 1.0;
    double rho, phi;
    if (a > -b) {
        if (a > b) {
            rho = a;
            phi = kQuarterPi * (b / a);
        } else {
            rho = b;
            phi = kQuarterPi * (2.0 - a / b);
        }
    } else {
        if (a < b) {
            rho = -a;
            phi = kQuarterPi * (4.0 + b / a);
        } else {
            rho = -b;
            phi = b != 0.0 ? kQuarterPi * (6.0 - a / b) : 0.0;  // a = b = 0: the centre
        }
    }
    return {rho * std::cos(phi), rho * std::sin(phi)};
}

glm::dvec2 concentricDiscToSquare(const glm::dvec2& disc) {
    const double rho = std::sqrt(disc.x * disc.x + disc.y * disc.y);
    double phi = std::atan2(disc.y, disc.x);
    if (phi < -kQuarterPi) phi += 8.0 * kQuarterPi;  // [-pi/4, 7pi/4): the forward map's range
    const double f = phi / kQuarterPi;
    double a, b;
    if (f < 1.0) {
        a = rho;
        b = a * f;
    } else if (f < 3.0) {
        b = rho;
        a = b * (2.0 - f);
    } else if (f < 5.0) {
        a = -rho;
        b = a * (f - 4.0);
    } else {
        b = -rho;
        a = b * (6.0 - f);
    }
    return {(a + 1.0) * 0.5, (b + 1.0) * 0.5};
}

glm::dvec3 elevatedConcentricMap(const glm::dvec2& st) {
    const glm::dvec2 disc = concentricSquareToDisc(st);
    const double rho2 = std::min(disc.x * disc.x + disc.y * disc.y, 1.0);
    const double scale = std::sqrt(2.0 - rho2);
    return {disc.x * scale, disc.y * scale, 1.0 - rho2};
}

glm::dvec2 elevatedConcentricInverse(const glm::dvec3& direction) {
    glm::dvec3 d = direction;
    d.z = std::max(d.z, 0.0);
    d = glm::normalize(d);
    return concentricDiscToSquare(glm::dvec2(d.x, d.y) / std::sqrt(1.0 + d.z));
}

}  // namespace osgBTF
