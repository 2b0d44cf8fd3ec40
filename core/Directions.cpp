#include "core/Directions.h"

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <glm/geometric.hpp>
#include <glm/trigonometric.hpp>

#include "core/Error.h"
#include "core/FloatImage.h"

namespace osgBTF {

namespace {

float wrapDegrees(float phi) {
    float wrapped = std::fmod(phi, 360.0f);
    if (wrapped < 0.0f) wrapped += 360.0f;
    if (wrapped >= 360.0f) wrapped -= 360.0f;
    return wrapped;
}

float angleBetweenDegrees(const Direction& a, const Direction& b) {
    // In double: acos near 1 amplifies float rounding to ~0.02 degrees.
    const glm::dvec3 u(a.toVector()), v(b.toVector());
    return glm::degrees(2.0 * std::asin(std::min(1.0, glm::length(u - v) / 2.0)));
}

struct Ring {
    float theta;
    int count;
    float firstPhi;
};

DirectionSet fromRings(const std::string& name, std::initializer_list<Ring> rings) {
    std::vector<Direction> directions;
    for (const Ring& ring : rings)
        for (int i = 0; i < ring.count; ++i)
            directions.push_back(
                {ring.theta, wrapDegrees(ring.firstPhi + 360.0f * i / ring.count)});
    return DirectionSet(name, std::move(directions));
}

}  // namespace

glm::vec3 Direction::toVector() const {
    const float t = glm::radians(theta), p = glm::radians(phi);
    return {std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t)};
}

Direction Direction::fromVector(const glm::vec3& v) {
    const glm::vec3 n = glm::normalize(v);
    Direction d;
    d.theta = glm::degrees(std::acos(std::clamp(n.z, -1.0f, 1.0f)));
    // At the pole phi is undefined; 0 keeps (0, 0) a fixed point of the round trip.
    d.phi = (std::abs(n.x) < 1e-7f && std::abs(n.y) < 1e-7f)
                ? 0.0f
                : wrapDegrees(glm::degrees(std::atan2(n.y, n.x)));
    return d;
}

DirectionSet::DirectionSet(std::string name, std::vector<Direction> directions)
    : _name(std::move(name)), _directions(std::move(directions)) {}

DirectionSet DirectionSet::bonn81() {
    return fromRings("bonn81",
                     {{0, 1, 0}, {15, 6, 0}, {30, 12, 0}, {45, 18, 0}, {60, 20, 0}, {75, 24, 0}});
}

DirectionSet DirectionSet::ubo2014() {
    return fromRings("ubo2014", {{0, 1, 0},
                                 {11, 6, 15},
                                 {23.5f, 12, 0},
                                 {30, 12, 15},
                                 {37.5f, 12, 0},
                                 {45, 18, 0},
                                 {52.5f, 18, 7.5f},
                                 {60, 24, 0},
                                 {67.5f, 24, 7.5f},
                                 {75, 24, 0}});
}

DirectionSet DirectionSet::readFile(const std::string& path) {
    std::ifstream in(path);
    if (!in) fail(path, "cannot open direction file");
    std::vector<Direction> directions;
    std::string line;
    int lineNumber = 0;
    while (std::getline(in, line)) {
        ++lineNumber;
        const auto first = line.find_first_not_of(" \t\r");
        if (first == std::string::npos || line[first] == '#') continue;
        std::istringstream fields(line);
        Direction d;
        std::string rest;
        if (!(fields >> d.theta >> d.phi) || (fields >> rest))
            fail(path,
                 "line " + std::to_string(lineNumber) + ": expected \"theta phi\" in degrees");
        if (!std::isfinite(d.theta) || !std::isfinite(d.phi) || d.theta < 0 || d.theta > 90)
            fail(path, "line " + std::to_string(lineNumber) + ": theta must be in [0, 90] degrees");
        d.phi = wrapDegrees(d.phi);
        directions.push_back(d);
    }
    if (directions.empty()) fail(path, "no directions in file");
    return DirectionSet(std::filesystem::path(path).stem().string(), std::move(directions));
}

void DirectionSet::writeFile(const std::string& path) const {
    std::ostringstream out;
    out << "# osgBTF direction set '" << _name << "': theta phi in degrees, one per line\n";
    out << std::setprecision(9);
    for (const Direction& d : _directions) out << d.theta << ' ' << d.phi << '\n';
    writeFileAtomically(path, [&](const std::string& tmp) {
        std::ofstream file(tmp, std::ios::binary);
        file << out.str();
        file.close();
        if (!file) fail(path, "cannot write direction file");
    });
}

std::string DirectionSet::serialize() const {
    std::ostringstream out;
    out << std::setprecision(9) << _name;
    for (const Direction& d : _directions) out << ';' << d.theta << ',' << d.phi;
    return out.str();
}

DirectionSet DirectionSet::deserialize(const std::string& text) {
    std::istringstream in(text);
    std::string name, item;
    std::getline(in, name, ';');
    std::vector<Direction> directions;
    while (std::getline(in, item, ';')) {
        Direction d;
        char comma = 0;
        std::istringstream pair(item);
        if (!(pair >> d.theta >> comma >> d.phi) || comma != ',')
            throw Error("malformed direction set '" + item + "' in \"" + text.substr(0, 40) +
                        "...\"");
        directions.push_back(d);
    }
    return DirectionSet(name, std::move(directions));
}

int DirectionSet::find(float theta, float phi, float toleranceDegrees) const {
    const Direction query{theta, wrapDegrees(phi)};
    for (std::size_t i = 0; i < _directions.size(); ++i)
        if (angleBetweenDegrees(_directions[i], query) <= toleranceDegrees) return int(i);
    return -1;
}

bool DirectionSet::operator==(const DirectionSet& other) const {
    if (_directions.size() != other._directions.size()) return false;
    for (std::size_t i = 0; i < _directions.size(); ++i)
        if (_directions[i].theta != other._directions[i].theta ||
            _directions[i].phi != other._directions[i].phi)
            return false;
    return true;
}

}  // namespace osgBTF
