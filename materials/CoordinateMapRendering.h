// osgBTF: rendering any fitted material through a coordinate map (core/CoordinateMap.h, the
// output of BTF synthesis), and the material such a render stands for.
//
// GPU: the method's program variant compiled with shader::kCoordinateMapDefine reads the map
// with dependent fetches: the surface's texture coordinates (times the texture scale) cover the
// MAP, wrapping around, and a fragment shows the bilinear blend (GL_LINEAR's weights) of the
// method's values at the sample texels named by the four map entries around its coordinate; the
// map tiles, so its last column blends with its first (shaders/common/btf_main.glsl). Every method
// blends values there, also one that filters its parameter textures without a map
// (Material::TexelFilter::Parameters): neighbouring entries name unrelated sample texels. The map's
// size is the texel grid on the surface: a 1024 x 1024 map over a 64 x 64 sample puts 1024 x 1024
// texels on each repeat. evaluateThroughMap is the CPU reference.
//
// Minified, a map over a mip-mapped material is filtered trilinearly through a mip chain of the
// map itself (coordinateMapChain): level l of the map has GL's size for that level and each of
// its entries names the texel of the sample's level l that holds the sample texel of the first
// (lower-left) base entry it covers. Inside a patch the map copies from the sample, that level
// texel averages the same 2^l x 2^l texels as the map's block, shifted by less than one level-l
// texel; where the block straddles a patch seam it shows the first patch's average. The level of
// detail counts screen steps in map texels, and the fragment blends two levels' four entries each,
// as GL_LINEAR_MIPMAP_LINEAR does. A material without levels is filtered at the map's base level
// at every distance (it may alias, as a texture without mip-maps).
//
// CPU: remapMaterial builds the "materialised" material: the map's size, every per-texel texture
// remapped through the map, every shared table copied. Evaluating it at texel (x, y) computes
// exactly what the original computes at map(x, y). Its filtered evaluation
// (Material::evaluateFiltered) equals evaluateThroughMap exactly where it blends values, and
// where it blends parameters and the finishing step (Material::finishLinear) is linear over the
// four entries (lambert, pca, plain fmf; ptm rgb while its clamp at 0 does not act). Between
// entries of an fmf with exp decoding (dynamic-range reduction, exp colour models) it decodes
// the blend of the parameters and the map render blends decoded values, so they differ there
// (tests/gl/coordinate_map_test.cpp). A mip-mapped material cannot be materialised (the levels
// would have to be fitted again for the map's layout): remapMaterial refuses it.
#pragma once

#include <string>
#include <vector>

#include <osg/Program>
#include <osg/StateSet>
#include <osg/Texture2D>

#include "core/CoordinateMap.h"
#include "core/MipPyramid.h"
#include "materials/Material.h"

