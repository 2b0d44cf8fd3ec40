#include "tests/gl/MaterialGpuCheck.h"

#include <algorithm>
#include <cmath>
#include <iostream>
#include <sstream>

#include <gtest/gtest.h>
#include <glm/geometric.hpp>
#include <osg/Geode>
#include <osg/MatrixTransform>
#include <osg/Program>
#include <osg/Uniform>

#include "core/ShaderSource.h"
#include "harness/MaterialImage.h"
#include "harness/PassCost.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/MethodPrograms.h"
#include "materials/ShaderInterface.h"
#include "materials/hsh/Hsh.h"
#include "materials/ptm/Ptm.h"

#include "tests/gl/GlTestEnv.h"

namespace osgBTF::test {

namespace {

glm::dvec3 toGlm(const osg::Vec3d& v) {
    return {v.x(), v.y(), v.z()};
}

osg::Vec3d toOsg(const glm::dvec3& v) {
    return {v.x, v.y, v.z};
}

}  // namespace

glm::dmat3 patchFrame(const osg::Matrixd& model) {
    const glm::dvec3 n = glm::normalize(
        toGlm(osg::Matrixd::transform3x3(osg::Matrixd::inverse(model), osg::Vec3d(0, 0, 1))));
    const glm::dvec3 s = toGlm(osg::Matrixd::transform3x3(osg::Vec3d(1, 0, 0), model));
    const glm::dvec3 t = glm::normalize(s - n * glm::dot(n, s));
    return glm::dmat3(t, glm::cross(n, t), n);
}

PatchRender orthoPatchRender(const Material& material, const glm::vec3& viewIn,
                             const glm::vec3& lightIn, const osg::Matrixd& model) {
    const glm::dmat3 frame = patchFrame(model);
    const osg::Vec3d toEye = toOsg(frame * glm::normalize(glm::dvec3(viewIn)));
    PatchRender render;
    render.model = model;
    render.toLight = toOsg(frame * glm::normalize(glm::dvec3(lightIn)));

    // Looking at the patch centre along -toEye.
    const osg::Vec3d centre = osg::Vec3d(0.5, 0.5, 0.0) * model;
    const osg::Vec3d up = std::abs(toEye.z()) > 0.999 ? osg::Vec3d(0, 1, 0) : osg::Vec3d(0, 0, 1);
    CameraSetup& camera = render.camera;
    camera.view = osg::Matrixd::lookAt(centre + toEye * 2.0, centre, up);
    // Extent of the patch and of one texel step in view space.
    const osg::Matrixd modelView = model * camera.view;
    double lo[2] = {1e9, 1e9}, hi[2] = {-1e9, -1e9};
    for (double x : {0.0, 1.0})
        for (double y : {0.0, 1.0}) {
            const osg::Vec3d p = osg::Vec3d(x, y, 0) * modelView;
            for (int a = 0; a < 2; ++a) {
                lo[a] = std::min(lo[a], p[a]);
                hi[a] = std::max(hi[a], p[a]);
            }
        }
    const osg::Vec3d stepS =
        osg::Matrixd::transform3x3(osg::Vec3d(1.0 / material.width(), 0, 0), modelView);
    const osg::Vec3d stepT =
        osg::Matrixd::transform3x3(osg::Vec3d(0, 1.0 / material.height(), 0), modelView);
    const double texelOnScreen = std::min(osg::Vec2d(stepS.x(), stepS.y()).length(),
                                          osg::Vec2d(stepT.x(), stepT.y()).length());
    const double pixelSize = texelOnScreen / 4.0;  // ~4 pixels per texel along its shortest side
    camera.width = std::clamp(int(std::ceil((hi[0] - lo[0]) / pixelSize)), 8, 2048);
    camera.height = std::clamp(int(std::ceil((hi[1] - lo[1]) / pixelSize)), 8, 2048);
    camera.projection = osg::Matrixd::ortho(lo[0], hi[0], lo[1], hi[1], 0.1, 10.0);
    return render;
}

PatchRender magnifiedPatchRender(const Material& material, const glm::vec2& centre,
                                 float textureScale, const glm::vec3& lightIn, int texels,
                                 int pixels) {
    PatchRender render;
    render.textureScale = textureScale;
    render.toLight = toOsg(glm::normalize(glm::dvec3(lightIn)));
    // Patch coordinates are texture coordinates / textureScale (identity model).
    const osg::Vec3d middle(centre.x / textureScale, centre.y / textureScale, 0.0);
    const double halfS = 0.5 * texels / (double(material.width()) * textureScale);
    const double halfT = 0.5 * texels / (double(material.height()) * textureScale);
    CameraSetup& camera = render.camera;
    camera.view = osg::Matrixd::lookAt(middle + osg::Vec3d(0, 0, 2), middle, osg::Vec3d(0, 1, 0));
    camera.projection = osg::Matrixd::ortho(-halfS, halfS, -halfT, halfT, 0.1, 10.0);
    camera.width = camera.height = pixels;
    return render;
}

GpuCpuComparison compareGpuWithCpu(const Material& material, const PatchRender& render) {
    osg::ref_ptr<osg::StateSet> stateSet = material.createStateSet();
    osg::ref_ptr<osg::Geometry> quad = createFullScreenQuadGeometry();
    osg::ref_ptr<osg::Vec4Array> tangents =
        new osg::Vec4Array(quad->getVertexArray()->getNumElements());
    std::fill(tangents->begin(), tangents->end(), osg::Vec4(1, 0, 0, 1));
    quad->setVertexAttribArray(6, tangents.get(), osg::Array::BIND_PER_VERTEX);
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(quad.get());
    osg::ref_ptr<osg::MatrixTransform> transform = new osg::MatrixTransform(render.model);
    transform->addChild(geode.get());
    transform->setStateSet(stateSet.get());

    const CameraSetup& camera = render.camera;
    const osg::Vec3d eyeLight = osg::Matrixd::transform3x3(render.toLight, camera.view);
    stateSet->addUniform(new osg::Uniform("osgBTF_lightCount", 1));
    stateSet->getOrCreateUniform("osgBTF_textureScale", osg::Uniform::FLOAT)
        ->set(render.textureScale);
    osg::ref_ptr<osg::Uniform> position =
        new osg::Uniform(osg::Uniform::FLOAT_VEC4, "osgBTF_lightPosition", 8);
    position->setElement(0, osg::Vec4(eyeLight, 0.0f));
    stateSet->addUniform(position.get());
    osg::ref_ptr<osg::Uniform> color =
        new osg::Uniform(osg::Uniform::FLOAT_VEC3, "osgBTF_lightColor", 8);
    color->setElement(0, osg::Vec3(1, 1, 1));
    stateSet->addUniform(color.get());

    osg::ref_ptr<osg::Image> image = sharedRenderer().render(transform.get(), camera);

    const glm::dmat3 frame = patchFrame(render.model);
    const glm::dvec3 toLight = glm::normalize(toGlm(render.toLight));
    const glm::vec3 light(glm::dot(toLight, frame[0]), glm::dot(toLight, frame[1]),
                          glm::dot(toLight, frame[2]));
    // Pixel centre -> the eye ray in patch coordinates, through the inverse of the whole chain.
    const osg::Matrixd clipToWorld = osg::Matrixd::inverse(camera.view * camera.projection);
    const osg::Matrixd worldToPatch = osg::Matrixd::inverse(render.model);
    GpuCpuComparison result;
    for (int j = 0; j < camera.height; ++j) {
        for (int i = 0; i < camera.width; ++i) {
            const double x = (i + 0.5) / camera.width * 2.0 - 1.0;
            const double y = (j + 0.5) / camera.height * 2.0 - 1.0;
            const osg::Vec3d nearWorld = osg::Vec3d(x, y, -1.0) * clipToWorld;
            const osg::Vec3d farWorld = osg::Vec3d(x, y, 1.0) * clipToWorld;
            const osg::Vec3d a = nearWorld * worldToPatch, b = farWorld * worldToPatch;
            if (std::abs(a.z() - b.z()) < 1e-12) continue;  // ray parallel to the patch
            const double along = a.z() / (a.z() - b.z());
            const double s = a.x() + (b.x() - a.x()) * along;
            const double t = a.y() + (b.y() - a.y()) * along;
            if (!(s > 0 && s < 1 && t > 0 && t < 1)) continue;
            const double u = s * render.textureScale, v = t * render.textureScale;
            // Every material is filtered (Material::evaluateFiltered): no texel edge is a step,
            // every pixel compares.
            const double fs = u * material.width(), ft = v * material.height();
            const glm::dvec3 toEye = glm::normalize(toGlm(nearWorld - farWorld));
            const glm::vec3 view(glm::dot(toEye, frame[0]), glm::dot(toEye, frame[1]),
                                 glm::dot(toEye, frame[2]));
            if (view.z <= 0.0f) continue;  // the back of the patch renders black
            const int tx = int(fs) % material.width(), ty = int(ft) % material.height();
            const glm::vec3 expected =
                material.evaluateFiltered(float(u), float(v), 0.0f, view, light);
            for (int c = 0; c < 3; ++c) {
                const double d = std::abs(double(pixel(*image, i, j, c)) - expected[c]);
                if (!(d <= result.maxAbsDifference)) {
                    result.maxAbsDifference = std::isnan(d) ? 1e30 : d;
                    std::ostringstream where;
                    where << "pixel (" << i << ", " << j << ") texel (" << tx << ", " << ty
                          << ") channel " << c << ": GPU " << pixel(*image, i, j, c) << " CPU "
                          << expected[c];
                    result.worst = where.str();
                }
            }
            ++result.pixelsCompared;
        }
    }
    return result;
}

GpuCpuComparison compareGpuWithCpu(const Material& material, const glm::vec3& view,
                                   const glm::vec3& light) {
    return compareGpuWithCpu(material, orthoPatchRender(material, view, light));
}

}  // namespace osgBTF::test

