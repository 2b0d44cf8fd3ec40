// Environment lighting on the GPU (materials/EnvironmentState.h): per-vertex folded pca, fmf and
// lpca data, blended across the triangles, against the CPU's evaluateFoldedFiltered at every
// pixel (magnified: a fragment blends the four texels around it, wrapping at the material's
// edges; minified, a mip-mapped material's two levels around the level of detail), and the white
// environment against the brute-force integral of the point-light rendering.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <functional>
#include <iostream>
#include <random>

#include <glm/geometric.hpp>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Group>
#include <osg/LightSource>
#include <osg/MatrixTransform>
#include <osg/Texture2D>
#include <osgDB/ReadFile>
#include <osgDB/WriteFile>
#include <osgUtil/UpdateVisitor>

#include "environment/EnvironmentLitGroup.h"
#include "environment/VertexEnvironment.h"
#include "fit/MipMapping.h"
#include "harness/MaterialImage.h"
#include "harness/sample/SampleBtf.h"
#include "materials/BilinearTaps.h"
#include "materials/EnvironmentLighting.h"
#include "materials/EnvironmentState.h"
#include "materials/MethodRegistry.h"
#include "materials/ShaderInterface.h"
#include "materials/fmf/Fmf.h"
#include "materials/lpca/Lpca.h"
#include "materials/pca/Pca.h"
#include "scene/EnvironmentLight.h"
#include "scene/MaterialNode.h"
#include "tests/gl/GlTestEnv.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::trianglePatch;

namespace {

const PcaMaterial& pca() {
    static osg::ref_ptr<PcaMaterial> m = [] {
        SampleOptions options;
        options.width = options.height = 4;
        return PcaMaterial::fit(makeSampleBtf(options),
                                FitOptions::parse("components=5 storage=unorm8"));
    }();
    return *m;
}

MeasuredBtf sample4() {
    SampleOptions options;
    options.width = options.height = 4;
    return makeSampleBtf(options);
}

const FmfMaterial& fmf() {
    static osg::ref_ptr<FmfMaterial> m =
        FmfMaterial::fit(sample4(), FitOptions::parse("components=6 storage=half"));
    return *m;
}

const LpcaMaterial& lpca() {
    static osg::ref_ptr<LpcaMaterial> m =
        LpcaMaterial::fit(sample4(), FitOptions::parse("clusters=2 components=3"));
    return *m;
}

/** The unit square as two indexed triangles (0 1 2, 0 2 3), normal +Z, tangent +X. */
/** A map of one radiance everywhere, width x width / 2 texels. */
EnvironmentMap uniformMap(int width, float radiance) {
    EnvironmentMap map;
    map.width = width;
    map.height = width / 2;
    map.rgb.assign(std::size_t(map.width) * map.height * 3, radiance);
    return map;
}

/** Barycentric coordinates of point (u, v) of the square over its 4 vertices. */
std::array<float, 4> barycentric(float u, float v) {
    if (u >= v) return {1.0f - u, u - v, v, 0.0f};
    return {1.0f - v, 0.0f, u, v - u};
}

struct Rendered {
    osg::ref_ptr<osg::Image> image;
    int size;
};

/** The square at texture scale `scale` (it shows [0, scale]^2 of the material) in 32 x 32
 *  pixels: 8 pixels per texel of the 4 x 4 materials at scale 1. */
Rendered render(const Material& material, const std::vector<std::vector<float>>& folded,
                const glm::vec3& view, float exposure, float scale = 1.0f) {
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->setStateSet(material.sharedStateSet());
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(trianglePatch());
    geode->setStateSet(environmentStateSet(material, folded, exposure));
    geode->getStateSet()->addUniform(
        new osg::Uniform(shader::kFixedView, osg::Vec4(view.x, view.y, view.z, 1.0f)));
    geode->getStateSet()->addUniform(new osg::Uniform(shader::kTextureScale, scale));
    root->addChild(geode);
    const int size = 32;
    return {test::sharedRenderer().render(root, orthoUnitSquare(size, size)), size};
}

/** What pixel (x, y) of a size x size render shows on the CPU: evaluateFoldedFiltered at the
 *  pixel's texture coordinate and level of detail `lod`, the vertices' values blended across the
 *  triangle, times the exposure. */
glm::vec3 expectedPixel(const Material& material, const std::vector<std::vector<float>>& folded,
                        const glm::vec3& view, float exposure, float scale, float lod, int x, int y,
                        int size) {
    const float px = (x + 0.5f) / size, py = (y + 0.5f) / size;
    const std::array<float, 4> b = barycentric(px, py);
    glm::vec3 expected(0.0f);
    for (int k = 0; k < 4; ++k)
        if (b[k] > 0.0f)
            expected += b[k] * evaluateFoldedFiltered(material, folded[k], scale * px, scale * py,
                                                      lod, view);
    return expected * exposure;
}

/** Largest |GPU - CPU| over the image (CPU: expectedPixel at level of detail `lod`); `largest`:
 *  the largest CPU value; `fromNearest`, when given: the largest difference between the CPU
 *  value and what the nearest texel alone would give, how far a render without filtering would
 *  be off. */
double compare(const Material& material, const Rendered& r,
               const std::vector<std::vector<float>>& folded, const glm::vec3& view, float exposure,
               double* largest, float scale = 1.0f, double* fromNearest = nullptr,
               float lod = 0.0f) {
    double worst = 0;
    *largest = 0;
    if (fromNearest) *fromNearest = 0;
    for (int y = 0; y < r.size; ++y)
        for (int x = 0; x < r.size; ++x) {
            // Barycentric coordinates on the square; texture coordinates scaled.
            const float px = (x + 0.5f) / r.size, py = (y + 0.5f) / r.size;
            const std::array<float, 4> b = barycentric(px, py);
            const float u = scale * px, v = scale * py;
            const glm::vec3 expected =
                expectedPixel(material, folded, view, exposure, scale, lod, x, y, r.size);
            glm::vec3 nearest(0.0f);
            const int tx = int(u * 4) % 4, ty = int(v * 4) % 4;
            for (int k = 0; k < 4; ++k)
                if (b[k] > 0.0f)
                    nearest += b[k] * evaluateFolded(material, folded[k], tx, ty, view);
            nearest *= exposure;
            for (int ch = 0; ch < 3; ++ch) {
                worst = std::max(worst,
                                 double(std::abs(test::pixel(*r.image, x, y, ch) - expected[ch])));
                *largest = std::max(*largest, double(std::abs(expected[ch])));
                if (fromNearest)
                    *fromNearest =
                        std::max(*fromNearest, double(std::abs(nearest[ch] - expected[ch])));
            }
        }
    return worst;
}

/** Per-texel values of a 4 x 4 material, [ty * 4 + tx]. */
using TexelValues = std::array<glm::vec3, 16>;

TexelValues texelValues(const std::function<glm::vec3(int, int)>& value) {
    TexelValues values;
    for (int ty = 0; ty < 4; ++ty)
        for (int tx = 0; tx < 4; ++tx) values[std::size_t(ty * 4 + tx)] = value(tx, ty);
    return values;
}

/** What pixel (x, y) of a size x size render of the square (texture scale 1) shows of a 4 x 4
 *  material whose texels alone show `values`: the blend of the four texels around the pixel
 *  centre with GL_LINEAR's weights, wrapping at the edges. */
glm::vec3 filteredPixel(const TexelValues& values, int x, int y, int size) {
    const BilinearTaps taps((x + 0.5f) / float(size), (y + 0.5f) / float(size), 4, 4);
    glm::vec3 value(0.0f);
    for (int k = 0; k < 4; ++k)
        value += taps.weight[k] * values[std::size_t(taps.y[k] * 4 + taps.x[k])];
    return value;
}

}  // namespace

