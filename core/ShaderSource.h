// osgBTF: GLSL sources, embedded at build time and overridable from disk.
//
// shaderSource("laf.frag") returns laf.frag as built into the library, unless a file
// "shaders/laf.frag" is found on OSG_FILE_PATH (osgDB's data path), which then wins: edit a shader
// and rerun without rebuilding (the osgEarth pattern). Lines `#pragma include "common/x.glsl"` are
// replaced by that file, found the same way, recursively. The built-in names are the paths under
// shaders/ in the source tree ("common/btf.vert"), and for a method's shaders in its folder
// materials/<m>/, "<m>.frag", "environment/<m>.frag" and "<m>/<file>" for any other
// (cmake/EmbedShaders.cmake); libosgBTFStreaming adds its own (streaming/*.frag) when it is
// loaded. An override file is always shaders/NAME.
#pragma once

#include <string>
#include <vector>

namespace osgBTF {

/** Throws Error "shader 'NAME': not found (neither on OSG_FILE_PATH as shaders/NAME nor
 *  embedded)" or "FILE: cannot read shader" for an unreadable override. */
std::string shaderSource(const std::string& name);

/** Where the shader comes from: the override file's path, or "embedded:NAME". */
std::string shaderOrigin(const std::string& name);

/** Makes `text` the built-in source of shader NAME when the library embeds none of that name
 *  (for methods registered from outside the library: MethodInfo::fragmentShader). An override
 *  file on OSG_FILE_PATH still wins. Call before the first use (not thread-safe). */
void addShaderSource(const std::string& name, const std::string& text);

/** `source` with `#define NAME 1` (`#define NAME VALUE` for a `name` of "NAME VALUE") after its
 *  `#version` line (GLSL wants #version first), or at the top when it has none: how a program
 *  variant is made from one source. */
std::string addShaderDefine(const std::string& source, const std::string& name);

/** Names of all embedded shaders (those built into the library). */
std::vector<std::string> embeddedShaderNames();

}  // namespace osgBTF
