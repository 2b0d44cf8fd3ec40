#include "materials/MethodPrograms.h"

#include <algorithm>
#include <map>
#include <mutex>
#include <string>
#include <tuple>
#include <utility>
#include <vector>

#include <osg/Shader>

#include "core/ShaderSource.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/EnvironmentState.h"
#include "materials/LightVisibility.h"
#include "materials/Material.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"
#include "materials/ShaderInterface.h"

namespace osgBTF {

namespace {

/** One program per method and variant for the whole process (every material of a method shares
 *  it, so OSG compiles it once per context); releaseCachedPrograms empties its per-context part. */
struct ProgramCache {
    std::mutex mutex;
    std::map<std::tuple<std::string, bool, bool, std::vector<std::string>>,
             osg::ref_ptr<osg::Program>>
        programs;
    osg::ref_ptr<osg::Program> depthOnly;
};

ProgramCache& programCache() {
    static ProgramCache cache;
    return cache;
}

osg::ref_ptr<osg::Program> programVariant(const std::string& method, bool coordinateMap,
                                          bool shadowMap = false,
                                          const std::vector<std::string>& defines = {}) {
    ProgramCache& cache = programCache();
    std::lock_guard<std::mutex> lock(cache.mutex);
    auto& program = cache.programs[{method, coordinateMap, shadowMap, defines}];
    if (!program) {
        osg::ref_ptr<osg::Program> created = new osg::Program;
        std::string name = "osgBTF_" + method;
        for (const std::string& define : defines) {
            name += "_" + define;
            std::replace(name.begin(), name.end(), ' ', '=');
        }
        created->setName(name + (coordinateMap ? "_coordinateMap" : "") +
                         (shadowMap ? "_shadowMap" : ""));
        const std::string vert = "common/btf.vert", frag = method + ".frag";
        std::string vertex = shaderSource(vert);
        // The shadow variant reads the technique's TexGen in the vertex stage too.
        if (shadowMap) vertex = addShaderDefine(vertex, shader::kShadowMapDefine);
        osg::ref_ptr<osg::Shader> vs = new osg::Shader(osg::Shader::VERTEX, vertex);
        vs->setName(shaderOrigin(vert));
        std::string fragment = shaderSource(frag);
        if (coordinateMap) fragment = addShaderDefine(fragment, shader::kCoordinateMapDefine);
        if (shadowMap) fragment = addShaderDefine(fragment, shader::kShadowMapDefine);
        for (const std::string& define : defines) fragment = addShaderDefine(fragment, define);
        osg::ref_ptr<osg::Shader> fs = new osg::Shader(osg::Shader::FRAGMENT, fragment);
        fs->setName(shaderOrigin(frag));
        created->addShader(vs);
        created->addShader(fs);
        created->addBindAttribLocation(shader::kTangentAttributeName, shader::kTangentAttribute);
        for (int a = 0; a < shader::kLightVisibilityAttributes; ++a)
            created->addBindAttribLocation(shader::kLightVisibilityAttributeName[a],
                                           shader::kLightVisibilityAttribute[a]);
        program = created;
    }
    return program;
}

}  // namespace

osg::ref_ptr<osg::Program> depthOnlyProgram() {
    ProgramCache& cache = programCache();
    std::lock_guard<std::mutex> lock(cache.mutex);
    if (!cache.depthOnly) {
        osg::ref_ptr<osg::Program> created = new osg::Program;
        created->setName("osgBTF_depthOnly");
        for (const auto& [type, name] :
             {std::pair{osg::Shader::VERTEX, "common/depth_only.vert"},
              std::pair{osg::Shader::FRAGMENT, "common/depth_only.frag"}}) {
            osg::ref_ptr<osg::Shader> shader = new osg::Shader(type, shaderSource(name));
            shader->setName(shaderOrigin(name));
            created->addShader(shader);
        }
        cache.depthOnly = created;
    }
    return cache.depthOnly;
}

osg::ref_ptr<osg::Program> methodProgram(const std::string& method) {
    return programVariant(method, false);
}

void releaseCachedPrograms(osg::State* state) {
    {
        ProgramCache& cache = programCache();
        std::lock_guard<std::mutex> lock(cache.mutex);
        for (const auto& entry : cache.programs) entry.second->releaseGLObjects(state);
        if (cache.depthOnly) cache.depthOnly->releaseGLObjects(state);
    }
    releaseCachedEnvironmentPrograms(state);
}

osg::ref_ptr<osg::Program> coordinateMapProgram(const std::string& method) {
    return programVariant(method, true);
}

osg::ref_ptr<osg::Program> shadowMapProgram(const std::string& method, bool coordinateMap) {
    return programVariant(method, coordinateMap, true);
}

osg::ref_ptr<osg::Program> methodProgram(const Material& material) {
    return programVariant(material.methodName(), false, false, material.shaderDefines());
}

osg::ref_ptr<osg::Program> coordinateMapProgram(const Material& material) {
    return programVariant(material.methodName(), true, false, material.shaderDefines());
}

osg::ref_ptr<osg::Program> shadowMapProgram(const Material& material, bool coordinateMap) {
    return programVariant(material.methodName(), coordinateMap, true, material.shaderDefines());
}

}  // namespace osgBTF