TEST(EnvironmentGpu, FoldedPcaBlendedAcrossTrianglesMatchesTheCpu) {
    // Four vertices with different environments: what the fragment stage blends must be each
    // vertex's own data. Float sums of ~100 products in a different order: 1e-4 relative.
    std::mt19937 rng(3);
    std::uniform_real_distribution<float> uniform(0.0f, 0.05f);
    std::vector<std::vector<float>> folded;
    for (int v = 0; v < 4; ++v) {
        std::vector<glm::vec3> g(pca().lights().size());
        for (glm::vec3& x : g) x = glm::vec3(uniform(rng), uniform(rng), uniform(rng));
        g[std::size_t(v) * 7] *= 40.0f;  // one strong direction per vertex
        folded.push_back(foldEnvironment(pca(), g));
    }
    for (const glm::vec3& view : {glm::vec3(0, 0, 1), glm::normalize(glm::vec3(0.5f, -0.3f, 0.6f))})
        for (float exposure : {1.0f, 0.25f}) {
            const Rendered r = render(pca(), folded, view, exposure);
            double largest = 0;
            const double worst = compare(pca(), r, folded, view, exposure, &largest);
            EXPECT_GT(largest, 0.01);
            EXPECT_LE(worst, 1e-4 * largest) << "view " << view.x << " exposure " << exposure;
        }
}

