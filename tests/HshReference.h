// The hemispherical harmonics of the RTI tools, written as they write them (the trigonometric
// form: theta and phi from acos and atan2, multiple angles and powers taken directly), as the
// tests' independent reference for materials/hsh, which evaluates them without trigonometry.
#pragma once

#include <array>
#include <cmath>

#include <glm/vec3.hpp>

namespace osgBTF::test {

inline constexpr double kHshPi = 3.14159265358979323846;

/** The 16 harmonics as the RTI viewers write them: theta = acos(z), phi = atan2(y, x), cosines
 *  and sines of multiple angles and powers taken directly (no identities). */
inline std::array<double, 16> hshTrigonometricForm(const glm::vec3& l) {
    const double phi = std::atan2(double(l.y), double(l.x)), ct = double(l.z);
    const double ct2 = ct * ct, r = std::sqrt(ct - ct2);
    return {1 / std::sqrt(2 * kHshPi),
            std::sqrt(6 / kHshPi) * std::cos(phi) * r,
            std::sqrt(3 / (2 * kHshPi)) * (-1 + 2 * ct),
            std::sqrt(6 / kHshPi) * r * std::sin(phi),
            std::sqrt(30 / kHshPi) * std::cos(2 * phi) * (-ct + ct2),
            std::sqrt(30 / kHshPi) * std::cos(phi) * (-1 + 2 * ct) * r,
            std::sqrt(5 / (2 * kHshPi)) * (1 - 6 * ct + 6 * ct2),
            std::sqrt(30 / kHshPi) * (-1 + 2 * ct) * r * std::sin(phi),
            std::sqrt(30 / kHshPi) * (-ct + ct2) * std::sin(2 * phi),
            2 * std::sqrt(35 / kHshPi) * std::cos(3 * phi) * std::pow(ct - ct2, 1.5),
            std::sqrt(210 / kHshPi) * std::cos(2 * phi) * (-1 + 2 * ct) * (-ct + ct2),
            2 * std::sqrt(21 / kHshPi) * std::cos(phi) * r * (1 - 5 * ct + 5 * ct2),
            std::sqrt(7 / (2 * kHshPi)) * (-1 + 12 * ct - 30 * ct2 + 20 * ct2 * ct),
            2 * std::sqrt(21 / kHshPi) * r * (1 - 5 * ct + 5 * ct2) * std::sin(phi),
            std::sqrt(210 / kHshPi) * (-1 + 2 * ct) * (-ct + ct2) * std::sin(2 * phi),
            2 * std::sqrt(35 / kHshPi) * std::pow(ct - ct2, 1.5) * std::sin(3 * phi)};
}

}  // namespace osgBTF::test