namespace osgBTF {

/** Declares the textures of METHOD's FittedMaterial that are shared by all texels (pca's
 *  weights, lpca's eigen-BRDFs, fmf's U). Every other texture holds per-texel data: each of its
 *  layers is a grid of tiles of the material's width x height, indexed by texel like the
 *  material (pca's components side by side, laf's lobes as layers). remapFittedMaterial remaps
 *  those and copies these; it refuses a per-texel texture that is not such a grid. Each method
 *  declares its own from a static initialiser beside registerMethod; a method that declares
 *  nothing has only per-texel textures. Returns true. */
bool declareSharedTextures(const std::string& method, std::vector<std::string> textures);
/** What declareSharedTextures declared for METHOD (empty: none). */
std::vector<std::string> sharedTextures(const std::string& method);

/** Throws Error "MAPNAME: made for a WxH sample, but material 'MATERIAL' is wxh"
 *  (MATERIAL: its source file, else its method) when the map does not point into the
 *  material's texels (the base level's, for a mip-mapped material). */
void checkCoordinateMapMatches(const Material& material, const CoordinateMap& map,
                               const std::string& mapName);

/** The mip chain of `map` for a material laid out as `sampleLayout` (Material::mipLayout):
 *  level 0 is the map; level l >= 1 has GL's size max(1, floor(W / 2^l)) x max(1, floor(H /
 *  2^l)), down to 1 x 1, and its entry (x, y) names the atlas texel of the sample's level
 *  min(l, last) that holds the sample texel of base entry (x 2^l, y 2^l): (sx >> l, sy >> l)
 *  inside that level's rectangle. Each level's sampleWidth x sampleHeight is the atlas's (level
 *  0: the base's). A layout without levels gives the map alone. The map must be valid
 *  (validateCoordinateMap) and made for the layout's base. */
std::vector<CoordinateMap> coordinateMapChain(const CoordinateMap& map,
                                              const MipLayout& sampleLayout);

/** The fitted material of the same method whose per-texel textures (all but the method's
 *  sharedTextures) are remapped: texel (x, y) of every tile of every layer holds the
 *  original's texel map(x, y); size = the map's. Throws Error for a map into another size, an
 *  unknown method, a per-texel texture that is not a grid of width x height tiles, or a result
 *  over memoryLimit(). */
FittedMaterial remapFittedMaterial(const FittedMaterial& file, const CoordinateMap& map);

/** remapFittedMaterial of the material, loaded back as a Material (no source file). */
osg::ref_ptr<Material> remapMaterial(const Material& material, const CoordinateMap& map);

/** The CPU reference of a render through the map at texture coordinate (u, v) (after the texture
 *  scale; the map repeats), magnified: the bilinear blend, with wrap-around, of material.evaluate
 *  at the sample texels named by the four map entries around (u, v), GL_LINEAR's weights (centres
 *  at (i + 0.5) / map size, weights frac(uv size - 0.5)), in btf_main.glsl's order. The map must
 *  point into the material (checkCoordinateMapMatches). */
glm::vec3 evaluateThroughMap(const Material& material, const CoordinateMap& map, float u, float v,
                             const glm::vec3& view, const glm::vec3& light);

/** The same at level of detail `lod` (log2 of a screen step in map texels) through `chain`
 *  (coordinateMapChain of the map for material.mipLayout()): for a mip-mapped material the four
 *  entries around (u, v) of chain level floor(lod) and of the next, the coarser one's share
 *  lod - floor(lod), as GL_LINEAR_MIPMAP_LINEAR (lod clamped to the chain; NaN or negative:
 *  level 0); for a material without levels level 0 at any lod. */
glm::vec3 evaluateThroughMap(const Material& material, const std::vector<CoordinateMap>& chain,
                             float u, float v, float lod, const glm::vec3& view,
                             const glm::vec3& light);

/** The map's chain (coordinateMapChain) as an R32I texture, each texel (sample row << 16) |
 *  sample column (atlas texels), one GL mip level per chain level, NEAREST_MIPMAP_NEAREST, for
 *  texelFetch through an isampler2D. Throws Error for an atlas wider or taller than 65535
 *  texels. */
osg::ref_ptr<osg::Texture2D> createCoordinateMapTexture(const std::vector<CoordinateMap>& chain);

/** createCoordinateMapTexture of the map's chain for `material`'s levels (checkCoordinateMapMatches
 *  first). */
osg::ref_ptr<osg::Texture2D> createCoordinateMapTexture(const Material& material,
                                                        const CoordinateMap& map);

/** What renders `material` through a map when applied on top of `materialState`, the material's
 *  own StateSet (Material::sharedStateSet or createStateSet): the method's coordinate-map program
 *  and the map texture (createCoordinateMapTexture) on unit shader::kCoordinateMapUnit (15), with
 *  its sampler uniform and its number of levels (shader::kCoordinateMapLevels). Throws
 *  Error if the program's source is missing or the material uses that unit. */
osg::ref_ptr<osg::StateSet> createCoordinateMapStateSet(const Material& material,
                                                        const osg::StateSet& materialState,
                                                        osg::Texture2D* mapTexture);

}  // namespace osgBTF