TEST(EnvironmentGpu, FoldedFmfAndLpcaMatchTheCpu) {
    // fmf (u* per view, dotted with SxV) and lpca (g per vertex folded into the cluster's
    // Eigen-BRDFs per fragment), four vertices with different environments, against the CPU
    // evaluateFolded blended with the same barycentric weights; evaluateFolded equals the exact
    // evaluateProjected (tests/environment_test.cpp). Float sums of ~100-250 products in another
    // order (lpca: light-outer): 1e-4 of the largest value.
    std::mt19937 rng(5);
    std::uniform_real_distribution<float> uniform(0.0f, 0.05f);
    for (const Material* m :
         {static_cast<const Material*>(&fmf()), static_cast<const Material*>(&lpca())}) {
        std::vector<std::vector<float>> folded;
        for (int v = 0; v < 4; ++v) {
            std::vector<glm::vec3> g(m->lights().size());
            for (glm::vec3& x : g) x = glm::vec3(uniform(rng), uniform(rng), uniform(rng));
            g[std::size_t(v) * 9 + 2] *= 40.0f;
            folded.push_back(foldEnvironment(*m, g));
        }
        const glm::vec3 view = glm::normalize(glm::vec3(0.4f, 0.2f, 0.7f));
        const Rendered r = render(*m, folded, view, 0.5f);
        double largest = 0;
        const double worst = compare(*m, r, folded, view, 0.5f, &largest);
        EXPECT_GT(largest, 0.01) << m->methodName();
        EXPECT_LE(worst, 1e-4 * largest) << m->methodName();
    }
}

TEST(EnvironmentGpu, FoldedLightingBlendsTheFourTexelsAroundAFragment) {
    // Texture scale 2: 4 pixels per texel (pixel centres at 1/8, 3/8, 5/8, 7/8 of a texel, none
    // on a centre), u and v pass 1 in the middle of the square (the last column blends with the
    // first across the wrap), and the bands left of and below the first centres blend with the
    // last column and row. Every method with folded lighting, each vertex its own environment,
    // against evaluateFoldedFiltered within the tests' bound above (1e-4 of the largest value);
    // the nearest texel alone would be off by far more.
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> uniform(0.0f, 0.05f);
    std::vector<std::string> covered;
    std::vector<const Material*> materials = {&pca(), &fmf(), &lpca()};
    // Any other method with folded lighting (the test-only "dummy" of tests/DummyMethod.cpp, which
    // the GL tests link, or a new method): its quick fit of the same sample, so none goes
    // unchecked; after the three above, whose environments stay those of the rng's first draws.
    std::vector<osg::ref_ptr<Material>> others;
    for (const std::string& name : methodNames())
        if (hasFoldedEnvironment(name) && name != "pca" && name != "fmf" && name != "lpca") {
            const MethodInfo& method = findMethod(name);
            others.push_back(method.fit(sample4(), FitOptions::parse(method.quickFitOptions)));
            materials.push_back(others.back().get());
        }
    for (const Material* m : materials) {
        ASSERT_TRUE(foldsEnvironment(*m)) << m->methodName();
        covered.push_back(m->methodName());
        std::vector<std::vector<float>> folded;
        for (int v = 0; v < 4; ++v) {
            std::vector<glm::vec3> g(m->lights().size());
            for (glm::vec3& x : g) x = glm::vec3(uniform(rng), uniform(rng), uniform(rng));
            g[std::size_t(v) * 9 + 4] *= 40.0f;
            folded.push_back(foldEnvironment(*m, g));
        }
        const glm::vec3 view = glm::normalize(glm::vec3(0.3f, -0.2f, 0.8f));
        const float scale = 2.0f;
        const Rendered r = render(*m, folded, view, 1.0f, scale);
        double largest = 0, fromNearest = 0;
        const double worst = compare(*m, r, folded, view, 1.0f, &largest, scale, &fromNearest);
        EXPECT_GT(largest, 0.01) << m->methodName();
        EXPECT_LE(worst, 1e-4 * largest) << m->methodName();
        EXPECT_GT(fromNearest, 1e-2 * largest) << m->methodName();
        std::cout << m->methodName() << " environment, magnified x4 across the wrap: GPU vs CPU "
                  << worst << " of largest " << largest << " (nearest texel off by " << fromNearest
                  << ")\n";
    }
    for (const std::string& name : methodNames()) {
        if (hasFoldedEnvironment(name)) {
            EXPECT_NE(std::find(covered.begin(), covered.end(), name), covered.end()) << name;
        }
    }
}

