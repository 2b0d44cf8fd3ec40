// osgBTF examples: the models and side-by-side scenes that `btf-examples` writes and `btfviewer`
// shows materials on.
//
// Every model is plain OSG geometry (vertices, per-vertex normals, texture coordinates on unit 0;
// no tangents: osgBTF::MaterialNode adds those), Z up like OSG's sample data, so they are usable
// without osgBTF too. The scenes put one MaterialNode per material side by side along +X, each
// with the same (shared) model below a MatrixTransform, a label under each, and two LightSources.
#pragma once

#include <string>
#include <vector>

#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Group>
#include <osg/LightSource>
#include <osgDB/Options>

#include "core/FloatImage.h"

namespace osgBTF::examples {

/** A unit sphere, poles on +-Z, s around the equator, t from pole to pole. */
osg::ref_ptr<osg::Geode> createSphereModel();

/** A square cloth (2 x 2 units before draping) over a round table top of radius 0.6: flat on
 *  top, bent over the edge, hanging with folds that widen toward the hem; tilted 25 degrees
 *  toward a viewer on -Y so the top shows. Texture coordinates follow the cloth (0..1 across
 *  it), so a woven material keeps its threads straight on the top and along the folds.
 *  `resolution` quads per side. */
osg::ref_ptr<osg::Geode> createClothModel(int resolution = 64);

/** A turned vase (a lathe around +Z, about 1.6 units tall): foot, belly, neck and a rounded lip
 *  that continues into the inner wall, plus a bottom disc. s goes around, t up the profile
 *  (scaled to keep texels roughly square). `segments` around, `profileSamples` along. */
osg::ref_ptr<osg::Geode> createVaseModel(int segments = 48, int profileSamples = 80);

/** One object of a side-by-side scene: a fitted-material file (a name relative to the scene,
 *  as the MaterialNode stores it) and the label shown under the object. */
struct SceneItem {
    std::string materialFile;
    std::string label;
};

/** The two lights of every example scene: a warm directional key light from the upper left
 *  front (light 0) and a cool point light to the right (light 1), placed for a row of objects
 *  `rowWidth` wide centred on the origin. */
std::vector<osg::ref_ptr<osg::LightSource>> createTwoLights(float rowWidth);

/** The side-by-side scene: for each item a MatrixTransform (spaced `spacing` apart along +X)
 *  holding a MaterialNode (the item's material, `textureScale`) over `model`, a label below,
 *  and the two lights. The material files are loaded (found through `options`' database paths)
 *  so tangents exist and problems show now; the nodes keep the names as given. Throws Error
 *  naming the material file when one cannot be loaded. */
osg::ref_ptr<osg::Group> createSideBySideScene(osg::Node* model,
                                               const std::vector<SceneItem>& items, float spacing,
                                               float textureScale, const osgDB::Options* options);

/** The shadowed cloth scene (Sattler et al. 2003's setting): the draped cloth
 * (createClothModel(56): 3249 vertices, coarse enough to show what the smooth terminator does)
 * under a MaterialNode with `materialFile`, on its round table, over a floor, inside an
 * osgShadow::ShadowedScene with an osgShadow::ShadowMap (2048 texels), lit by a cool fill light and
 * a warm key light that casts the shadows (the last light: ShadowMap's and MaterialNode's default
 * choice). The table and floor are plain OSG geometry, drawn by ShadowMap's own shader. Throws
 * Error like createSideBySideScene. */
osg::ref_ptr<osg::Group> createShadowedClothScene(const std::string& materialFile,
                                                  float textureScale,
                                                  const osgDB::Options* options);

/** The draped cloth (createClothModel(56)) under a MaterialNode with `materialFile`, inside an
 *  osgBTF::EnvironmentLitGroup lit by the HDR map `environmentFile` (Sattler et al. 2003 section 5:
 * the folds shadow the environment per vertex): the group computes the lighting by itself when a
 *  viewer first updates it, so stock osgviewer shows it. Throws Error like
 *  createSideBySideScene, or naming an unusable map. */
osg::ref_ptr<osg::Group> createEnvironmentLitClothScene(const std::string& materialFile,
                                                        const std::string& environmentFile,
                                                        float textureScale,
                                                        const osgDB::Options* options);

/** The direction toward the sun of createSkyEnvironment (Z up): azimuth 210 degrees from +X
 *  toward +Y, elevation 35 degrees. */
osg::Vec3 skySunDirection();

/** A procedural HDR sky (CC0, made here, nothing downloaded): a latitude-longitude map, column x
 *  at azimuth 360 * (x + 0.5) / width degrees from +X toward +Y, row y (0 = top) at elevation
 *  90 - 180 * (y + 0.5) / height degrees (Z up); a blue gradient from zenith to a bright hazy
 *  horizon, a dark brown ground below it, and a sun (0.53 degrees across, radiance 20000 times
 *  the zenith's, with a glow) in skySunDirection(). RGB, linear radiance, all values finite and
 *  positive. Throws Error for a size under 8 x 4. */
FloatImage createSkyEnvironment(int width = 512, int height = 256);

/** Writes a node with osgDB (the format follows the extension) to a temporary name beside
 *  `path`, then renames it, so a reader never sees half a file. Throws Error "PATH: ..." on
 *  failure. */
void writeNodeAtomically(const osg::Node& node, const std::string& path);

}  // namespace osgBTF::examples