namespace osgBTF::test {

namespace {

/** Registers the probe "methods" once: btfEvaluate returns one of its inputs. */
void addProbeShaders() {
    static const bool added = [] {
        const std::string head =
            "#version 330 compatibility\n#pragma include \"common/btf_main.glsl\"\n"
            "vec3 btfEvaluate(ivec2 texel, vec3 view, vec3 light) { return ";
        addShaderSource("osgbtf-probe-view.frag", head + "view; }\n");
        addShaderSource("osgbtf-probe-light.frag", head + "light; }\n");
        addShaderSource("osgbtf-probe-texel.frag", head + "vec3(vec2(texel), 1.0); }\n");
        addShaderSource("osgbtf-probe-uv.frag", head + "vec3(btfTexCoord, 1.0); }\n");
        return true;
    }();
    (void)added;
}

glm::vec3 rgb(const osg::Image& image, int x, int y) {
    return {pixel(image, x, y, 0), pixel(image, x, y, 1), pixel(image, x, y, 2)};
}

}  // namespace

ProbedRender renderProbed(const Material& material, osg::Drawable* drawable,
                          const CameraSetup& camera,
                          const std::function<void(osg::StateSet&)>& configure) {
    addProbeShaders();
    osg::ref_ptr<osg::StateSet> stateSet = material.createStateSet();
    configure(*stateSet);
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(drawable);
    geode->setStateSet(stateSet.get());
    ProbedRender out;
    out.width = camera.width;
    out.height = camera.height;
    const std::size_t n = std::size_t(out.width) * out.height;
    out.color.resize(n);
    out.view.resize(n);
    out.light.resize(n);
    out.texel.resize(n);
    out.uv.resize(n);
    out.shaded.resize(n);
    for (const char* pass :
         {"", "osgbtf-probe-view", "osgbtf-probe-light", "osgbtf-probe-texel", "osgbtf-probe-uv"}) {
        if (*pass) {
            stateSet->setAttributeAndModes(methodProgram(pass).get(), osg::StateAttribute::ON);
            // A probe reports its fragment's nearest texel and inputs, not a blend of them.
            stateSet->addUniform(new osg::Uniform(shader::kBlendTexels, false));
        }
        osg::ref_ptr<osg::Image> image = sharedRenderer().render(geode.get(), camera);
        for (int y = 0; y < out.height; ++y)
            for (int x = 0; x < out.width; ++x) {
                const std::size_t i = out.at(x, y);
                const glm::vec3 v = rgb(*image, x, y);
                const std::string name = pass;
                if (name.empty()) {
                    out.color[i] = v;
                } else if (name == "osgbtf-probe-view") {
                    out.view[i] = v;
                    out.shaded[i] = glm::length(v) > 0.5f;
                } else if (name == "osgbtf-probe-light") {
                    out.light[i] = v;
                } else if (name == "osgbtf-probe-texel") {
                    out.texel[i] = glm::ivec2(int(std::lround(v.x)), int(std::lround(v.y)));
                } else {
                    out.uv[i] = glm::vec2(v.x, v.y);
                }
            }
    }
    sharedRenderer().setScene(nullptr);
    return out;
}

ProbedRender renderProbedSphere(const Material& material, const SphereSetting& setting, int size,
                                float textureScale) {
    const CameraSetup camera = sphereCamera(setting, size);  // renderSphere's
    osg::ref_ptr<osg::Geometry> sphere = createTangentSphere();
    return renderProbed(material, sphere.get(), camera, [&](osg::StateSet& s) {
        setDirectionalLights(s, {setting.lightDirection});
        s.getOrCreateUniform("osgBTF_textureScale", osg::Uniform::FLOAT)->set(textureScale);
    });
}

GpuCpuComparison compareProbedWithCpu(const Material& material, const ProbedRender& render) {
    GpuCpuComparison result;
    for (int y = 0; y < render.height; ++y)
        for (int x = 0; x < render.width; ++x) {
            const std::size_t i = render.at(x, y);
            if (!render.shaded[i]) continue;
            const glm::ivec2 t = render.texel[i];
            const glm::vec2 uv = render.uv[i];
            const glm::vec3 expected =
                material.evaluateFiltered(uv.x, uv.y, 0.0f, render.view[i], render.light[i]);
            for (int c = 0; c < 3; ++c) {
                const double d = std::abs(double(render.color[i][c]) - expected[c]);
                if (!(d <= result.maxAbsDifference)) {
                    result.maxAbsDifference = std::isnan(d) ? 1e30 : d;
                    std::ostringstream where;
                    where << "pixel (" << x << ", " << y << ") texel (" << t.x << ", " << t.y
                          << ") view (" << render.view[i].x << ", " << render.view[i].y << ", "
                          << render.view[i].z << ") channel " << c << ": GPU " << render.color[i][c]
                          << " CPU " << expected[c];
                    result.worst = where.str();
                }
            }
            ++result.pixelsCompared;
        }
    return result;
}

}  // namespace osgBTF::test

