// osgBTF: per-vertex visibility of single lights, for the representative lights of environment
// lighting (environment/EnvironmentLitGroup.h): the methods without folded environment lighting are
// lit by a few median-cut lights, and each vertex sees each of them or not (ray cast against
// the scene), as the folded methods see the environment itself.
//
// Shader interface (shaders/common/btf.vert): three vertex attributes hold the occlusion (1:
// hidden, 0: seen) of up to 9 lights in their x, y, z (w unused: a geometry without the arrays
// reads OpenGL's default (0, 0, 0, 1), every light seen); light i of the pass reads slot
// osgBTF_lightVisibilitySlot[i] (-1: always seen). MaterialNode fills the slots from the
// LightSources' user value "osgBTF.visibilitySlot" (an int).
#pragma once

namespace osgBTF::shader {

constexpr int kLightVisibilityAttributes = 3;
constexpr unsigned kLightVisibilityAttribute[kLightVisibilityAttributes] = {10, 11, 12};
constexpr const char* kLightVisibilityAttributeName[kLightVisibilityAttributes] = {
    "osgBTF_lightOcclusion0", "osgBTF_lightOcclusion1", "osgBTF_lightOcclusion2"};
constexpr int kLightVisibilitySlots = 3 * kLightVisibilityAttributes;
constexpr const char* kLightVisibilitySlot = "osgBTF_lightVisibilitySlot";  ///< int[kMaxLights]
/** The int user value of an osg::LightSource naming its slot. */
constexpr const char* kLightVisibilityUserValue = "osgBTF.visibilitySlot";

}  // namespace osgBTF::shader
