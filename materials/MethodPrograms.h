// osgBTF: one osg::Program per method and variant (plain, through a coordinate map, under a shadow
// map) for the whole process, built from the method's embedded shaders (core/ShaderSource.h):
// every material of a method shares it, so OSG compiles it once per context.
#pragma once

#include <string>

#include <osg/Program>
#include <osg/ref_ptr>

namespace osg {
class State;
}

namespace osgBTF {

class Material;

/** The method's shared program: common/btf.vert + <method>.frag (materials/<method>/, or the
 *  method's MethodInfo::fragmentShader), the tangent bound to shader::kTangentAttribute. Compiled
 * by OSG at first use; built once per process and method. Throws Error if a source is missing. */
osg::ref_ptr<osg::Program> methodProgram(const std::string& method);
/** methodProgram's variant for rendering through a coordinate map: the same sources, the
 *  fragment shader compiled with `#define OSGBTF_COORDINATE_MAP 1` (shader::kCoordinateMapDefine,
 *  after its #version line). Built once per process and method, like methodProgram. */
osg::ref_ptr<osg::Program> coordinateMapProgram(const std::string& method);
/** methodProgram's variant that samples an osgShadow::ShadowMap for one light (both stages
 *  compiled with shader::kShadowMapDefine; with `coordinateMap` also kCoordinateMapDefine, the
 *  coordinate-map variant's). Built once per process, method and variant; used by MaterialNode
 *  below an osgShadow::ShadowedScene. */
osg::ref_ptr<osg::Program> shadowMapProgram(const std::string& method, bool coordinateMap);
/** The three programs above for one material: compiled also with its
 *  Material::shaderDefines() (after the variant's own defines), one program per method, variant
 *  and list of defines. What a material's state sets use. */
osg::ref_ptr<osg::Program> methodProgram(const Material& material);
osg::ref_ptr<osg::Program> coordinateMapProgram(const Material& material);
osg::ref_ptr<osg::Program> shadowMapProgram(const Material& material, bool coordinateMap);
/** What MaterialNode draws with in a shadow technique's depth pass, for every method: the
 *  fixed-function position and an empty fragment stage (shaders/common/depth_only.*), so a depth
 *  map costs what it costs for a plain textured node. One per process. */
osg::ref_ptr<osg::Program> depthOnlyProgram();
/** Releases the GL objects that the process-wide programs (methodProgram, its variants,
 *  environmentProgram) hold for the context of `state` (null: every context). OSG releases what a
 *  closing context's scene graph holds, but these programs outlive any scene graph: a context
 *  that is closed after its scene was removed leaves them pointing at its program objects, and a
 *  later context that gets the same context ID would use those dead objects (GL_INVALID_VALUE at
 *  every draw). Call it with the context current before closing such a context;
 *  HeadlessRenderer does. */
void releaseCachedPrograms(osg::State* state);

}  // namespace osgBTF
