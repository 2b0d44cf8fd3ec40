#include "materials/EnvironmentState.h"

#include <algorithm>
#include <map>
#include <mutex>

#include <osg/Uniform>

#include "core/Error.h"
#include "core/ShaderSource.h"
#include "materials/BilinearTaps.h"
#include "materials/Material.h"
#include "materials/MaterialState.h"
#include "materials/MethodRegistry.h"
#include "materials/ShaderInterface.h"

namespace osgBTF {

namespace {

// Columns of the data texture: a power of two every GL 3.3 implementation allows; rows follow.
constexpr int kDataWidth = 4096;

[[noreturn]] void noFolding(const std::string& method) {
    throw Error("environment: method '" + method + "' has no folded environment lighting");
}

const EnvironmentHooks& hooksOf(const Material& material) {
    const std::string method = material.methodName();
    const MethodInfo* info = findMethodIfRegistered(method);
    if (!info || !info->environment) noFolding(method);
    return *info->environment;
}

}  // namespace

bool hasFoldedEnvironment(const std::string& method) {
    const MethodInfo* info = findMethodIfRegistered(method);
    return info && info->environment;
}

bool foldsEnvironment(const Material& material) {
    const MethodInfo* info = findMethodIfRegistered(material.methodName());
    if (!info || !info->environment) return false;
    return !info->environment->folds || info->environment->folds(material);
}

std::vector<float> foldEnvironment(const Material& material, const std::vector<glm::vec3>& g) {
    return hooksOf(material).fold(material, g);
}

glm::vec3 evaluateFolded(const Material& material, const std::vector<float>& folded, int x, int y,
                         const glm::vec3& view) {
    return hooksOf(material).evaluateFolded(material, folded, x, y, view);
}

glm::vec3 evaluateFoldedFiltered(const Material& material, const std::vector<float>& folded,
                                 float u, float v, float lod, const glm::vec3& view) {
    const EnvironmentHooks& hooks = hooksOf(material);
    // The texels and weights point lights blend (Material::evaluateFiltered), as environment.glsl
    // shares surface_frame.glsl's btfAddMipTaps with btf_main.glsl.
    const FilterTaps taps =
        mipFilterTaps(material.mipLayout(), material.width(), material.height(), u, v, lod);
    glm::vec3 value(0.0f);
    for (int k = 0; k < taps.count; ++k)
        value += taps.taps[k].weight *
                 hooks.evaluateFolded(material, folded, taps.taps[k].x, taps.taps[k].y, view);
    return value;
}

std::size_t foldedStride(const Material& material) {
    return hooksOf(material).foldedStride(material);
}

namespace {

/** environmentProgram's programs, one per method for the whole process. */
struct EnvironmentPrograms {
    std::mutex mutex;
    std::map<std::string, osg::ref_ptr<osg::Program>> programs;
};

EnvironmentPrograms& environmentPrograms() {
    static EnvironmentPrograms cache;
    return cache;
}

}  // namespace

void releaseCachedEnvironmentPrograms(osg::State* state) {
    EnvironmentPrograms& cache = environmentPrograms();
    std::lock_guard<std::mutex> lock(cache.mutex);
    for (const auto& entry : cache.programs) entry.second->releaseGLObjects(state);
}

osg::ref_ptr<osg::Program> environmentProgram(const std::string& method) {
    if (!hasFoldedEnvironment(method)) noFolding(method);
    EnvironmentPrograms& cache = environmentPrograms();
    std::lock_guard<std::mutex> lock(cache.mutex);
    osg::ref_ptr<osg::Program>& program = cache.programs[method];
    if (!program) {
        osg::ref_ptr<osg::Program> created = new osg::Program;
        created->setName("osgBTF_" + method + "_environment");
        const std::pair<osg::Shader::Type, std::string> stages[] = {
            {osg::Shader::VERTEX, "common/environment.vert"},
            {osg::Shader::GEOMETRY, "common/environment_geom.glsl"},
            {osg::Shader::FRAGMENT, "environment/" + method + ".frag"}};
        for (const auto& [type, name] : stages) {
            osg::ref_ptr<osg::Shader> shader = new osg::Shader(type, shaderSource(name));
            shader->setName(shaderOrigin(name));
            created->addShader(shader);
        }
        created->addBindAttribLocation(shader::kTangentAttributeName, shader::kTangentAttribute);
        program = created;
    }
    return program;
}

osg::ref_ptr<osg::StateSet> environmentStateSet(const Material& material,
                                                const std::vector<std::vector<float>>& folded,
                                                float exposure) {
    const std::size_t stride = foldedStride(material);
    const std::size_t texelsPerVertex = stride / 3;
    MaterialTexture data;
    data.name = "osgBTF_envData";
    data.kind = MaterialTexture::Float;
    data.channels = 3;
    const std::size_t texels = std::max<std::size_t>(1, folded.size() * texelsPerVertex);
    data.width = int(std::min<std::size_t>(texels, kDataWidth));
    data.height = int((texels + std::size_t(data.width) - 1) / std::size_t(data.width));
    if (data.height > kDataWidth)
        throw Error("environment: " + std::to_string(folded.size()) +
                    " vertices of folded data exceed one 4096 x 4096 texture");
    data.data.assign(data.valueCount(), 0.0f);
    for (std::size_t v = 0; v < folded.size(); ++v) {
        if (folded[v].size() != stride)
            throw Error("environment: vertex " + std::to_string(v) + " has " +
                        std::to_string(folded[v].size()) + " folded values, the material needs " +
                        std::to_string(stride));
        std::copy(folded[v].begin(), folded[v].end(), data.data.begin() + v * stride);
    }
    const osg::ref_ptr<osg::Program> program = environmentProgram(material.methodName());
    osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
    stateSet->setAttributeAndModes(program.get(), osg::StateAttribute::ON);
    addTexture(*stateSet, createFloatTexture(data).get(), "osgBTF_envData", kEnvironmentDataUnit);
    addSamplerUnits(*stateSet, *program, *material.sharedStateSet());
    stateSet->addUniform(new osg::Uniform("osgBTF_envStride", int(texelsPerVertex)));
    stateSet->addUniform(new osg::Uniform("osgBTF_envExposure", exposure));
    // The real eye direction unless set again on this StateSet (a rectified image): a program
    // keeps the last value any StateSet gave a uniform (addCommonState).
    stateSet->addUniform(new osg::Uniform(shader::kFixedView, osg::Vec4(0.0f, 0.0f, 0.0f, 0.0f)));
    const EnvironmentHooks& hooks = hooksOf(material);
    if (hooks.addUniforms) hooks.addUniforms(material, *stateSet);
    return stateSet;
}

}  // namespace osgBTF