TEST(EnvironmentGpu, MinifiedMipMappedLightingBlendsTwoLevelsBilinearly) {
    // Mip-mapped pca, fmf and lpca of an 8 x 8 base under the shared StateSet's mip uniforms, at
    // texture scale 12: 3 base texels per pixel, lod log2(3) = 1.58 between level 1 (4 x 4
    // texels) and level 2 (2 x 2), pixel centres between the texel centres of both (1.5 x + 0.25
    // of level 1's, 0.75 x - 0.125 of level 2's), so every fragment blends eight texels, as
    // btf_main.glsl does for point lights (MipMapGpu's MinifiedBetweenLevels test). Against
    // evaluateFoldedFiltered at that lod within the bound of the tests above; the base level
    // alone (the shader before mip-mapped environment lighting) would be off by far more.
    SampleOptions options;
    options.width = options.height = 8;
    const MeasuredBtf btf = makeSampleBtf(options);
    constexpr float kScale = 12.0f;
    const float lod = std::log2(kScale * 8.0f / 32.0f);
    std::mt19937 rng(13);
    std::uniform_real_distribution<float> uniform(0.0f, 0.05f);
    for (const std::string name : {"pca", "fmf", "lpca"}) {
        const MethodInfo& method = findMethod(name);
        const osg::ref_ptr<Material> m =
            fitMipMapped(method, btf, FitOptions::parse(method.quickFitOptions));
        ASSERT_EQ(m->mipLayout().levelCount(), 4) << name;
        ASSERT_TRUE(foldsEnvironment(*m)) << name;
        std::vector<std::vector<float>> folded;
        for (int v = 0; v < 4; ++v) {
            std::vector<glm::vec3> g(m->lights().size());
            for (glm::vec3& x : g) x = glm::vec3(uniform(rng), uniform(rng), uniform(rng));
            g[std::size_t(v) * 9 + 4] *= 40.0f;
            folded.push_back(foldEnvironment(*m, g));
        }
        const glm::vec3 view = glm::normalize(glm::vec3(-0.3f, 0.4f, 0.8f));
        const Rendered r = render(*m, folded, view, 1.0f, kScale);
        double largest = 0;
        const double worst = compare(*m, r, folded, view, 1.0f, &largest, kScale, nullptr, lod);
        double fromBase = 0;
        for (int y = 0; y < r.size; ++y)
            for (int x = 0; x < r.size; ++x) {
                const glm::vec3 d =
                    expectedPixel(*m, folded, view, 1.0f, kScale, lod, x, y, r.size) -
                    expectedPixel(*m, folded, view, 1.0f, kScale, 0.0f, x, y, r.size);
                for (int ch = 0; ch < 3; ++ch)
                    fromBase = std::max(fromBase, double(std::abs(d[ch])));
            }
        std::cout << name << " environment, minified between mip levels 1 and 2: GPU vs CPU "
                  << worst << " of largest " << largest << " (base level alone off by " << fromBase
                  << ")\n";
        EXPECT_GT(largest, 0.01) << name;
        EXPECT_LE(worst, 1e-4 * largest) << name;
        // The test would see a shader that reads level 0 alone.
        EXPECT_GT(fromBase, 1e-2 * largest) << name;
    }
}

TEST(EnvironmentGpu, WhiteEnvironmentEqualsTheIntegralOfPointLights) {
    // constant white environment, no occlusion: the GPU image equals sum_i dOmega_i
    // BTF(x, v, l_i), i.e. the CPU's integral of the point-light rendering over the hemisphere.
    const EnvironmentMap white = uniformMap(64, 1.0f);
    const std::vector<EnvironmentSample> samples = visibleEnvironment(white, SurfaceFrame{});
    const std::vector<float> f =
        foldEnvironment(pca(), projectEnvironment(samples, DirectionInterpolator(pca().lights())));
    const std::vector<std::vector<float>> folded(4, f);
    const glm::vec3 view = glm::normalize(glm::vec3(-0.2f, 0.4f, 0.7f));
    const Rendered r = render(pca(), folded, view, 1.0f);
    // Each texel's integral; a pixel shows the blend of the four texels around it.
    const TexelValues integrals = texelValues(
        [&](int tx, int ty) { return environmentReference(pca(), tx, ty, view, samples); });
    double largest = 0;
    for (int ty = 0; ty < 4; ++ty)
        for (int tx = 0; tx < 4; ++tx) {
            const int x = tx * 8 + 4, y = ty * 8 + 3;
            const glm::vec3 expected = filteredPixel(integrals, x, y, r.size);
            for (int ch = 0; ch < 3; ++ch) {
                largest = std::max(largest, double(expected[ch]));
                EXPECT_NEAR(test::pixel(*r.image, x, y, ch), expected[ch],
                            1e-4 * expected[ch] + 1e-6)
                    << "texel " << tx << ", " << ty << " channel " << ch;
            }
        }
    EXPECT_GT(largest, 0.01);
}

