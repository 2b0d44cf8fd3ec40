// osgBTF: the elevated concentric map (Schneider 2004 section 6.1): Shirley & Chiu's concentric
// square-to-disc map followed by the area-preserving elevation of the disc onto the hemisphere,
// and its exact inverse. Square coordinates (s, t) in [0, 1]^2, directions in the local frame
// (+Z the normal).
//
//   concentric map:  a = 2s - 1, b = 2t - 1; in the region |a| >= |b|, a > 0:
//                    rho = a, phi = (pi/4) (b/a)  (the other three regions rotate it)
//   elevation:       x = rho sqrt(2 - rho^2) cos phi, y = rho sqrt(2 - rho^2) sin phi,
//                    z = 1 - rho^2
// The paper's text extraction shows region 1 only; the other regions are Shirley & Chiu's
// (A Low Distortion Map Between Disk and Square, 1997). Inverting the elevation needs no
// trigonometry: rho^2 = 1 - z and rho sqrt(2 - rho^2) = sqrt(1 - z^2), so the disc point is
// (x, y) / sqrt(1 + z). The GLSL copy is in lpca-revised.frag.
#pragma once

#include <glm/vec2.hpp>
#include <glm/vec3.hpp>

namespace osgBTF {

/** Square [0, 1]^2 -> unit disc (Cartesian). */
glm::dvec2 concentricSquareToDisc(const glm::dvec2& st);
/** Unit disc -> square [0, 1]^2; the exact inverse of concentricSquareToDisc. */
glm::dvec2 concentricDiscToSquare(const glm::dvec2& disc);

/** Omega(s, t): square [0, 1]^2 -> unit direction on the upper hemisphere. */
glm::dvec3 elevatedConcentricMap(const glm::dvec2& st);
/** Omega^-1: unit direction (z clamped to >= 0, then renormalised) -> square [0, 1]^2. */
glm::dvec2 elevatedConcentricInverse(const glm::dvec3& direction);

}  // namespace osgBTF
