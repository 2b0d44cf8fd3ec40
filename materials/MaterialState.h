// osgBTF: building blocks of every method's StateSet (float textures, common uniforms; the
// direction tables are materials/DirectionLookup.h's).
#pragma once

#include <string>

#include <osg/StateSet>
#include <osg/Texture2D>
#include <osg/Texture2DArray>
#include <osg/Texture3D>

#include "core/FittedMaterialFile.h"

namespace osgBTF {

/** NEAREST-filtered, clamped float texture of 1-4 channels (GL_R32F ... GL_RGBA32F, or the 16F
 *  formats for half data), NPOT resize off (float data would be normalised otherwise). For a
 *  texture with depth > 1 a Texture2DArray, one layer per slice. */
osg::ref_ptr<osg::Texture> createFloatTexture(const MaterialTexture& texture);
/** The same as a Texture2DArray whatever the depth: for shaders that declare a sampler2DArray
 *  and whose layer count depends on the data (one layer is a valid array). */
osg::ref_ptr<osg::Texture2DArray> createFloatTextureArray(const MaterialTexture& texture);
osg::ref_ptr<osg::Texture3D> createFloatTexture3D(const MaterialTexture& texture, bool linear);

/** An empty osg::Texture2DArray that uploads its layers again into a texture object created after
 *  a release. OSG 3.6.5's Texture2DArray keeps each context's "layer uploaded" counts when its
 *  texture object is released, so the object it creates next for that context ID (a context
 *  opened after another closed gets the freed ID) is allocated but never filled. Every material
 *  array texture is made with this. */
osg::ref_ptr<osg::Texture2DArray> newTexture2DArray();

/** A sampler uniform + texture on a unit. */
void addTexture(osg::StateSet& stateSet, osg::Texture* texture, const std::string& sampler,
                int unit);

class Material;

/** The uniforms every material sets: osgBTF_size, osgBTF_textureScale (= 1), its mip levels (one
 *  for a material without), the terminator's defaults, and the method's program. */
void addCommonState(osg::StateSet& stateSet, const Material& material);

}  // namespace osgBTF
