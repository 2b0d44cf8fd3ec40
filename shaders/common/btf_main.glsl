// Shared fragment stage: builds the local frame, loops over the lights, and calls the method's
// btfEvaluate(texel, view, light). Included by each method's <method>.frag (materials/<method>/)
// after its #version line.

in vec2 btfTexCoord;
in vec3 btfEyePosition;
in vec3 btfEyeNormal;
in vec4 btfEyeTangent;

const int osgBTF_maxLights = 8;
uniform int osgBTF_lightCount = 0;
// Eye space; w = 0: directional (xyz points toward the light), w = 1: point light position.
uniform vec4 osgBTF_lightPosition[osgBTF_maxLights];
uniform vec3 osgBTF_lightColor[osgBTF_maxLights];
uniform ivec2 osgBTF_size;  // texels of the material
// w = 1: shade every fragment as seen from this local view direction (a rectified image, like a
// measured BTF image: `btf eval`); w = 0: the real eye direction.
uniform vec4 osgBTF_fixedView = vec4(0.0);

// Texel filtering (Material::texelFilter; Material::evaluateFiltered is the CPU reference). A
// fragment shows the bilinear blend, with wrap-around, of the values of the four texels around
// its texture coordinate (trilinear between two mip levels), in one of two ways:
// - TexelFilter::Parameters (osgBTF_bilinear): the material's per-texel parameter textures are
//   GL_LINEAR and GL_REPEAT, and its btfEvaluate samples them at btfBilinearCoordinate when
//   btfBilinear is set (main() sets it for a fragment that reads the base texels: not a
//   mip-mapped or coordinate-mapped lookup). Samples with textureLod at level 0: the lookups sit
//   in non-uniform control flow, where implicit derivatives are undefined. One evaluation.
// - TexelFilter::Values (osgBTF_blendTexels): main() evaluates btfEvaluate at each of the four
//   texels (per level) and blends the values; no method's shader takes part.
// - TexelFilter::Inputs (osgBTF_blendInputs, with osgBTF_blendTexels): main() sets btfBlendInputs
//   and calls btfEvaluate once per light; the method's btfEvaluate blends its own per-texel
//   inputs over the taps (btfTapTexel(k), btfTapWeight(k)) and evaluates the blend (neural's
//   latents: Material::evaluateTaps is the CPU reference). Also through a coordinate map.
// Neither set: the nearest texel (of each of two levels). Through a coordinate map every method
// takes the second way over the map's four entries per level (btfAddMapTaps), whatever its
// TexelFilter: neighbouring entries name unrelated sample texels, so no hardware filter of the
// parameter textures can blend them; btfBilinear stays false there.
uniform bool osgBTF_bilinear = false;
uniform bool osgBTF_blendTexels = false;
uniform bool osgBTF_blendInputs = false;
bool btfBilinear = false;
bool btfBlendInputs = false;
vec2 btfBilinearCoordinate = vec2(0.0);
// The fragment's level of detail in base texels (btfMipLod), set by main() in uniform control
// flow before any evaluation: for a method that picks levels itself (the BSVTF cache,
// streaming/bsvtf.frag), whose btfEvaluate runs inside the light loop, where derivatives are
// undefined. Not set in the coordinate-map variant.
float btfFragmentLod = 0.0;

/** The method's BTF value for one texel and local unit directions (view, light: away from the
 *  surface, z > 0). Measured values include the cosine term: nothing multiplies by n.l again. */
vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light);

#pragma include "common/surface_frame.glsl"

// Smooth shadow terminator (btf.vert computes u per vertex and light; scene/ShadowTerminator.h is
// the CPU reference): the light's term times the blurred step at u.
uniform bool osgBTF_terminator = false;
uniform sampler1D osgBTF_terminatorTexture;
in float btfTerminatorCoordinate[osgBTF_maxLights];
// Per-vertex visibility of single lights (btf.vert, materials/LightVisibility.h).
in float btfLightVisibility[osgBTF_maxLights];

float btfTerminatorFactor(int i) {
    return osgBTF_terminator ? texture(osgBTF_terminatorTexture, btfTerminatorCoordinate[i]).r
                             : 1.0;
}

#ifdef OSGBTF_SHADOW_MAP
// Cast shadows of an osgShadow::ShadowMap, SoftShadowMap or ViewDependentShadowMap (its first
// map) for light osgBTF_shadowLight: the technique's depth texture
// (compare mode on, so the lookup returns the lit fraction; outside the map its border is 1, lit).
uniform sampler2DShadow osgBTF_shadowMap;
uniform int osgBTF_shadowLight = -1;
in vec4 btfShadowCoordinate;

float btfShadowFactor(int i) {
    // q <= 0: the TexGen unit holds no projection this frame (GL's default Q plane is 0, and a
    // ViewDependentShadowMap that made no map sets none), or the point lies behind a positional
    // light's shadow camera, which cannot see occluders there: lit, rather than a division by 0.
    if (i != osgBTF_shadowLight || btfShadowCoordinate.w <= 0.0) return 1.0;
    return textureProj(osgBTF_shadowMap, btfShadowCoordinate);
}
#else
float btfShadowFactor(int i) {
    return 1.0;
}
#endif

