// osgBTF: interpolation between the measured directions of one direction set, on the CPU and in
// shaders, for every method that blends measured views or lights.
//
// It owns the set's DirectionInterpolator (exact Delaunay barycentric weights,
// core/DirectionInterpolation.h) and the table btfLookupDirections reads in
// shaders/common/directions.glsl to compute the same weights per fragment. A method keeps one
// lookup per direction set and uses it in its CPU evaluator and its StateSet:
//
//     _viewLookup = DirectionLookup(_views);                        // once the views are known
//     const InterpolationWeights w = _viewLookup.weights(view);     // CPU evaluator
//     _viewLookup.addToStateSet(*stateSet, "pcaViewTable", 2);      // createStateSet
//     // GLSL: uniform sampler2D pcaViewTable; ... btfLookupDirections(pcaViewTable, view, i, w);
//
// Copies share the (immutable) interpolator, table and texture, so materials copy it freely.
#pragma once

#include <memory>
#include <string>

#include <glm/vec3.hpp>
#include <osg/StateSet>
#include <osg/Texture2D>

#include "core/DirectionInterpolation.h"

namespace osgBTF {

class DirectionLookup {
public:
    /** An empty lookup (weights() and addToStateSet() throw Error until one is assigned). */
    DirectionLookup() = default;
    /** Triangulates the set and builds the shader table; throws Error as DirectionInterpolator. */
    explicit DirectionLookup(const DirectionSet& directions);

    /** The exact weights (DirectionInterpolator::weights): what the shader computes. */
    InterpolationWeights weights(const glm::vec3& direction) const;

    /** Binds the table as an RGBA32F texture on `unit` to the sampler uniform `sampler`. Every
     *  state set gets the same texture object, so GL holds one copy per context. */
    void addToStateSet(osg::StateSet& stateSet, const std::string& sampler, int unit) const;

    /** Operations of one btfLookupDirections call for this set (ShaderCost counting rule), with
     *  its candidate loops at their mean over directions uniform on the hemisphere. */
    struct Cost {
        int alu = 0, tex = 0;
    };
    Cost cost() const;

    bool empty() const { return !_shared; }
    const DirectionInterpolator& interpolator() const;
    const DirectionTable& table() const;

private:
    struct Shared;
    std::shared_ptr<const Shared> _shared;
};

}  // namespace osgBTF
