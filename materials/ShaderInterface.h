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
/** bool: the method's per-texel lookups filter the parameters bilinearly
 *  (Material::TexelFilter::Parameters). */
constexpr const char* kBilinear = "osgBTF_bilinear";
/** bool: btf_main.glsl blends the evaluations of the four texels around the texture coordinate
 *  (per mip level; Material::TexelFilter::Values); false with kBilinear false: nearest texel. */
constexpr const char* kBlendTexels = "osgBTF_blendTexels";
/** bool: with kBlendTexels, the method's btfEvaluate blends its per-texel inputs over the taps
 *  itself (btfTapTexel, btfTapWeight) and main() calls it once per light
 *  (Material::TexelFilter::Inputs). */
constexpr const char* kBlendInputs = "osgBTF_blendInputs";
/** Mip-mapped materials (core/MipPyramid.h): the level count (1: not mip-mapped) and each level's
 *  rectangle (x, y, width, height) in the material's texels; level 0 is the base. */
constexpr const char* kMipLevels = "osgBTF_mipLevels";  ///< int
constexpr const char* kMipLevel = "osgBTF_mipLevel";    ///< ivec4[kMaxMipLevels]
constexpr int kMaxMipLevels = 16;  ///< surface_frame.glsl's `const int osgBTF_maxMipLevels`

/** The coordinate-map variant of every program (btf_main.glsl): the define coordinateMapProgram
 * adds, and the integer sampler it then reads (R32I, (sample row << 16) | sample column). */
constexpr const char* kCoordinateMapDefine = "OSGBTF_COORDINATE_MAP";
constexpr const char* kCoordinateMap = "osgBTF_coordinateMap";
/** The map texture's mip levels (int, createCoordinateMapStateSet): its chain over a mip-mapped
 *  material (coordinateMapChain), else 1. */
constexpr const char* kCoordinateMapLevels = "osgBTF_coordinateMapLevels";
/** The map's texture unit: the last of the 16 every GL 3.x fragment stage has. A fixed unit
 *  rather than the first free one, because methods also point samplers their variant never
 *  reads at units without a texture (ptm), and GL refuses to draw when samplers of different
 *  types share a unit. */
constexpr int kCoordinateMapUnit = 15;

/** Smooth shadow terminator (Sattler et al. 2003 sec. 4.3; scene/ShadowTerminator.h): btf.vert
 * computes u = (1 + cos(alpha + angle(n, l))) / 2 per vertex and light, btf_main.glsl multiplies
 * each light's term by the blurred step texture at u. Off unless kTerminator is true (MaterialNode
 *  sets it; a material's own StateSet, as `btf eval` and the GPU checks use it, leaves it off). */
constexpr const char* kTerminator = "osgBTF_terminator";                ///< bool
constexpr const char* kTerminatorAlpha = "osgBTF_terminatorAlpha";      ///< float, radians
constexpr const char* kTerminatorTexture = "osgBTF_terminatorTexture";  ///< sampler1D
/** A fixed unit, set by addCommonState even when off: an unset sampler1D would point at unit 0,
 *  where the methods keep other sampler types, and GL refuses such draws. */
constexpr int kTerminatorUnit = 14;

/** Cast shadows from osgShadow::ShadowMap, SoftShadowMap or ViewDependentShadowMap (its first map;
 *  scene/README.md): the program variant compiled with
 *  kShadowMapDefine samples the technique's depth texture, rebound by MaterialNode on
 *  kShadowMapUnit, at the coordinates of the technique's eye-linear TexGen (read in btf.vert from
 *  gl_EyePlane*[kShadowTexGenUnit]), for light kShadowLight only. */
constexpr const char* kShadowMapDefine = "OSGBTF_SHADOW_MAP";
constexpr const char* kShadowMap = "osgBTF_shadowMap";                ///< sampler2DShadow
constexpr const char* kShadowTexGenUnit = "osgBTF_shadowTexGenUnit";  ///< int
constexpr const char* kShadowLight = "osgBTF_shadowLight";            ///< int, -1: none
constexpr int kShadowMapUnit = 13;

/** Grid and texel row width of the direction lookup tables (materials/DirectionLookup.h):
 *  shaders/common/directions.glsl's `const int btfDirectionGrid` and `btfDirectionTableWidth`
 *  (a power of 2: the shader splits addresses with a mask). 32 cells across the disc keep the
 *  candidate lists short (1.6 triangles tested per lookup on average for the Bonn set). */
constexpr int kDirectionGrid = 32;
constexpr const char* kDirectionGridName = "btfDirectionGrid";
constexpr int kDirectionTableWidth = 1024;
constexpr const char* kDirectionTableWidthName = "btfDirectionTableWidth";

}  // namespace osgBTF::shader