// The texels a fragment evaluates (btfTapTexel, btfTapWeight, btfTapCount; btfAddTap,
// btfAddMipTaps) come from surface_frame.glsl, shared with environment lighting.

#ifdef OSGBTF_COORDINATE_MAP
// The program variant for a coordinate map (materials/CoordinateMapRendering.h): the texture
// coordinates cover the map, whose entries are the sample texels shown there (dependent fetches).
// The map's size comes from the texture itself, so osgBTF_size stays the sample's, which the
// methods' own texel arithmetic (tiles, stacked layers) needs. Entry = (row << 16) | column, in
// the material's atlas texels. Over a mip-mapped material the map has a mip chain
// (coordinateMapChain): level l's entries name texels of the sample's level l.
uniform isampler2D osgBTF_coordinateMap;
uniform int osgBTF_coordinateMapLevels = 1;

/** The sample texel that entry `entry` of map level `level` names. */
ivec2 btfMapEntry(ivec2 entry, int level) {
    int columnRow = texelFetch(osgBTF_coordinateMap, entry, level).r;
    return ivec2(columnRow & 0xFFFF, columnRow >> 16);
}

/** The four entries of map level `level` around uv with GL_LINEAR's weights times `share`,
 *  wrapping at the level's edges (a synthesised map tiles: its last column blends with its
 *  first), each tap the sample texel its entry names. */
void btfAddMapLevelTaps(vec2 uv, int level, float share) {
    ivec2 i0, i1;
    vec2 w;
    btfBilinearNeighbours(uv, textureSize(osgBTF_coordinateMap, level), i0, i1, w);
    btfAddTap(btfMapEntry(i0, level), share * (1.0 - w.x) * (1.0 - w.y));
    btfAddTap(btfMapEntry(ivec2(i1.x, i0.y), level), share * w.x * (1.0 - w.y));
    btfAddTap(btfMapEntry(ivec2(i0.x, i1.y), level), share * (1.0 - w.x) * w.y);
    btfAddTap(btfMapEntry(i1, level), share * w.x * w.y);
}

/** The map's taps at uv, as GL_LINEAR_MIPMAP_LINEAR over the map's chain: levels floor(lod) and
 *  the next, the coarser one's share lod - floor(lod), the lod in map texels; main() blends the
 *  method's values there (CoordinateMapRendering.h: evaluateThroughMap is the CPU reference).
 *  Over a material without levels the map's base level at any distance, as GL_LINEAR without
 *  mip-maps. Calls btfLod: uniform control flow. */
void btfAddMapTaps(vec2 uv) {
    float lod = btfLod(uv, vec2(textureSize(osgBTF_coordinateMap, 0)));
    int last = osgBTF_mipLevels > 1 ? osgBTF_coordinateMapLevels - 1 : 0;
    // NaN (no derivative) or negative: level 0.
    lod = lod > 0.0 ? min(lod, float(last)) : 0.0;
    int level = int(floor(lod));
    float coarserWeight = lod - float(level);
    btfAddMapLevelTaps(uv, level, 1.0 - coarserWeight);
    if (coarserWeight > 0.0) btfAddMapLevelTaps(uv, min(level + 1, last), coarserWeight);
}
#endif

void main() {
    vec3 t, b, n;
    btfSurfaceFrame(t, b, n);
    vec3 view = btfLocalView(t, b, n);
#ifndef OSGBTF_COORDINATE_MAP
    btfFragmentLod = btfMipLod(btfTexCoord);
    // A mip-mapped material blends two levels as GL_LINEAR_MIPMAP_LINEAR (btfAddMipTaps: the
    // level selection environment.glsl shares); the four texels of each, or the nearest one.
    btfAddMipTaps(btfTexCoord, osgBTF_blendTexels);
    btfBilinear = osgBTF_bilinear && osgBTF_mipLevels <= 1;
    btfBilinearCoordinate = btfTexCoord;
#else
    // btfBilinear stays false: the method reads each tap's own sample texel.
    btfAddMapTaps(btfTexCoord);
#endif
    // The method blends its inputs over the taps itself: one evaluation per light.
    btfBlendInputs = osgBTF_blendInputs;
    int evaluations = btfBlendInputs ? min(btfTapCount, 1) : btfTapCount;
    vec3 color = vec3(0.0);
    if (view.z > 0.0) {
        for (int i = 0; i < osgBTF_lightCount && i < osgBTF_maxLights; ++i) {
            vec4 p = osgBTF_lightPosition[i];
            vec3 toLight = normalize(p.w == 0.0 ? p.xyz : p.xyz - btfEyePosition);
            vec3 light = vec3(dot(toLight, t), dot(toLight, b), dot(toLight, n));
            if (!(light.z > 0.0)) continue;
            float visible = btfTerminatorFactor(i) * btfShadowFactor(i) * btfLightVisibility[i];
            // Skipped when dark: shadowed lights cost no method evaluation.
            if (visible > 0.0) {
                vec3 value = vec3(0.0);
                for (int k = 0; k < evaluations; ++k)
                    value += (btfBlendInputs ? 1.0 : btfTapWeight(k)) *
                             btfEvaluate(btfTapTexel(k), view, light);
                color += visible * osgBTF_lightColor[i] * value;
            }
        }
    }
    gl_FragColor = vec4(color, 1.0);
}
