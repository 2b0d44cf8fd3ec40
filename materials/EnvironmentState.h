// osgBTF: GPU state for environment lighting of linear methods (Sattler et al. 2003 section 5.2).
//
// Per vertex, the environment folded into the method's light basis (foldEnvironment) is far too
// large for vertex attributes or varyings (pca: views x (c + 1) RGB = 81 x 17 x 3 floats), so it
// goes into one float texture per geometry, addressed linearly by vertex index. The program
// (shaders/common/environment.vert, environment_geom.glsl, materials/<method>/
// <method>_environment.frag, embedded as environment/<method>.frag)
// hands every fragment the three vertex indices of its triangle (flat) and its barycentric
// coordinates; the fragment blends the three vertices' folded values across the triangle and
// interpolates views as the method's point-light shader does. Only the nearest views of each
// fragment are read, so the cost per texel is 3 vertices x 3 views x (c + 1) fetches. Texels are
// filtered as point lights filter them: a fragment blends the values of the four texels around
// its texture coordinate (GL_LINEAR's weights, wrapping; evaluateFoldedFiltered), up to 4 texels'
// cost where it lies between texel centres; a minified mip-mapped material blends two levels'
// four texels by the level of detail (GL_LINEAR_MIPMAP_LINEAR), up to 8.
//
// Use: the material's sharedStateSet() above the geometry (textures, tables, uniforms), the
// environmentStateSet() on the geometry (program, data texture, exposure).
//
// What differs between methods (the folding, its CPU reference, the data's size, extra uniforms)
// is the method's own: MethodInfo::environment (materials/Material.h), set in its folder; the
// functions below look it up by the material's method name.
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <osg/Program>
#include <osg/StateSet>

namespace osg {
class State;
}

namespace osgBTF {

class Material;

/** Texture unit of the per-vertex data (above every method's own units). */
constexpr int kEnvironmentDataUnit = 12;

/** Whether the method's environment lighting is folded per vertex (exact) rather than drawn
 *  with representative lights: it registered MethodInfo::environment. False for an unknown
 *  name. */
bool hasFoldedEnvironment(const std::string& method);

/** Whether this material's environment lighting folds (hasFoldedEnvironment, and the method's
 *  EnvironmentHooks::folds: for fmf the plain model, fmfFoldable). */
bool foldsEnvironment(const Material& material);

/** Folded data of one vertex: the method's EnvironmentHooks::fold (pca: foldPca, fmf: foldFmf,
 *  lpca: foldLpca). Throws Error "environment: method 'X' has no folded environment lighting"
 *  for the others. */
std::vector<float> foldEnvironment(const Material& material, const std::vector<glm::vec3>& g);

/** What the method's environment shader draws from one vertex's folded data (no blending across
 *  the triangle): EnvironmentHooks::evaluateFolded (evaluateFoldedPca, evaluateFoldedFmf,
 *  evaluateFoldedLpca). Throws Error as foldEnvironment. */
glm::vec3 evaluateFolded(const Material& material, const std::vector<float>& folded, int x, int y,
                         const glm::vec3& view);

/** What the environment shader draws at texture coordinate (u, v) (after the texture scale) and
 *  level of detail `lod` (log2 of base texels per pixel) from one vertex's folded data: the
 *  bilinear blend, with wrap-around, of evaluateFolded at the four texels around (u, v), with
 *  GL_LINEAR's weights; for a mip-mapped material at a lod between two levels, the blend of both
 *  levels' such blends by the lod (the texels and weights of Material::evaluateFiltered: lod
 *  <= 0, NaN, or a material without levels reads the base texels). Throws Error as
 *  foldEnvironment. */
glm::vec3 evaluateFoldedFiltered(const Material& material, const std::vector<float>& folded,
                                 float u, float v, float lod, const glm::vec3& view);

/** RGB values per vertex in foldEnvironment's result. Throws Error as foldEnvironment. */
std::size_t foldedStride(const Material& material);

/** The method's environment program, built once per process and method. Throws Error as
 *  foldEnvironment, or if a shader source is missing. */
osg::ref_ptr<osg::Program> environmentProgram(const std::string& method);
/** environmentProgram's part of releaseCachedPrograms (MethodPrograms.h). */
void releaseCachedEnvironmentPrograms(osg::State* state);

/** Program, per-vertex data texture (folded[v] for vertex index v, each of foldedStride values)
 *  and exposure for one geometry, and the program's other samplers on the units the material's
 *  StateSet gives them (so the program can draw with this StateSet's uniforms alone, as OSG's
 *  compile pass makes it do). Throws Error for data of the wrong size. */
osg::ref_ptr<osg::StateSet> environmentStateSet(const Material& material,
                                                const std::vector<std::vector<float>>& folded,
                                                float exposure = 1.0f);

}  // namespace osgBTF
