#include "materials/EnvironmentState.h"

#include <algorithm>
#include <map>
#include <mutex>

#include <osg/Uniform>

#include "core/Error.h"
#include "core/ShaderSource.h"
#include "materials/EnvironmentLighting.h"
#include "materials/Material.h"
#include "materials/MaterialState.h"
#include "materials/ShaderInterface.h"
#include "materials/fmf/Fmf.h"
#include "materials/lpca/Lpca.h"
#include "materials/pca/Pca.h"

namespace osgBTF {

namespace {

// Columns of the data texture: a power of two every GL 3.3 implementation allows; rows follow.
constexpr int kDataWidth = 4096;

[[noreturn]] void noFolding(const std::string& method) {
    throw Error("environment: method '" + method + "' has no folded environment lighting");
}

}  // namespace

bool hasFoldedEnvironment(const std::string& method) {
    return method == "pca" || method == "fmf" || method == "lpca";
}

bool foldsEnvironment(const Material& material) {
    if (const auto* fmf = dynamic_cast<const FmfMaterial*>(&material)) return fmfFoldable(*fmf);
    return hasFoldedEnvironment(material.methodName());
}

std::vector<float> foldEnvironment(const Material& material, const std::vector<glm::vec3>& g) {
    if (const auto* pca = dynamic_cast<const PcaMaterial*>(&material)) return foldPca(*pca, g);
    if (const auto* fmf = dynamic_cast<const FmfMaterial*>(&material)) return foldFmf(*fmf, g);
    if (const auto* lpca = dynamic_cast<const LpcaMaterial*>(&material)) return foldLpca(*lpca, g);
    noFolding(material.methodName());
}

glm::vec3 evaluateFolded(const Material& material, const std::vector<float>& folded, int x, int y,
                         const glm::vec3& view) {
    if (const auto* pca = dynamic_cast<const PcaMaterial*>(&material))
        return evaluateFoldedPca(*pca, folded, x, y, view);
    if (const auto* fmf = dynamic_cast<const FmfMaterial*>(&material))
        return evaluateFoldedFmf(*fmf, folded, x, y, view);
    if (const auto* lpca = dynamic_cast<const LpcaMaterial*>(&material))
        return evaluateFoldedLpca(*lpca, folded, x, y, view);
    noFolding(material.methodName());
}

std::size_t foldedStride(const Material& material) {
    if (const auto* pca = dynamic_cast<const PcaMaterial*>(&material))
        return pca->views().size() * std::size_t(pca->components() + 1) * 3;
    if (const auto* fmf = dynamic_cast<const FmfMaterial*>(&material))
        return fmf->views().size() * std::size_t(fmf->factors().factors[0].U.cols()) * 3;
    if (dynamic_cast<const LpcaMaterial*>(&material)) return material.lights().size() * 3;
    noFolding(material.methodName());
}

osg::ref_ptr<osg::Program> environmentProgram(const std::string& method) {
    if (!hasFoldedEnvironment(method)) noFolding(method);
    static std::mutex mutex;
    static std::map<std::string, osg::ref_ptr<osg::Program>> programs;
    std::lock_guard<std::mutex> lock(mutex);
    osg::ref_ptr<osg::Program>& program = programs[method];
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
    if (const auto* fmf = dynamic_cast<const FmfMaterial*>(&material))
        stateSet->addUniform(
            new osg::Uniform("fmfComponents", int(fmf->factors().factors[0].U.cols())));
    if (dynamic_cast<const LpcaMaterial*>(&material))
        stateSet->addUniform(new osg::Uniform("lpcaLights", int(material.lights().size())));
    return stateSet;
}

}  // namespace osgBTF