TEST(EnvironmentGpu, OneBrightTexelDrawsThePointLightImage) {
    // one bright texel centred on the measured direction (45, 0) (a 108 x 54 map
    // turned by half a column) gives the image of a point light there of intensity L Omega: the
    // CPU point-light evaluation, which the pca GL tests match on the GPU.
    const int index = pca().lights().find(45.0f, 0.0f);
    ASSERT_GE(index, 0);
    EnvironmentMap map;
    map.width = 108;
    map.height = 54;
    map.rgb.assign(108 * 54 * 3, 0.0f);
    map.rotationDegrees = -360.0f * 0.5f / 108.0f;
    const int row = 54 - 1 - 13;
    const glm::vec3 radiance(50.0f, 20.0f, 10.0f);
    for (int ch = 0; ch < 3; ++ch) map.rgb[std::size_t(row) * 108 * 3 + ch] = radiance[ch];
    const std::vector<glm::vec3> g = projectEnvironment(visibleEnvironment(map, SurfaceFrame{}),
                                                        DirectionInterpolator(pca().lights()));
    const std::vector<std::vector<float>> folded(4, foldEnvironment(pca(), g));
    const glm::vec3 view = glm::normalize(glm::vec3(0.3f, 0.3f, 0.8f));
    const Rendered r = render(pca(), folded, view, 1.0f);
    const float omega = float(map.solidAngle(row));
    const TexelValues pointLights = texelValues([&](int tx, int ty) {
        return radiance * omega * pca().evaluate(tx, ty, view, pca().lights().vector(index));
    });
    for (int ty = 0; ty < 4; ++ty)
        for (int tx = 0; tx < 4; ++tx) {
            const glm::vec3 pointLight = filteredPixel(pointLights, tx * 8 + 4, ty * 8 + 3, r.size);
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(test::pixel(*r.image, tx * 8 + 4, ty * 8 + 3, ch), pointLight[ch],
                            1e-4 * glm::length(pointLight) + 1e-6)
                    << "texel " << tx << ", " << ty << " channel " << ch;
        }
}

TEST(EnvironmentGpu, MaterialNodeSceneLitByApplyEnvironmentLighting) {
    // End to end: a MaterialNode over the square, applyEnvironmentLighting with a white
    // environment, seen straight from above (view +Z everywhere): each texel equals the CPU
    // integral of the point-light rendering; a new exposure shows without recomputation.
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    const EnvironmentMap white = uniformMap(64, 1.0f);
    light->setMap(white);
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->setMaterial(const_cast<PcaMaterial*>(&pca()));
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(trianglePatch());
    node->addChild(geode);
    // A rectified image of the same method first, its view fixed at 60 degrees: GL keeps a
    // program's uniform values until they are set again, so environmentStateSet sets the real
    // eye direction (osgBTF_fixedView w = 0) that the renders below need.
    renderEnvironmentImage(test::sharedRenderer(), pca(), projectPatchEnvironment(pca(), white),
                           Direction{60, 30}.toVector());
    std::size_t reports = 0;
    VertexEnvironmentOptions options;
    options.progress = [&](std::size_t, std::size_t) { ++reports; };
    EXPECT_EQ(applyEnvironmentLighting(*node, node.get(), pca(), *light, options), 1u);
    EXPECT_EQ(reports, 4u);
    const std::vector<EnvironmentSample> samples = visibleEnvironment(white, SurfaceFrame{});
    for (float exposure : {1.0f, 2.0f}) {
        light->setExposure(exposure);
        osg::ref_ptr<osg::Image> image =
            test::sharedRenderer().render(node, orthoUnitSquare(32, 32));
        const TexelValues integrals = texelValues([&](int tx, int ty) {
            return exposure * environmentReference(pca(), tx, ty, glm::vec3(0, 0, 1), samples);
        });
        for (int ty = 0; ty < 4; ++ty)
            for (int tx = 0; tx < 4; ++tx) {
                const glm::vec3 expected = filteredPixel(integrals, tx * 8 + 4, ty * 8 + 3, 32);
                for (int ch = 0; ch < 3; ++ch)
                    EXPECT_NEAR(test::pixel(*image, tx * 8 + 4, ty * 8 + 3, ch), expected[ch],
                                1e-4 * expected[ch] + 1e-6)
                        << "exposure " << exposure << " texel " << tx << ", " << ty;
            }
    }
}

/** The environment data installed in the StateSet of the one geometry below `node` against
 *  pca()'s folded data of `map` computed here without occlusion, texel by texel. */
