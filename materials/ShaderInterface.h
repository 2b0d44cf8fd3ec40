// osgBTF: the interface between C++ and every method's GLSL program, in one place.
//
// shaders/common/btf.vert and btf_main.glsl declare the same names and the light limit
// (tests/shader_interface_test.cpp reads them and checks they agree with this header); methods
// add their own uniforms and samplers (prefixed with the method's name) on top.
#pragma once

namespace osgBTF::shader {

/** Vertex attribute index of the tangent (xyz along +s, w = handedness), bound by methodProgram
 *  and filled by MaterialNode. OSG's fixed aliases use 0-3 and 8+ (texcoords); 6 is free. */
constexpr unsigned kTangentAttribute = 6;
constexpr const char* kTangentAttributeName = "osgBTF_tangent";

/** Lights one pass shades; btf_main.glsl's `const int osgBTF_maxLights`. */
constexpr int kMaxLights = 8;
constexpr const char* kMaxLightsName = "osgBTF_maxLights";

// Uniforms of the shared stages (set by MaterialState's addCommonState and by MaterialNode).
constexpr const char* kLightCount = "osgBTF_lightCount";        ///< int
constexpr const char* kLightPosition = "osgBTF_lightPosition";  ///< vec4[kMaxLights], eye space
constexpr const char* kLightColor = "osgBTF_lightColor";        ///< vec3[kMaxLights]
constexpr const char* kSize = "osgBTF_size";                    ///< ivec2, texels of the material
constexpr const char* kFixedView = "osgBTF_fixedView";          ///< vec4, w = 1: fixed local view
constexpr const char* kTextureScale = "osgBTF_textureScale";    ///< float, tiling

/** The coordinate-map variant of every program (btf_main.glsl): the define coordinateMapProgram
 * adds, and the integer sampler it then reads (R32I, (sample row << 16) | sample column). */
constexpr const char* kCoordinateMapDefine = "OSGBTF_COORDINATE_MAP";
constexpr const char* kCoordinateMap = "osgBTF_coordinateMap";
/** The map's texture unit: the last of the 16 every GL 3.x fragment stage has. A fixed unit
 *  rather than the first free one, because methods also point samplers their variant never
 *  reads at units without a texture (ptm), and GL refuses to draw when samplers of different
 *  types share a unit. */
constexpr int kCoordinateMapUnit = 15;

/** Grid and texel row width of the direction lookup tables (materials/DirectionLookup.h):
 *  shaders/common/directions.glsl's `const int btfDirectionGrid` and `btfDirectionTableWidth`
 *  (a power of 2: the shader splits addresses with a mask). 32 cells across the disc keep the
 *  candidate lists short (1.6 triangles tested per lookup on average for the Bonn set). */
constexpr int kDirectionGrid = 32;
constexpr const char* kDirectionGridName = "btfDirectionGrid";
constexpr int kDirectionTableWidth = 1024;
constexpr const char* kDirectionTableWidthName = "btfDirectionTableWidth";

}  // namespace osgBTF::shader
