// osgBTF harness: the scene a new user first tries cast shadows with: a lit box over a ground
// quad in an osgShadow::ShadowedScene, the ground covered by a BTF material or by a plain texture
// (what OSG's own techniques draw unaided). The shadow tests and bench_shadow_techniques draw it
// under each technique, so a BTF ground can be compared with a plain one in the same run.
#pragma once

#include <string>
#include <vector>

#include <osg/Geometry>
#include <osg/Group>
#include <osgShadow/ShadowTechnique>

#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"

namespace osgBTF {

/** "none", "ShadowMap", "SoftShadowMap", "ViewDependentShadowMap": the techniques MaterialNode
 *  samples, and none (a plain osg::Group holds the scene). */
const std::vector<std::string>& shadowTechniqueNames();

/** A technique with OSG's defaults, as an application sets one up (ShadowMap and SoftShadowMap
 *  1024 x 1024, ViewDependentShadowMap 2048 x 2048 fitted to the view); null for "none". Throws
 *  Error "shadow technique 'X': unknown (none, ShadowMap, SoftShadowMap,
 *  ViewDependentShadowMap)". */
osg::ref_ptr<osgShadow::ShadowTechnique> makeShadowTechnique(const std::string& name);

/** The ground is `groundSize` units square at z = 0, the box (1 unit, its bottom 0.5 above the
 *  ground) at the centre, lit by one directional light from 35 degrees. `ground` null: a plain
 *  RGB texture repeated `textureRepeat` times, drawn by the technique's own shader (or fixed
 *  function without one); else a MaterialNode of `ground` with that texture scale. */
struct ShadowScene {
    osg::ref_ptr<osg::Group> root;               ///< the ShadowedScene, or a Group for "none"
    osg::ref_ptr<osg::Group> ground;             ///< the MaterialNode, or the plain ground's Geode
    osg::ref_ptr<osg::Geometry> groundGeometry;  ///< the quad itself, in either case
    osg::ref_ptr<osg::Node> box;
};
ShadowScene makeShadowScene(Material* ground, const std::string& technique, float groundSize = 8,
                            float textureRepeat = 4);

/** A perspective view of that scene from above and to the side (45 degree field of view): the
 *  ground fills most of a `width` x `height` image. */
CameraSetup shadowSceneCamera(int width, int height);

}  // namespace osgBTF
