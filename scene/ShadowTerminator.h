// osgBTF: the smooth shadow terminator of Sattler et al. 2003 (sec. 4.3), the CPU reference of what
// shaders/common/btf.vert and btf_main.glsl compute.
//
// Per vertex and light, u = (1 + cos(alpha + angle(n, l))) / 2 (n the vertex normal, l the
// direction toward the light); u is interpolated across the triangle and looked up in a 1D
// texture of 1024 texels that is black below u = 0.5 and white above, blurred; the light's term
// is multiplied by the value. The boundary u = 0.5 lies at angle(n, l) = 90 - alpha degrees,
// alpha before the faceted silhouette of a coarse mesh, so the light's cut at n.l = 0 and the
// cast shadow's zig-zag boundary fall where the factor is already 0, and the interpolated u puts
// the boundary on each edge where the angles at its two vertices place it (Sattler et al. 2003
// figure 9).
#pragma once

#include <vector>

#include <glm/vec3.hpp>
#include <osg/StateSet>
#include <osg/Texture1D>
#include <osg/ref_ptr>

namespace osgBTF {

/** Sattler et al. 2003's texture size and offset (chosen there for a high-resolution pair of
 * trousers). */
constexpr int kTerminatorTexels = 1024;
constexpr float kDefaultTerminatorAlpha = 15.0f;  // degrees
/** Width in u of the blurred step (u falls by about 0.5 per radian of angle near the boundary,
 *  so 0.1 is a soft band of about 11.5 degrees). Lights at angle(n, l) <= acos(softness) - alpha
 *  (69.3 degrees by default) keep their full value. */
constexpr float kDefaultTerminatorSoftness = 0.1f;

/** u = (1 + cos(alpha + angle(n, l))) / 2 for unit vectors `normal` and `toLight`, alpha in
 *  degrees. */
float terminatorCoordinate(const glm::vec3& normal, const glm::vec3& toLight, float alphaDegrees);

/** The blurred step: 0 below 0.5 - softness / 2, 1 above 0.5 + softness / 2, smoothstep in
 *  between (softness 0: the hard step, 0.5 itself 1). */
float terminatorStep(float u, float softness);

/** The texture's `texels` values: terminatorStep at the texel centres (i + 0.5) / texels. */
std::vector<float> terminatorTexels(float softness, int texels = kTerminatorTexels);

/** What a GL LINEAR, CLAMP_TO_EDGE lookup of `texels` returns at u: the CPU side of the shader's
 *  texture() call. */
float sampleTerminatorTexels(const std::vector<float>& texels, float u);

/** The factor one light gets at a vertex whose u is terminatorCoordinate(n, l, alpha):
 *  sampleTerminatorTexels(terminatorTexels(softness), u), texels cached per softness. */
float terminatorFactor(float u, float softness);

/** A StateSet binding the 1D texture of terminatorTexels(softness) (R32F, LINEAR, CLAMP_TO_EDGE)
 *  on shader::kTerminatorUnit, shared by every caller with the same softness while one holds it.
 *  Nodes push it at cull rather than binding the shared texture in StateSets of their own: a
 *  StateAttribute's list of parent StateSets is not thread-safe, and nodes are made and deleted
 *  on any thread (a DatabasePager's, say), each adding or removing itself there. */
osg::ref_ptr<osg::StateSet> terminatorStateSet(float softness);

/** The texture terminatorStateSet(softness) binds. */
osg::Texture1D* terminatorTexture(const osg::StateSet& terminatorState);

/** Deletes the terminator StateSets no node uses any more (releaseUnusedSharedObjects,
 *  scene/MaterialNode.h, calls it); returns how many. */
std::size_t releaseUnusedTerminatorStateSets();

}  // namespace osgBTF