namespace osgBTF::test {

double ptmGpuTolerance(const PtmMaterial& m) {
    double largest = 0;
    for (std::size_t t = 0; t < m.texelCount(); ++t)
        for (int s = 0; s < m.slots(); ++s)
            for (int c = 0; c < 3; ++c) {
                double sum = 0;
                for (int k = 0; k < PtmMaterial::kTerms; ++k)
                    sum += std::abs(m.coefficient(t, s, k, c));
                if (m.shape().luminance)
                    sum *= std::abs(m.colour[(s * m.texelCount() + t) * 3 + c]);
                largest = std::max(largest, sum);
            }
    return 64 * std::ldexp(1.0, -24) * largest;
}

double hshGpuTolerance(const HshMaterial& m) {
    // Every harmonic is at most ~1.1 in size over the hemisphere (h12 at the normal); 2 covers it.
    double largest = 0;
    for (std::size_t t = 0; t < m.texelCount(); ++t)
        for (int s = 0; s < m.slots(); ++s)
            for (int c = 0; c < 3; ++c) {
                double sum = 0;
                for (int k = 0; k < m.terms(); ++k) sum += std::abs(m.coefficient(t, s, k, c));
                largest = std::max(largest, 2 * sum);
            }
    return 64 * std::ldexp(1.0, -24) * largest;
}

std::string fragmentSourceOf(const Material& material) {
    const auto* program = dynamic_cast<const osg::Program*>(
        material.sharedStateSet()->getAttribute(osg::StateAttribute::PROGRAM));
    if (!program) return "";
    for (unsigned i = 0; i < program->getNumShaders(); ++i)
        if (program->getShader(i)->getType() == osg::Shader::FRAGMENT)
            return program->getShader(i)->getShaderSource();
    return "";
}

void expectGpuEqualsCpuAtPairs(const Material& material, double bound,
                               const std::vector<std::pair<Direction, Direction>>& pairs,
                               const std::string& label) {
    double worst = 0;
    for (const auto& [v, l] : pairs) {
        const GpuCpuComparison r = compareGpuWithCpu(material, v.toVector(), l.toVector());
        worst = std::max(worst, r.maxAbsDifference);
        EXPECT_GT(r.pixelsCompared, 48) << label << ": view " << v.theta << "/" << v.phi;
        EXPECT_LE(r.maxAbsDifference, bound)
            << label << ": view " << v.theta << "/" << v.phi << " light " << l.theta << "/" << l.phi
            << ": " << r.worst;
    }
    std::cout << label << " GPU vs CPU: largest difference " << worst << " (bound " << bound
              << ") over " << pairs.size() << " (view, light) pairs\n";
}

double methodGpuBound(const Material& m, const glm::vec3& view, const glm::vec3& light) {
    if (m.methodName() == "lambert") return 1e-5;
    if (const auto* ptm = dynamic_cast<const PtmMaterial*>(&m)) return ptmGpuTolerance(*ptm);
    if (const auto* hsh = dynamic_cast<const HshMaterial*>(&m)) return hshGpuTolerance(*hsh);
    if (m.methodName() == "fmf") {
        double largest = 1;
        for (int y = 0; y < m.height(); ++y)
            for (int x = 0; x < m.width(); ++x) {
                const glm::vec3 value = m.evaluate(x, y, view, light);
                for (int c = 0; c < 3; ++c) largest = std::max(largest, double(std::abs(value[c])));
            }
        return 1e-3 * largest;
    }
    return 1e-3;
}

osg::ref_ptr<osg::Image> renderRectifiedPatch(const Material& material,
                                              const RectifiedPatchRender& r) {
    // The material's StateSet above the map's (which replaces its program and adds the map) and
    // the render's own uniforms on the patch, as a scene layers them: the patch's values win.
    osg::ref_ptr<osg::StateSet> stateSet = material.createStateSet();
    osg::ref_ptr<osg::StateSet> render = new osg::StateSet;
    addRectifiedLighting(*render, r.view, r.light);
    render->addUniform(new osg::Uniform(shader::kTextureScale, r.textureScale));
    if (r.mipLevels >= 0) render->addUniform(new osg::Uniform(shader::kMipLevels, r.mipLevels));
    if (!r.blendTexels) render->addUniform(new osg::Uniform(shader::kBlendTexels, false));
    osg::ref_ptr<osg::Geode> geode = rectifiedPatch();
    geode->setStateSet(render.get());
    osg::ref_ptr<osg::Group> mapped = new osg::Group;
    if (r.map) {
        osg::ref_ptr<osg::Texture2D> texture = createCoordinateMapTexture(material, *r.map);
        mapped->setStateSet(createCoordinateMapStateSet(material, *stateSet, texture.get()));
    }
    mapped->addChild(geode.get());
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->setStateSet(stateSet.get());
    root->addChild(mapped.get());
    return sharedRenderer().render(root.get(), orthoUnitSquare(r.width, r.height));
}

osg::ref_ptr<osg::Geometry> trianglePatch() {
    osg::ref_ptr<osg::Geometry> g = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec2Array> texCoords = new osg::Vec2Array;
    for (const osg::Vec2& p :
         {osg::Vec2(0, 0), osg::Vec2(1, 0), osg::Vec2(1, 1), osg::Vec2(0, 1)}) {
        vertices->push_back(osg::Vec3(p, 0.0f));
        texCoords->push_back(p);
    }
    g->setVertexArray(vertices);
    g->setTexCoordArray(0, texCoords);
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array;
    normals->assign(4, osg::Vec3(0, 0, 1));
    g->setNormalArray(normals, osg::Array::BIND_PER_VERTEX);
    osg::ref_ptr<osg::Vec4Array> tangents = new osg::Vec4Array;
    tangents->assign(4, osg::Vec4(1, 0, 0, 1));
    g->setVertexAttribArray(shader::kTangentAttribute, tangents, osg::Array::BIND_PER_VERTEX);
    osg::ref_ptr<osg::DrawElementsUInt> triangles = new osg::DrawElementsUInt(GL_TRIANGLES);
    for (unsigned i : {0u, 1u, 2u, 0u, 2u, 3u}) triangles->push_back(i);
    g->addPrimitiveSet(triangles);
    g->setUseDisplayList(false);
    g->setUseVertexBufferObjects(true);
    return g;
}

ThroughMapCheck checkThroughMap(const Material& material, const Material& remapped,
                                const CoordinateMap& map, const glm::vec3& view,
                                const glm::vec3& light) {
    // Texture scale 2: the patch shows the map twice along each axis, so u and v cross 1 (the
    // wrap edge: the last column blends with the first) in the middle, and the bands left of and
    // below the first centres blend with the last column and row. 4 pixels per entry: pixel
    // centres at 1/8, 3/8, 5/8 and 7/8 of an entry, weights exact in any filter's arithmetic.
    const int perEntry = 4;
    RectifiedPatchRender render;
    render.view = view;
    render.light = light;
    render.textureScale = 2.0f;
    render.width = 2 * map.width * perEntry;
    render.height = 2 * map.height * perEntry;
    const osg::ref_ptr<osg::Image> materialised = renderRectifiedPatch(remapped, render);
    render.map = &map;
    const osg::ref_ptr<osg::Image> mapped = renderRectifiedPatch(material, render);
    ThroughMapCheck r;
    for (int y = 0; y < render.height; ++y)
        for (int x = 0; x < render.width; ++x) {
            const float u = render.textureScale * (float(x) + 0.5f) / float(render.width);
            const float v = render.textureScale * (float(y) + 0.5f) / float(render.height);
            const glm::vec3 expected = evaluateThroughMap(material, map, u, v, view, light);
            const glm::vec3 remappedValue = remapped.evaluateFiltered(u, v, 0.0f, view, light);
            // The entry under the pixel: what a nearest lookup would show.
            const int ex = (x / perEntry) % map.width, ey = (y / perEntry) % map.height;
            const glm::vec3 nearest =
                material.evaluate(map.sampleX(ex, ey), map.sampleY(ex, ey), view, light);
            for (int c = 0; c < 3; ++c) {
                const double got = pixel(*mapped, x, y, c);
                r.gpuCpu = std::max(r.gpuCpu, std::abs(got - double(expected[c])));
                r.materialisedCpu =
                    std::max(r.materialisedCpu, double(std::abs(remappedValue[c] - expected[c])));
                r.materialisedGpu = std::max(r.materialisedGpu,
                                             std::abs(got - double(pixel(*materialised, x, y, c))));
                r.fromNearest = std::max(r.fromNearest, double(std::abs(nearest[c] - expected[c])));
            }
        }
    return r;
}

}  // namespace osgBTF::test