void expectInstalledDataUnoccluded(osg::Node& node, const EnvironmentMap& map,
                                   const std::string& what) {
    VertexEnvironmentOptions unoccluded;
    unoccluded.visibility = false;
    const std::vector<GeometryEnvironment> direct =
        computeVertexEnvironment(node, &node, pca().lights(), map, unoccluded);
    ASSERT_EQ(direct.size(), 1u);
    std::vector<std::vector<float>> folded;
    for (const auto& g : direct[0].g) folded.push_back(foldEnvironment(pca(), g));
    const osg::ref_ptr<osg::StateSet> expected = environmentStateSet(pca(), folded);
    const osg::StateSet* installed = direct[0].geometry->getStateSet();
    ASSERT_NE(installed, nullptr) << what;
    int compared = 0;
    for (unsigned unit = 0; unit < expected->getTextureAttributeList().size(); ++unit) {
        const auto* want = dynamic_cast<const osg::Texture2D*>(
            expected->getTextureAttribute(unit, osg::StateAttribute::TEXTURE));
        const auto* got = dynamic_cast<const osg::Texture2D*>(
            installed->getTextureAttribute(unit, osg::StateAttribute::TEXTURE));
        if (!want || !want->getImage()) continue;
        ASSERT_TRUE(got && got->getImage()) << what << ", unit " << unit;
        const osg::Image& a = *want->getImage();
        const osg::Image& b = *got->getImage();
        ASSERT_EQ(a.getTotalSizeInBytes(), b.getTotalSizeInBytes());
        const float* pa = reinterpret_cast<const float*>(a.data());
        const float* pb = reinterpret_cast<const float*>(b.data());
        double largest = 0, worst = 0;
        for (std::size_t i = 0; i < a.getTotalSizeInBytes() / sizeof(float); ++i) {
            largest = std::max(largest, double(std::abs(pa[i])));
            worst = std::max(worst, double(std::abs(pa[i] - pb[i])));
        }
        EXPECT_LE(worst, 1e-4 * largest)
            << what << ", unit " << unit << " first values " << pa[0] << " " << pa[1] << " "
            << pa[2] << " / " << pb[0] << " " << pb[1] << " " << pb[2];
        ++compared;
    }
    EXPECT_GT(compared, 0) << what;
}

TEST(EnvironmentGpu, EnvironmentLitGroupLightsItsMaterialNodesByItself) {
    // The scene of the test above, but under an EnvironmentLitGroup and no call into the
    // library: an update traversal starts the work, finish() installs it, the render equals
    // the CPU integral; a non-folding material goes back to its own StateSet and the group's
    // representative lights; a serialized group keeps its settings and children.
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    const EnvironmentMap white = uniformMap(64, 1.0f);
    light->setMap(white);
    osg::ref_ptr<EnvironmentLitGroup> group = new EnvironmentLitGroup;
    group->setLight(light.get());
    group->setRepresentativeLights(4);
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->setMaterial(const_cast<PcaMaterial*>(&pca()));
    osg::ref_ptr<osg::Geometry> geometry = trianglePatch();
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(geometry);
    node->addChild(geode);
    group->addChild(node);
    ASSERT_EQ(geometry->getStateSet(), nullptr);

    osgUtil::UpdateVisitor update;
    group->accept(update);
    EXPECT_TRUE(group->computing());
    group->finish();
    EXPECT_FALSE(group->computing());
    EXPECT_EQ(group->getError(), "");
    ASSERT_NE(geometry->getStateSet(), nullptr);
    const std::vector<EnvironmentSample> samples = visibleEnvironment(white, SurfaceFrame{});
    osg::ref_ptr<osg::Image> image = test::sharedRenderer().render(group, orthoUnitSquare(32, 32));
    const TexelValues integrals = texelValues([&](int tx, int ty) {
        return environmentReference(pca(), tx, ty, glm::vec3(0, 0, 1), samples);
    });
    for (int ty = 0; ty < 4; ++ty)
        for (int tx = 0; tx < 4; ++tx) {
            const glm::vec3 expected = filteredPixel(integrals, tx * 8 + 4, ty * 8 + 3, 32);
            for (int ch = 0; ch < 3; ++ch)
                EXPECT_NEAR(test::pixel(*image, tx * 8 + 4, ty * 8 + 3, ch), expected[ch],
                            1e-4 * expected[ch] + 1e-6)
                    << "texel " << tx << ", " << ty;
        }
    // Nothing changed: an update starts nothing. A new rotation does.
    group->accept(update);
    EXPECT_FALSE(group->computing());
    light->setRotation(30.0f);
    group->accept(update);
    EXPECT_TRUE(group->computing());
    group->finish();

    // lambert has no folded lighting: its own StateSet (none here) and the representative lights.
    node->setMaterial(findMethod("lambert").fit(sample4(), FitOptions::parse("")).get());
    group->accept(update);
    group->finish();
    EXPECT_EQ(geometry->getStateSet(), nullptr);
    struct CountLights : osg::NodeVisitor {
        CountLights() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
        void apply(osg::LightSource& source) override {
            ++count;
            traverse(source);
        }
        int count = 0;
    } lights;
    group->accept(lights);
    EXPECT_EQ(lights.count, 4);

    const std::string file = (std::filesystem::temp_directory_path() /
                              ("osgbtf-lit-" + std::to_string(getpid()) + ".osgt"))
                                 .string();
    ASSERT_TRUE(osgDB::writeNodeFile(*group, file));
    struct Remove {
        std::string file;
        ~Remove() { std::remove(file.c_str()); }
    } remove{file};
    osg::ref_ptr<EnvironmentLitGroup> read =
        dynamic_cast<EnvironmentLitGroup*>(osgDB::readNodeFile(file));
    ASSERT_NE(read, nullptr);
    EXPECT_EQ(read->getRepresentativeLights(), 4);
    EXPECT_TRUE(read->getVisibility());
    ASSERT_NE(read->getLight(), nullptr);
    EXPECT_FLOAT_EQ(read->getLight()->getRotation(), 30.0f);
    EXPECT_EQ(read->getNumChildren(), 1u);
    // Its map was in memory, not a file: the group says so once and lights nothing.
    read->finish();
    EXPECT_EQ(read->getError(), "the EnvironmentLight has no map");
}

