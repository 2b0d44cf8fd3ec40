// osgBTF: building blocks of every method's StateSet (float textures, common uniforms; the
// direction tables are materials/DirectionLookup.h's).
#pragma once

#include <functional>
#include <memory>
#include <string>

#include <osg/Program>
#include <osg/StateSet>
#include <osg/Texture2D>
#include <osg/Texture2DArray>
#include <osg/Texture3D>

#include "core/FittedMaterialFile.h"

namespace osg {
class State;
}

namespace osgBTF {

/** NEAREST-filtered, clamped float texture (bilinear: per-texel parameters of a material that
 *  Material::filtersParameters, LINEAR and REPEAT, no mipmaps) of 1-4 channels (GL_R32F ...
 * GL_RGBA32F, or the 16F formats for half data), NPOT resize off (float data would be normalised
 * otherwise). For a texture with depth > 1 a Texture2DArray, one layer per slice. */
osg::ref_ptr<osg::Texture> createFloatTexture(const MaterialTexture& texture,
                                              bool bilinear = false);
/** The same as a Texture2DArray whatever the depth: for shaders that declare a sampler2DArray
 *  and whose layer count depends on the data (one layer is a valid array). */
osg::ref_ptr<osg::Texture2DArray> createFloatTextureArray(const MaterialTexture& texture,
                                                          bool bilinear = false);
osg::ref_ptr<osg::Texture3D> createFloatTexture3D(const MaterialTexture& texture, bool linear);

/** A texture array of `stored` (Half or Float values, in `halves` or `data`) uploaded straight
 *  from them in one call: no copy of the texture in host memory besides `stored` itself, whose
 *  ownership the texture shares (it can outlive the material), and a context that needs the
 *  texture again (a new one, or after a release) gets it from `stored` again. For textures a
 *  method holds anyway in the GPU's layout (fmf's U and SxV). Filtering as
 *  createFloatTextureArray. Throws Error for 8-bit values, no texels or a size mismatch. */
osg::ref_ptr<osg::Texture2DArray> createStoredTextureArray(
    std::shared_ptr<const MaterialTexture> stored, bool bilinear = false);

/** An empty osg::Texture2DArray that uploads its layers again into a texture object created after
 *  a release. OSG 3.6.5's Texture2DArray keeps each context's "layer uploaded" counts when its
 *  texture object is released, so the object it creates next for that context ID (a context
 *  opened after another closed gets the freed ID) is allocated but never filled. It also fills
 *  the texture object OSG recycles from a deleted texture of the same size and format without
 *  specifying that object's storage again (glTexImage3D on immutable storage: a GL error). Every
 *  material array texture is made with this. */
osg::ref_ptr<osg::Texture2DArray> newTexture2DArray();

/** A sampler uniform + texture on a unit. */
void addTexture(osg::StateSet& stateSet, osg::Texture* texture, const std::string& sampler,
                int unit);

/** For every sampler the shaders of `program` declare that `materialState` gives a unit and
 *  `stateSet` does not, a new uniform with that unit on `stateSet`: for a StateSet that sets
 *  another program for a material (environment lighting, a coordinate map), so that the program
 *  can draw with that StateSet's uniforms alone. OSG's compile pass (osgUtil::GLObjectsVisitor)
 *  makes a StateSet's program current with only that StateSet's uniforms and may draw with it
 *  (osgText's compile does); samplers left at unit 0 differ in type on one unit, which makes the
 *  draw invalid. New uniforms, not the material's: adding a uniform to a StateSet changes its
 *  list of parents, which OSG does not guard, and these StateSets are made on any thread. */
void addSamplerUnits(osg::StateSet& stateSet, const osg::Program& program,
                     const osg::StateSet& materialState);

class Material;

/** The uniforms every material sets: osgBTF_size, osgBTF_textureScale (= 1), its mip levels (one
 *  for a material without), the terminator's defaults, and the method's program. */
void addCommonState(osg::StateSet& stateSet, const Material& material);

}  // namespace osgBTF
