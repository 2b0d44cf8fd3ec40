#include "materials/ForeignFiles.h"

#include <cstdio>
#include <vector>

namespace osgBTF {

DirectionSet nominalFileLights() {
    const DirectionSet bonn = DirectionSet::bonn81();
    std::vector<Direction> lights;
    for (std::size_t l = 0; l < bonn.size(); ++l) lights.push_back(bonn[l]);
    return DirectionSet("nominal lights (Bonn 81): the file records none", std::move(lights));
}

std::string floatText(float value) {
    char text[32];
    std::snprintf(text, sizeof text, "%.9g", double(value));
    return text;
}

}  // namespace osgBTF