TEST(EnvironmentGpu, EnvironmentLitGroupRebuildsRotationsFromItsIlluminationPca) {
    // A map with a bright patch (so rotation matters), 4 rotation samples and 3 components: the
    // centred samples span at most 3 dimensions, so the PCA is exact at the samples. Turning the
    // light to a sample's rotation (90 degrees) rebuilds the data in the update traversal, no
    // worker, and the render equals the CPU integral of the map turned by 90 degrees.
    EnvironmentMap map = uniformMap(32, 0.2f);
    for (int c = 2; c < 6; ++c)
        for (int r = 10; r < 13; ++r)  // rows bottom-up: above the horizon
            for (int ch = 0; ch < 3; ++ch) map.rgb[(r * 32 + c) * 3 + ch] = 4.0f + float(ch);
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    light->setMap(map);
    osg::ref_ptr<EnvironmentLitGroup> group = new EnvironmentLitGroup;
    group->setLight(light.get());
    group->setVisibility(false);
    group->setRotationSamples(4);
    group->setRotationComponents(3);
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->setMaterial(const_cast<PcaMaterial*>(&pca()));
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(trianglePatch());
    node->addChild(geode);
    group->addChild(node);
    group->finish();
    ASSERT_EQ(group->getError(), "");
    EXPECT_LT(group->lastRebuildMilliseconds(), 0.0 + 1e9);  // rebuilt once when installed

    osgUtil::UpdateVisitor update;
    for (float degrees : {90.0f, 0.0f}) {
        light->setRotation(degrees);
        group->accept(update);
        EXPECT_FALSE(group->computing()) << "a rotation is rebuilt, not computed again";
        EnvironmentMap turned = map;
        turned.rotationDegrees = degrees;
        // The rebuilt per-vertex data against the folded data computed at that rotation.
        expectInstalledDataUnoccluded(*node, turned, std::to_string(degrees) + " degrees");
        const std::vector<EnvironmentSample> samples = visibleEnvironment(turned, SurfaceFrame{});
        osg::ref_ptr<osg::Image> image =
            test::sharedRenderer().render(group, orthoUnitSquare(32, 32));
        const TexelValues integrals = texelValues([&](int tx, int ty) {
            return environmentReference(pca(), tx, ty, glm::vec3(0, 0, 1), samples);
        });
        double largest = 0;
        for (int ty = 0; ty < 4; ++ty)
            for (int tx = 0; tx < 4; ++tx) {
                const glm::vec3 expected = filteredPixel(integrals, tx * 8 + 4, ty * 8 + 3, 32);
                for (int ch = 0; ch < 3; ++ch) {
                    largest = std::max(largest, double(expected[ch]));
                    EXPECT_NEAR(test::pixel(*image, tx * 8 + 4, ty * 8 + 3, ch), expected[ch],
                                1e-3 * expected[ch] + 1e-5)
                        << degrees << " degrees, texel " << tx << ", " << ty;
                }
            }
        EXPECT_GT(largest, 0.0);
    }
    EXPECT_GE(group->lastRebuildMilliseconds(), 0.0);
}

TEST(EnvironmentGpu, EnvironmentLitGroupPlacesMaterialNodesUnderTransformsWhereTheyAre) {
    // A MaterialNode moved 100 units along +X by a transform inside the group, and a roof just
    // over the origin: the node's square, where it is drawn, sees the whole sky (the roof is
    // 0.03 degrees above its horizon). Computed without
    // the transform (as applyEnvironmentLighting on the node alone would), its vertices would lie
    // under the roof and see nothing above.
    const EnvironmentMap white = uniformMap(32, 1.0f);
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    light->setMap(white);
    osg::ref_ptr<EnvironmentLitGroup> group = new EnvironmentLitGroup;
    group->setLight(light.get());
    osg::ref_ptr<osg::Geometry> roof = trianglePatch();
    osg::ref_ptr<osg::Vec3Array> corners = new osg::Vec3Array;
    for (const osg::Vec3& c : {osg::Vec3(-1, -1, 0.05f), osg::Vec3(2, -1, 0.05f),
                               osg::Vec3(2, 2, 0.05f), osg::Vec3(-1, 2, 0.05f)})
        corners->push_back(c);
    roof->setVertexArray(corners.get());
    osg::ref_ptr<osg::Geode> roofGeode = new osg::Geode;
    roofGeode->addDrawable(roof);
    group->addChild(roofGeode);
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->setMaterial(const_cast<PcaMaterial*>(&pca()));
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(trianglePatch());
    node->addChild(geode);
    osg::ref_ptr<osg::MatrixTransform> moved =
        new osg::MatrixTransform(osg::Matrix::translate(100, 0, 0));
    moved->addChild(node);
    group->addChild(moved);
    group->finish();
    ASSERT_EQ(group->getError(), "");
    expectInstalledDataUnoccluded(*node, white, "moved square");
}

