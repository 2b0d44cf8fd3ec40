#include "harness/PassCost.h"

#include <algorithm>
#include <cctype>
#include <random>

#include <osg/Texture2D>
#include <osg/Uniform>

#include "core/Error.h"
#include "materials/MethodPrograms.h"

namespace osgBTF {

namespace {

PassTime timeCurrentScene(HeadlessRenderer& renderer, const PassSettings& settings,
                          const PassTarget& target) {
    PassTime t;
    renderer.setColorTarget(target.format, false);
    try {
        t.timing = renderer.timePasses(settings.frames, GpuTimer::Auto, settings.warmupFrames);
    } catch (...) {
        renderer.setColorTarget(GL_RGBA32F_ARB, true);
        throw;
    }
    renderer.setColorTarget(GL_RGBA32F_ARB, true);
    if (!renderer.isSoftwareRenderer() && t.timing.gpuMs >= 0) {
        t.ms = t.timing.gpuMs;
        t.clock = "GL_TIME_ELAPSED";
    } else {
        t.ms = t.timing.wallMs;
        t.clock = "wall+glFinish";
    }
    return t;
}

void checkSettings(const PassSettings& s) {
    if (s.width < 1 || s.height < 1) throw Error("pass resolution must be at least 1x1");
    if (s.lights < 1 || s.lights > 8) throw Error("pass lights must be 1..8");
    if (s.frames < 1) throw Error("pass frames must be at least 1");
    if (s.warmupFrames < 0) throw Error("pass warm-up frames must be at least 0");
}

}  // namespace

PassTarget passTarget(const std::string& name) {
    std::string lower = name;
    for (char& c : lower) c = char(std::tolower(static_cast<unsigned char>(c)));
    if (lower == "rgba8") return {"RGBA8", GL_RGBA8};
    if (lower == "rgba16f") return {"RGBA16F", GL_RGBA16F_ARB};
    if (lower == "rgba32f") return {"RGBA32F", GL_RGBA32F_ARB};
    throw Error("pass target '" + name + "': must be rgba8, rgba16f or rgba32f");
}

std::vector<osg::Vec3> defaultLightDirections(int count) {
    std::vector<osg::Vec3> directions;
    for (int i = 0; i < count; ++i) {
        // Spread around the first light, all well above the horizon of a patch facing +Z.
        const float angle = 0.9f + 2.39996f * float(i);  // golden angle
        osg::Vec3 d(0.45f * std::cos(angle), 0.45f * std::sin(angle), 0.85f);
        d.normalize();
        directions.push_back(d);
    }
    return directions;
}

void setDirectionalLights(osg::StateSet& stateSet, const std::vector<osg::Vec3>& directions) {
    if (directions.size() > 8) throw Error("at most 8 lights");
    stateSet.addUniform(new osg::Uniform("osgBTF_lightCount", int(directions.size())));
    osg::ref_ptr<osg::Uniform> position =
        new osg::Uniform(osg::Uniform::FLOAT_VEC4, "osgBTF_lightPosition", 8);
    osg::ref_ptr<osg::Uniform> colour =
        new osg::Uniform(osg::Uniform::FLOAT_VEC3, "osgBTF_lightColor", 8);
    for (int i = 0; i < 8; ++i) {
        osg::Vec3 d = i < int(directions.size()) ? directions[i] : osg::Vec3(0, 0, 1);
        d.normalize();
        position->setElement(i, osg::Vec4(d, 0.0f));
        colour->setElement(i, osg::Vec3(1, 1, 1));
    }
    stateSet.addUniform(position.get());
    stateSet.addUniform(colour.get());
}

osg::ref_ptr<osg::Geode> createTangentPatch(osg::StateSet* stateSet) {
    osg::ref_ptr<osg::Geode> geode = createFullScreenQuad(stateSet);
    osg::Geometry* quad = geode->getDrawable(0)->asGeometry();
    osg::ref_ptr<osg::Vec4Array> tangents =
        new osg::Vec4Array(quad->getVertexArray()->getNumElements());
    std::fill(tangents->begin(), tangents->end(), osg::Vec4(1, 0, 0, 1));
    quad->setVertexAttribArray(6, tangents.get(), osg::Array::BIND_PER_VERTEX);
    return geode;
}

PassTime timeMaterialPass(HeadlessRenderer& renderer, const Material& material,
                          const PassSettings& settings, const PassTarget& target) {
    checkSettings(settings);
    osg::ref_ptr<osg::StateSet> stateSet = material.createStateSet();
    setDirectionalLights(*stateSet, defaultLightDirections(settings.lights));
    // Tiled so that neighbouring pixels read different texels, as on a textured model.
    stateSet->getOrCreateUniform("osgBTF_textureScale", osg::Uniform::FLOAT)
        ->set(settings.textureScale);
    renderer.setScene(createTangentPatch(stateSet.get()).get());
    renderer.setCamera(orthoUnitSquare(settings.width, settings.height));
    const PassTime t = timeCurrentScene(renderer, settings, target);
    renderer.setScene(nullptr);
    return t;
}

Calibration runCalibration(HeadlessRenderer& renderer, const PassSettings& settings,
                           const PassTarget& target) {
    checkSettings(settings);
    if (settings.calibrationFetches < 1) throw Error("calibration fetches must be at least 1");
    constexpr int kSize = 512;
    osg::ref_ptr<osg::Image> image = new osg::Image;
    image->allocateImage(kSize, kSize, 1, GL_RGBA, GL_FLOAT);
    image->setInternalTextureFormat(GL_RGBA32F_ARB);
    std::mt19937 random(7);
    std::uniform_real_distribution<float> uniform(0.0f, 1.0f);
    float* data = reinterpret_cast<float*>(image->data());
    for (int i = 0; i < kSize * kSize * 4; ++i) data[i] = uniform(random);
    osg::ref_ptr<osg::Texture2D> texture = new osg::Texture2D(image.get());
    texture->setInternalFormat(GL_RGBA32F_ARB);
    texture->setResizeNonPowerOfTwoHint(false);
    texture->setFilter(osg::Texture::MIN_FILTER, osg::Texture::NEAREST);
    texture->setFilter(osg::Texture::MAG_FILTER, osg::Texture::NEAREST);

    Calibration result;
    result.target = target;
    result.fetchCount = settings.calibrationFetches;
    renderer.setCamera(orthoUnitSquare(settings.width, settings.height));
    for (int fetches : {0, settings.calibrationFetches}) {
        osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
        stateSet->setAttributeAndModes(methodProgram("calibration/fetch").get());
        stateSet->setTextureAttributeAndModes(0, texture.get());
        stateSet->addUniform(new osg::Uniform("calibrationTexture", 0));
        stateSet->addUniform(new osg::Uniform("calibrationFetches", fetches));
        renderer.setScene(createFullScreenQuad(stateSet.get()).get());
        (fetches == 0 ? result.empty : result.fetches) =
            timeCurrentScene(renderer, settings, target);
    }
    renderer.setScene(nullptr);
    const double pixels = double(settings.width) * double(settings.height);
    // The reads alone: what the N fetches add to the pass without them.
    const double readMs = result.fetches.ms - result.empty.ms;
    if (result.empty.ms >= 0 && readMs > 0)
        result.fetchesPerSecond = double(result.fetchCount) * pixels / (readMs * 1e-3);
    return result;
}

MethodPass timeMethodPass(HeadlessRenderer& renderer, const Material& material,
                          const PassSettings& settings, const Calibration& calibration,
                          int texPerPixel) {
    MethodPass m;
    m.target = calibration.target;
    m.pass = timeMaterialPass(renderer, material, settings, calibration.target);
    m.emptyMs = calibration.empty.ms;
    m.shadingMs = m.pass.ms - m.emptyMs;
    const double pixels = double(settings.width) * double(settings.height);
    if (texPerPixel >= 0 && calibration.fetchesPerSecond > 0) {
        m.floorMs = double(texPerPixel) * pixels / calibration.fetchesPerSecond * 1e3;
        if (m.floorMs > 0) m.floorRatio = m.shadingMs / m.floorMs;
    }
    return m;
}

}  // namespace osgBTF
