#include "harness/MaterialImage.h"

#include <algorithm>
#include <cmath>
#include <vector>

#include <tbb/parallel_for.h>

#include <osg/Uniform>

#include "core/Error.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/EnvironmentState.h"
#include "materials/ShaderInterface.h"

namespace osgBTF {

namespace {

/** One pixel per base texel: a mip-mapped material's texels also hold its coarser levels, which
 *  a rectified image at the base's size never shows (its level of detail is 0). */
void rectifiedSize(const Material& material, int& w, int& h) {
    const bool mip = material.mipLayout().mipMapped();
    w = mip ? material.mipLayout().baseWidth() : material.width();
    h = mip ? material.mipLayout().baseHeight() : material.height();
}

/** One pixel per texel of a w x h grid: `stateSet` (the material's) over `mapState` (none or the
 *  coordinate-map program and texture) over the render uniforms. */
FloatImage renderImage(HeadlessRenderer& renderer, osg::StateSet* stateSet, osg::StateSet* mapState,
                       int w, int h, const glm::vec3& view, const glm::vec3& light) {
    osg::ref_ptr<osg::StateSet> render = new osg::StateSet;
    addRectifiedLighting(*render, view, light);

    osg::ref_ptr<osg::Geode> geode = rectifiedPatch();
    geode->setStateSet(render.get());
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->setStateSet(stateSet);
    if (mapState) {
        osg::ref_ptr<osg::Group> mapped = new osg::Group;
        mapped->setStateSet(mapState);
        mapped->addChild(geode.get());
        root->addChild(mapped.get());
    } else {
        root->addChild(geode.get());
    }

    osg::ref_ptr<osg::Image> image = renderer.render(root.get(), orthoUnitSquare(w, h));
    return rgbTopDown(*image, w, h);
}

}  // namespace

FloatImage rgbTopDown(const osg::Image& image, int w, int h) {
    FloatImage out(w, h, 3);
    out.channelNames = {"R", "G", "B"};
    const float* rgba = reinterpret_cast<const float*>(image.data());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                out.at(x, h - 1 - y, c) = rgba[(std::size_t(y) * w + x) * 4 + c];
    return out;
}

void addRectifiedLighting(osg::StateSet& stateSet, const glm::vec3& view, const glm::vec3& light) {
    // OVERRIDE: on a parent of materials' StateSets (bench/bsvtf.cpp's grid) the fixed view must
    // win over the real eye direction each of them sets (addCommonState).
    stateSet.addUniform(new osg::Uniform(shader::kFixedView, osg::Vec4(view.x, view.y, view.z, 1)),
                        osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
    stateSet.addUniform(new osg::Uniform(shader::kLightCount, 1));
    osg::ref_ptr<osg::Uniform> position =
        new osg::Uniform(osg::Uniform::FLOAT_VEC4, shader::kLightPosition, shader::kMaxLights);
    position->setElement(0, osg::Vec4(light.x, light.y, light.z, 0.0f));
    stateSet.addUniform(position.get());
    osg::ref_ptr<osg::Uniform> color =
        new osg::Uniform(osg::Uniform::FLOAT_VEC3, shader::kLightColor, shader::kMaxLights);
    color->setElement(0, osg::Vec3(1, 1, 1));
    stateSet.addUniform(color.get());
}

osg::ref_ptr<osg::Geode> rectifiedPatch() {
    osg::ref_ptr<osg::Geometry> quad = createFullScreenQuadGeometry();
    osg::ref_ptr<osg::Vec4Array> tangents =
        new osg::Vec4Array(quad->getVertexArray()->getNumElements());
    std::fill(tangents->begin(), tangents->end(), osg::Vec4(1, 0, 0, 1));
    quad->setVertexAttribArray(shader::kTangentAttribute, tangents.get(),
                               osg::Array::BIND_PER_VERTEX);
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(quad.get());
    return geode;
}

std::vector<glm::vec3> projectPatchEnvironment(const Material& material,
                                               const EnvironmentMap& map) {
    return projectEnvironment(visibleEnvironment(map, SurfaceFrame{}),
                              DirectionInterpolator(material.lights()));
}

FloatImage evaluateEnvironmentImage(const Material& material, const std::vector<glm::vec3>& g,
                                    const glm::vec3& view, float exposure) {
    int w, h;
    rectifiedSize(material, w, h);
    FloatImage out(w, h, 3);
    out.channelNames = {"R", "G", "B"};
    if (view.z <= 0.0f) return out;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const glm::vec3 value = exposure * evaluateProjected(material, x, y, view, g);
            for (int c = 0; c < 3; ++c) out.at(x, h - 1 - y, c) = value[c];
        }
    return out;
}

FloatImage renderEnvironmentImage(HeadlessRenderer& renderer, const Material& material,
                                  const std::vector<glm::vec3>& g, const glm::vec3& view,
                                  float exposure) {
    int w, h;
    rectifiedSize(material, w, h);
    if (!foldsEnvironment(material)) {
        FloatImage sum(w, h, 3);
        sum.channelNames = {"R", "G", "B"};
        for (std::size_t i = 0; i < g.size(); ++i) {
            if (g[i] == glm::vec3(0.0f)) continue;
            const FloatImage one =
                renderMaterialImage(renderer, material, view, material.lights().vector(i));
            for (std::size_t p = 0; p < sum.pixels.size(); ++p)
                sum.pixels[p] += exposure * g[i][int(p % 3)] * one.pixels[p];
        }
        return sum;
    }
    const std::vector<std::vector<float>> folded(4, foldEnvironment(material, g));
    osg::ref_ptr<osg::Geode> geode = rectifiedPatch();
    osg::ref_ptr<osg::StateSet> state = environmentStateSet(material, folded, exposure);
    state->addUniform(new osg::Uniform("osgBTF_fixedView", osg::Vec4(view.x, view.y, view.z, 1)));
    geode->setStateSet(state.get());
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->setStateSet(material.createStateSet().get());
    root->addChild(geode.get());
    osg::ref_ptr<osg::Image> image = renderer.render(root.get(), orthoUnitSquare(w, h));
    return rgbTopDown(*image, w, h);
}

FloatImage renderMaterialImage(HeadlessRenderer& renderer, const Material& material,
                               const glm::vec3& view, const glm::vec3& light) {
    osg::ref_ptr<osg::StateSet> stateSet = material.createStateSet();
    int w, h;
    rectifiedSize(material, w, h);
    return renderImage(renderer, stateSet.get(), nullptr, w, h, view, light);
}

FloatImage renderMaterialImage(HeadlessRenderer& renderer, const Material& material,
                               const CoordinateMap& map, const glm::vec3& view,
                               const glm::vec3& light) {
    osg::ref_ptr<osg::StateSet> stateSet = material.createStateSet();
    osg::ref_ptr<osg::Texture2D> mapTexture = createCoordinateMapTexture(material, map);
    osg::ref_ptr<osg::StateSet> mapState =
        createCoordinateMapStateSet(material, *stateSet, mapTexture.get());
    return renderImage(renderer, stateSet.get(), mapState.get(), map.width, map.height, view,
                       light);
}

FloatImage evaluateMaterialImage(const Material& material, const CoordinateMap& map,
                                 const glm::vec3& view, const glm::vec3& light) {
    checkCoordinateMapMatches(material, map, "coordinate map");
    const int w = map.width, h = map.height;
    FloatImage out(w, h, 3);
    out.channelNames = {"R", "G", "B"};
    if (light.z <= 0.0f || view.z <= 0.0f) return out;  // as the shader: below the horizon is dark
    // Rows in parallel: Material::evaluate is const and thread-safe (the comparison relies on it).
    tbb::parallel_for(0, h, [&](int y) {
        for (int x = 0; x < w; ++x) {
            const glm::vec3 value =
                material.evaluate(map.sampleX(x, y), map.sampleY(x, y), view, light);
            for (int c = 0; c < 3; ++c) out.at(x, h - 1 - y, c) = value[c];
        }
    });
    return out;
}

FloatImage evaluateMaterialImage(const Material& material, const glm::vec3& view,
                                 const glm::vec3& light) {
    int w, h;
    rectifiedSize(material, w, h);
    FloatImage out(w, h, 3);
    out.channelNames = {"R", "G", "B"};
    if (light.z <= 0.0f || view.z <= 0.0f) return out;  // as the shader: below the horizon is dark
    tbb::parallel_for(0, h, [&](int y) {
        std::vector<glm::vec3> row(static_cast<std::size_t>(w));
        material.evaluateRow(0, y, w, view, light, row.data());
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) out.at(x, h - 1 - y, c) = row[std::size_t(x)][c];
    });
    return out;
}

double maxAbsDifference(const FloatImage& a, const FloatImage& b) {
    if (a.width != b.width || a.height != b.height || a.channels != b.channels)
        throw Error("cannot compare images of different sizes");
    double worst = 0;
    for (std::size_t i = 0; i < a.pixels.size(); ++i) {
        const double d = std::abs(double(a.pixels[i]) - double(b.pixels[i]));
        worst = std::isnan(d) ? INFINITY : std::max(worst, d);
    }
    return worst;
}

}  // namespace osgBTF