TEST(EnvironmentGpu, RepresentativeLightsAreOccludedPerVertex) {
    // lambert has no folded lighting: one representative light carries the map, a bright patch
    // low in the +X direction. A wall beside the square (outside the camera's view) hides that
    // light from every vertex: the square goes black; without the wall, or with the group's
    // visibility off, it is lit, and the same in both.
    EnvironmentMap map = uniformMap(32, 0.0f);
    for (int r = 9; r < 11; ++r)  // rows bottom-up: elevations 11 to 34 degrees
        for (int c : {0, 31})     // azimuth about 0: toward +X
            for (int ch = 0; ch < 3; ++ch) map.rgb[(r * 32 + c) * 3 + ch] = 100.0f;
    osg::ref_ptr<EnvironmentLight> light = new EnvironmentLight;
    light->setMap(map);
    osg::ref_ptr<EnvironmentLitGroup> group = new EnvironmentLitGroup;
    group->setLight(light.get());
    group->setRepresentativeLights(1);
    osg::ref_ptr<MaterialNode> node = new MaterialNode;
    node->setMaterial(findMethod("lambert").fit(sample4(), FitOptions::parse("")).get());
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(trianglePatch());
    node->addChild(geode);
    group->addChild(node);
    osg::ref_ptr<osg::Geometry> wall = trianglePatch();
    osg::ref_ptr<osg::Vec3Array> corners = new osg::Vec3Array;
    for (const osg::Vec3& c : {osg::Vec3(1.5f, -2, -0.1f), osg::Vec3(1.5f, 3, -0.1f),
                               osg::Vec3(1.5f, 3, 2), osg::Vec3(1.5f, -2, 2)})
        corners->push_back(c);
    wall->setVertexArray(corners.get());
    osg::ref_ptr<osg::Geode> wallGeode = new osg::Geode;
    wallGeode->addDrawable(wall);
    group->addChild(wallGeode);

    const auto brightest = [&] {
        group->finish();
        EXPECT_EQ(group->getError(), "");
        osg::ref_ptr<osg::Image> image =
            test::sharedRenderer().render(group, orthoUnitSquare(16, 16));
        float largest = 0;
        for (int y = 0; y < 16; ++y)
            for (int x = 0; x < 16; ++x)
                for (int ch = 0; ch < 3; ++ch)
                    largest = std::max(largest, test::pixel(*image, x, y, ch));
        return largest;
    };
    EXPECT_EQ(brightest(), 0.0f) << "the wall hides the only light";
    group->setVisibility(false);
    const float unoccluded = brightest();
    EXPECT_GT(unoccluded, 0.01f);
    group->setVisibility(true);
    group->removeChild(wallGeode);
    EXPECT_NEAR(brightest(), unoccluded, 1e-5f * unoccluded) << "without the wall";
}

TEST(EnvironmentGpu, PatchImagesOfFoldedAndOtherMethodsMatchTheCpu) {
    // btf eval --env's images (harness/MaterialImage.h): fmf through its folded program, lambert
    // (no folding) as the g-weighted sum of its point-light renders, both against the CPU's
    // sum_i g_i BTF(x, v, l_i) times the exposure. Float sums of ~81 terms: 1e-4 of the largest.
    EnvironmentMap sky = uniformMap(16, 0.2f);
    for (int c = 0; c < 4; ++c)
        for (int ch = 0; ch < 3; ++ch) sky.rgb[(6 * 16 + c) * 3 + ch] = 5.0f * float(ch + 1);
    const osg::ref_ptr<Material> lambert =
        findMethod("lambert").fit(sample4(), FitOptions::parse(""));
    const glm::vec3 view = glm::normalize(glm::vec3(0.2f, 0.3f, 0.9f));
    for (const Material* m :
         {static_cast<const Material*>(&fmf()), static_cast<const Material*>(lambert.get())}) {
        const std::vector<glm::vec3> g = projectPatchEnvironment(*m, sky);
        const FloatImage cpu = evaluateEnvironmentImage(*m, g, view, 0.5f);
        const FloatImage gpu = renderEnvironmentImage(test::sharedRenderer(), *m, g, view, 0.5f);
        float largest = 0;
        for (float v : cpu.pixels) largest = std::max(largest, std::abs(v));
        EXPECT_GT(largest, 0.01f) << m->methodName();
        EXPECT_LE(maxAbsDifference(gpu, cpu), 1e-4 * largest) << m->methodName();
    }
}

}  // namespace OSGBTF_TEST_FILE
