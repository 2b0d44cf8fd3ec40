// osgBTF: measured direction sets in the local (tangent) frame.
//
// Frame: +Z is the surface normal, +X the texture's s direction, +Y its t direction. Angles are in
// degrees: theta from +Z, phi from +X toward +Y. Directions point away from the surface.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>

namespace osgBTF {

struct Direction {
    float theta = 0.0f;  ///< degrees from +Z
    float phi = 0.0f;    ///< degrees from +X toward +Y, in [0, 360)

    glm::vec3 toVector() const;
    static Direction fromVector(const glm::vec3& v);
};

/** An ordered list of measured directions (the index is the one the data use). */
class DirectionSet {
public:
    DirectionSet() = default;
    DirectionSet(std::string name, std::vector<Direction> directions);

    /** The 81 Bonn directions (Sattler et al. 2003 Table 1 "H2"), in the UBO2003 index order. */
    static DirectionSet bonn81();
    /** The 151 UBO2014 "Dome 1" directions (formats.md section 3), zenith first, rings upward. */
    static DirectionSet ubo2014();
    /** Text file: optional '# comment' lines, then one "theta phi" pair (degrees) per line. */
    static DirectionSet readFile(const std::string& path);
    void writeFile(const std::string& path) const;

    /** Compact text form "name;theta,phi;theta,phi;..." used in file headers. */
    std::string serialize() const;
    static DirectionSet deserialize(const std::string& text);

    const std::string& name() const { return _name; }
    std::size_t size() const { return _directions.size(); }
    const Direction& operator[](std::size_t i) const { return _directions[i]; }
    const std::vector<Direction>& directions() const { return _directions; }
    glm::vec3 vector(std::size_t i) const { return _directions[i].toVector(); }

    /** Index of the direction within toleranceDegrees of (theta, phi), or -1. */
    int find(float theta, float phi, float toleranceDegrees = 0.01f) const;

    bool operator==(const DirectionSet& other) const;

private:
    std::string _name;
    std::vector<Direction> _directions;
};

}  // namespace osgBTF
