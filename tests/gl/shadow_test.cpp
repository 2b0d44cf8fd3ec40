// Sattler et al. 2003 sec. 4.3 on the GPU: the smooth shadow terminator (GPU factor == CPU
// reference, no jump along a path of light angles, off and alpha = 0 reproduce the image without
// it) and cast shadows through osgShadow::ShadowedScene + ShadowMap (a box over the patch: the
// shadowed light is gone exactly where the box hides it, and nothing else changes), the same under
// SoftShadowMap and ViewDependentShadowMap, and unshadowed with one notice under other techniques.
// Built twice (EGL and OSMesa).
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <mutex>
#include <sstream>

#include <gtest/gtest.h>

#include <glm/geometric.hpp>
#include <osg/Geode>
#include <osg/Light>
#include <osg/LightSource>
#include <osg/ShapeDrawable>
#include <osg/Texture2D>
#include <osgShadow/ShadowMap>
#include <osgShadow/ShadowSettings>
#include <osgShadow/ShadowTexture>
#include <osgShadow/ShadowedScene>
#include <osgShadow/SoftShadowMap>
#include <osgShadow/ViewDependentShadowMap>
#include <osgUtil/CullVisitor>

#include "core/Directions.h"
#include "harness/ShadowScene.h"
#include "harness/sample/SampleBtf.h"
#include "materials/CoordinateMapRendering.h"
#include "materials/MethodOptions.h"
#include "materials/MethodPrograms.h"
#include "materials/lambert/Lambert.h"
#include "materials/pca/Pca.h"
#include "scene/MaterialNode.h"
#include "scene/ShadowTerminator.h"
#include "tests/NotifyCapture.h"
#include "tests/gl/GlTestEnv.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

/** A lambert material whose albedo is `rho` everywhere: the pixel is rho * l_z * factor, so the
 *  image shows the terminator factor itself. */
osg::ref_ptr<LambertMaterial> constantLambert(float rho) {
    SampleOptions sample;
    sample.width = 4;
    sample.height = 4;
    osg::ref_ptr<LambertMaterial> material = LambertMaterial::fit(makeSampleBtf(sample), {});
    material->albedo = StoredValues(MaterialTexture::Half, material->albedo.size(), rho);
    return material;
}

osg::ref_ptr<PcaMaterial> pcaSample() {
    SampleOptions sample;
    sample.width = 8;
    sample.height = 6;
    return PcaMaterial::fit(makeSampleBtf(sample), FitOptions::parse("components=4 storage=float"));
}

osg::ref_ptr<osg::LightSource> lightSource(int number, const osg::Vec4& position,
                                           const osg::Vec3& color = osg::Vec3(1, 1, 1)) {
    osg::ref_ptr<osg::Light> light = new osg::Light(number);
    light->setPosition(position);
    light->setDiffuse(osg::Vec4(color, 1));
    osg::ref_ptr<osg::LightSource> source = new osg::LightSource;
    source->setLight(light.get());
    return source;
}

/** Directional light at `thetaDeg` from the patch normal (+Z), in the XZ plane. */
osg::Vec4 directionAt(double thetaDeg) {
    const double t = osg::DegreesToRadians(thetaDeg);
    return osg::Vec4(float(std::sin(t)), 0.0f, float(std::cos(t)), 0.0f);
}

osg::ref_ptr<MaterialNode> patchNode(Material* material) {
    osg::ref_ptr<MaterialNode> node = new MaterialNode(material);
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(createFullScreenQuadGeometry().get());
    node->addChild(geode.get());
    return node;
}

float centre(const osg::Image& image, int channel = 0) {
    return pixel(image, image.s() / 2, image.t() / 2, channel);
}

double maxValue(const osg::Image& a) {
    const float* pa = reinterpret_cast<const float*>(a.data());
    return *std::max_element(pa, pa + a.s() * a.t() * 4);
}

}  // namespace

TEST(ShadowTerminatorGpu, FactorEqualsTheCpuReference) {
    // A flat patch under a directional light: every vertex has the same u, so each pixel is
    // rho * l_z * terminatorFactor(u) with no interpolation in between.
    const float rho = 0.5f;
    osg::ref_ptr<MaterialNode> node = patchNode(constantLambert(rho).get());
    const PatchView camera = patchViewFrom(10, 0, 8, 0.3);
    // Tolerance from the method, not from its output: GLSL acos/cos of float arguments, allowed
    // here 1e-4 rad, times the steepest slope of the factor in angle (smoothstep 1.5 / softness
    // in u, u changing by at most 1/2 per radian), plus 8-bit fixed-point filter weights on GPUs
    // (llvmpipe's are float): the largest step between two texels over 256.
    const std::vector<float> texels = terminatorTexels(kDefaultTerminatorSoftness);
    float texelStep = 0;
    for (std::size_t i = 1; i < texels.size(); ++i)
        texelStep = std::max(texelStep, std::abs(texels[i] - texels[i - 1]));
    const double tolerance =
        rho * (1e-4 * 0.5 * 1.5 / kDefaultTerminatorSoftness + texelStep / 256.0) + 1e-6;
    int inRamp = 0;
    for (double theta : {40.0, 68.0, 71.0, 73.5, 75.0, 77.0, 79.0, 82.0, 88.0}) {
        osg::ref_ptr<osg::Group> root = new osg::Group;
        root->addChild(lightSource(0, directionAt(theta)).get());
        root->addChild(node.get());
        osg::ref_ptr<osg::Image> image = sharedRenderer().render(root.get(), camera.setup);
        const osg::Vec4 l = directionAt(theta);
        const glm::vec3 toLight(l.x(), l.y(), l.z());
        const float u = terminatorCoordinate(glm::vec3(0, 0, 1), glm::normalize(toLight),
                                             kDefaultTerminatorAlpha);
        const float factor = terminatorFactor(u, kDefaultTerminatorSoftness);
        if (factor > 0.01f && factor < 0.99f) ++inRamp;
        const double expected = rho * toLight.z * factor;
        EXPECT_NEAR(centre(*image), expected, tolerance) << "theta " << theta << " u " << u;
    }
    EXPECT_GE(inRamp, 4);  // the angles above do test the blurred part, not only 0 and 1
}

TEST(ShadowTerminatorGpu, NoJumpAlongAPathOfLightAngles) {
    // The light turns from 50 to 95 degrees in 1 degree steps over the pca sample (whose value
    // near the horizon is far from 0: the measured data stop at 75 degrees). The rendered value is
    // F(theta) * B(theta) (F the factor, B the BTF, 0 past 90 degrees); per step it may change by
    // at most step * (max|F'| * max B + max|B'|) + 2 * (GPU - CPU rounding), F' bounded by the
    // smoothstep's 1.5 / softness times |du/dtheta| <= 1/2, max B and max|B'| taken from the CPU
    // evaluator over every texel along the same path (B' by differences on a 0.1 degree grid).
    osg::ref_ptr<PcaMaterial> material = pcaSample();
    const glm::vec3 view = Direction{10, 0}.toVector();
    double maxB = 0, maxSlope = 0;
    for (int y = 0; y < material->height(); ++y)
        for (int x = 0; x < material->width(); ++x) {
            glm::vec3 previous(0);
            for (double theta = 50; theta < 89.95; theta += 0.1) {
                const osg::Vec4 l = directionAt(theta);
                const glm::vec3 b = material->evaluate(x, y, view, glm::vec3(l.x(), l.y(), l.z()));
                for (int c = 0; c < 3; ++c) {
                    maxB = std::max(maxB, double(std::abs(b[c])));
                    if (theta > 50)
                        maxSlope = std::max(maxSlope, std::abs(double(b[c] - previous[c])) /
                                                          osg::DegreesToRadians(0.1));
                }
                previous = b;
            }
        }
    // A finite difference can underestimate the slope between grid points; 1.5x covers a smooth
    // curve's slope changing within 0.1 degrees.
    auto bound = [&](double stepDegrees) {
        return osg::DegreesToRadians(stepDegrees) *
                   (0.5 * 1.5 / kDefaultTerminatorSoftness * maxB + 1.5 * maxSlope) +
               2e-4;
    };

    const PatchView camera = patchViewFrom(10, 0, 8, 0.3);
    auto sweep = [&](bool terminator, double from, double to, double step) {
        osg::ref_ptr<MaterialNode> node = patchNode(material.get());
        node->setShadowTerminator(terminator);
        std::vector<float> values;
        for (double theta = from; theta <= to + 1e-9; theta += step) {
            osg::ref_ptr<osg::Group> root = new osg::Group;
            root->addChild(lightSource(0, directionAt(theta)).get());
            root->addChild(node.get());
            osg::ref_ptr<osg::Image> image = sharedRenderer().render(root.get(), camera.setup);
            values.push_back(centre(*image, 1));
        }
        return values;
    };
    const std::vector<float> on = sweep(true, 50, 95, 1.0);
    double worst = 0;
    for (std::size_t i = 1; i < on.size(); ++i)
        worst = std::max(worst, double(std::abs(on[i] - on[i - 1])));
    EXPECT_LE(worst, bound(1.0)) << "max B " << maxB << " max |B'| " << maxSlope;
    EXPECT_GT(worst, 0.1 * bound(1.0));  // the value does change along the path
    EXPECT_EQ(on.back(), 0.0f);
    // Without the terminator the value jumps at 90 degrees: a jump that no step makes smaller,
    // so at 0.1 degree steps it exceeds that step's bound many times (the check above can fail).
    auto largestStep = [](const std::vector<float>& values) {
        double largest = 0;
        for (std::size_t i = 1; i < values.size(); ++i)
            largest = std::max(largest, double(std::abs(values[i] - values[i - 1])));
        return largest;
    };
    EXPECT_GT(largestStep(sweep(false, 89.05, 90.95, 0.1)), 3 * bound(0.1));
    // With it, the same fine steps there and across the terminator's own band stay in bound.
    EXPECT_LE(largestStep(sweep(true, 89.05, 90.95, 0.1)), bound(0.1));
    EXPECT_LE(largestStep(sweep(true, 72.05, 76.95, 0.1)), bound(0.1));
}

TEST(ShadowTerminatorGpu, OffAndAlphaZeroReproduceTheImageWithoutIt) {
    // Lights at most 60 degrees from the normal (a directional one, a point light and a coloured
    // directional one): with alpha = 0 the factor is 1 up to acos(softness) = 84 degrees, with the
    // default 15 degrees up to 69 degrees, so every image equals the one without the terminator;
    // the filter's (1 - w) * 1 + w * 1 may round to 1 - 2^-24, hence a relative 1e-6.
    osg::ref_ptr<PcaMaterial> material = pcaSample();
    osg::ref_ptr<MaterialNode> node = patchNode(material.get());
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->addChild(lightSource(0, directionAt(35)).get());
    root->addChild(
        lightSource(1, osg::Vec4(0.3f, 0.9f, 1.1f, 1.0f), osg::Vec3(0.6f, 0.7f, 0.2f)).get());
    root->addChild(
        lightSource(2, osg::Vec4(-0.5f, -0.5f, 0.7071f, 0.0f), osg::Vec3(0.2f, 0.4f, 0.9f)).get());
    root->addChild(node.get());
    const PatchView camera = patchViewFrom(30, 60, 24, 0.6);

    node->setShadowTerminator(false);
    osg::ref_ptr<osg::Image> off = sharedRenderer().render(root.get(), camera.setup);
    node->setShadowTerminator(true);
    node->setTerminatorAlpha(0);
    osg::ref_ptr<osg::Image> alphaZero = sharedRenderer().render(root.get(), camera.setup);
    node->setTerminatorAlpha(kDefaultTerminatorAlpha);
    osg::ref_ptr<osg::Image> byDefault = sharedRenderer().render(root.get(), camera.setup);
    const double scale = maxValue(*off);
    ASSERT_GT(scale, 0.05);
    EXPECT_LE(maxDifference(*off, *alphaZero), 1e-6 * scale);
    EXPECT_LE(maxDifference(*off, *byDefault), 1e-6 * scale);
    // A light beyond 69 degrees does change the default image (the comparison can fail).
    root->addChild(lightSource(3, directionAt(78)).get());
    osg::ref_ptr<osg::Image> grazingOn = sharedRenderer().render(root.get(), camera.setup);
    node->setShadowTerminator(false);
    osg::ref_ptr<osg::Image> grazingOff = sharedRenderer().render(root.get(), camera.setup);
    EXPECT_GT(maxDifference(*grazingOn, *grazingOff), 100e-6 * scale);
}

TEST(ShadowTerminatorGpu, AMaterialsOwnStateSetIsWithoutItAfterANodeDrewIt) {
    // A GL program keeps the last value given to a uniform: after a MaterialNode drew with the
    // terminator on, the material's own StateSet (btf eval, btf compare, the GPU checks) must
    // still render the measured BTF, here at a light angle the terminator would darken to 0.
    osg::ref_ptr<LambertMaterial> material = constantLambert(0.5f);
    osg::ref_ptr<osg::Group> root = new osg::Group;
    root->addChild(lightSource(0, directionAt(85)).get());
    root->addChild(patchNode(material.get()).get());
    osg::ref_ptr<osg::Image> node =
        sharedRenderer().render(root.get(), patchViewFrom(10, 0, 8, 0.3).setup);
    EXPECT_EQ(centre(*node), 0.0f);
    const osg::Vec4 l = directionAt(85);
    const test::GpuCpuComparison r =
        test::compareGpuWithCpu(*material, Direction{10, 0}.toVector(), {l.x(), l.y(), l.z()});
    EXPECT_GT(r.pixelsCompared, 8);
    EXPECT_LE(r.maxAbsDifference, 1e-5) << r.worst;
}

namespace {

// The occluder: an axis-aligned box over the patch.
const osg::Vec3d kBoxMin(0.4, 0.35, 0.25), kBoxMax(0.6, 0.65, 0.35);

bool rayHitsBox(const osg::Vec3d& origin, const osg::Vec3d& direction) {
    double t0 = 0, t1 = 1e30;
    for (int a = 0; a < 3; ++a) {
        if (std::abs(direction[a]) < 1e-12) {
            if (origin[a] < kBoxMin[a] || origin[a] > kBoxMax[a]) return false;
            continue;
        }
        double ta = (kBoxMin[a] - origin[a]) / direction[a];
        double tb = (kBoxMax[a] - origin[a]) / direction[a];
        if (ta > tb) std::swap(ta, tb);
        t0 = std::max(t0, ta);
        t1 = std::min(t1, tb);
    }
    return t0 <= t1;
}

}  // namespace

/** Two directional lights, numbers 0 and 1; the technique shadows number 1, the last one
 *  unless `shadowedLightFirst` (its own choice when given none, and MaterialNode's default).
 *  Expected per pixel, from the geometry alone (a CPU ray test from the ground point seen in the
 *  pixel toward the shadowed light): where the ray hits the box, the image of the scene without
 *  that light; elsewhere the image of the scene without any shadowing. Pixels within `margin`
 *  (0.05, 2 pixels) of the shadow's outline are not judged (the shadow map's texels and
 *  filter, PCF or soft, and the image's pixels, all under 0.025), only counted: whether they are
 *  nearer the dark or the lit image, against the ray from the pixel's centre. With `shadowed`
 *  false the technique casts no shadow: lit everywhere. */
static void expectBoxShadow(Material* material, double minimumShadowDepth,
                            osgShadow::ShadowTechnique* technique, bool shadowed = true,
                            osgShadow::ShadowSettings* settings = nullptr,
                            bool shadowedLightFirst = false) {
    const osg::Vec4 free = osg::Vec4(-0.3f, 0.2f, 0.9327f, 0.0f);
    const osg::Vec4 shadowedLight = directionAt(35);
    const osg::Vec3d toShadowed(shadowedLight.x(), shadowedLight.y(), shadowedLight.z());
    const int size = 48;
    const double halfExtent = 0.6;
    const PatchView camera = patchViewFrom(5, 0, size, halfExtent);
    const osg::Vec3d toEye(camera.toEye.x, camera.toEye.y, camera.toEye.z);

    auto scene = [&](osg::Group* root, bool withShadowedLight) {
        if (withShadowedLight && shadowedLightFirst)
            root->addChild(lightSource(1, shadowedLight).get());
        root->addChild(lightSource(0, free, osg::Vec3(0.3f, 0.6f, 0.9f)).get());
        if (withShadowedLight && !shadowedLightFirst)
            root->addChild(lightSource(1, shadowedLight).get());
        root->addChild(patchNode(material).get());
        osg::ref_ptr<osg::Geode> box = new osg::Geode;
        const osg::Vec3d c = (kBoxMin + kBoxMax) * 0.5, e = kBoxMax - kBoxMin;
        box->addDrawable(new osg::ShapeDrawable(new osg::Box(c, e.x(), e.y(), e.z())));
        box->setStateSet(
            programStateSet(
                "",
                "#version 330 compatibility\nvoid main() { gl_FragColor = vec4(1, 0, 1, 1); }\n")
                .get());
        root->addChild(box.get());
        return root;
    };
    osg::ref_ptr<osgShadow::ShadowedScene> shadowedScene = new osgShadow::ShadowedScene;
    if (settings) shadowedScene->setShadowSettings(settings);
    shadowedScene->setShadowTechnique(technique);
    scene(shadowedScene.get(), true);
    osg::ref_ptr<osg::Group> unshadowed = scene(new osg::Group, true);
    osg::ref_ptr<osg::Group> withoutLight = scene(new osg::Group, false);

    HeadlessRenderer& renderer = sharedRenderer();
    osg::ref_ptr<osg::Image> shadowImage = renderer.render(shadowedScene.get(), camera.setup);
    osg::ref_ptr<osg::Image> litImage = renderer.render(unshadowed.get(), camera.setup);
    osg::ref_ptr<osg::Image> darkImage = renderer.render(withoutLight.get(), camera.setup);

    const osg::Matrixd eyeToWorld = osg::Matrixd::inverse(camera.setup.view);
    const double margin = 0.05;
    int inShadow = 0, lit = 0, band = 0, bandAgreeing = 0, rayShadowed = 0, drawnShadowed = 0;
    double worstShadow = 0, worstLit = 0, shadowDepth = 1e30;
    std::string where;
    for (int j = 0; j < size; ++j)
        for (int i = 0; i < size; ++i) {
            const double ex = -halfExtent + (i + 0.5) / size * 2 * halfExtent;
            const double ey = -halfExtent + (j + 0.5) / size * 2 * halfExtent;
            const osg::Vec3d origin = osg::Vec3d(ex, ey, 0) * eyeToWorld;
            const osg::Vec3d p = origin - toEye * (origin.z() / toEye.z());
            if (p.x() < margin || p.x() > 1 - margin || p.y() < margin || p.y() > 1 - margin)
                continue;
            if (rayHitsBox(p, toEye)) continue;  // the box itself is in front
            // Whether the pixel is drawn nearer the image without the light than the lit one:
            // the drawn shadow, for the counts (green: the shadowed light is white, the free one
            // adds less there than in blue).
            const float drawn = pixel(*shadowImage, i, j, 1);
            const bool drawnDark = std::abs(drawn - pixel(*darkImage, i, j, 1)) <
                                   std::abs(drawn - pixel(*litImage, i, j, 1));
            const bool rayDark = shadowed && rayHitsBox(p, toShadowed);
            rayShadowed += rayDark ? 1 : 0;
            drawnShadowed += drawnDark ? 1 : 0;
            int hits = 0;
            for (const osg::Vec3d& d :
                 {osg::Vec3d(0, 0, 0), osg::Vec3d(margin, 0, 0), osg::Vec3d(-margin, 0, 0),
                  osg::Vec3d(0, margin, 0), osg::Vec3d(0, -margin, 0)})
                hits += rayHitsBox(p + d, toShadowed) ? 1 : 0;
            if (hits != 0 && hits != 5) {
                ++band;
                bandAgreeing += drawnDark == rayDark ? 1 : 0;
                continue;
            }
            const osg::Image& expected = hits == 5 && shadowed ? *darkImage : *litImage;
            for (int c = 0; c < 3; ++c) {
                const double d = std::abs(pixel(*shadowImage, i, j, c) - pixel(expected, i, j, c));
                double& worst = hits == 5 ? worstShadow : worstLit;
                if (d > worst) {
                    worst = d;
                    std::ostringstream text;
                    text << (hits == 5 ? "shadow" : "lit") << " pixel (" << i << ", " << j
                         << ") channel " << c << ": " << pixel(*shadowImage, i, j, c)
                         << " expected " << pixel(expected, i, j, c);
                    where = text.str();
                }
            }
            if (hits == 5) {
                ++inShadow;
                shadowDepth = std::min(
                    shadowDepth, double(pixel(*litImage, i, j, 1) - pixel(*darkImage, i, j, 1)));
            } else {
                ++lit;
            }
        }
    // For the report (--gtest_output=xml): the shadowed area drawn against the ray test's.
    ::testing::Test::RecordProperty("judged_shadow_pixels", inShadow);
    ::testing::Test::RecordProperty("judged_lit_pixels", lit);
    ::testing::Test::RecordProperty("band_pixels", band);
    ::testing::Test::RecordProperty("band_pixels_agreeing", bandAgreeing);
    ::testing::Test::RecordProperty("ray_shadowed_pixels", rayShadowed);
    ::testing::Test::RecordProperty("drawn_shadowed_pixels", drawnShadowed);
    EXPECT_GE(inShadow, 40);
    EXPECT_GE(lit, 400);
    EXPECT_GT(shadowDepth, minimumShadowDepth);
    // The ground is drawn: much of the image is neither the box nor the background (0).
    int ground = 0;
    for (int j = 0; j < size; ++j)
        for (int i = 0; i < size; ++i)
            if (pixel(*shadowImage, i, j, 1) > 0.0f) ++ground;
    EXPECT_GE(ground, 400);
    EXPECT_LE(worstShadow, 1e-5) << where;
    EXPECT_LE(worstLit, 1e-5) << where;
    // The band is a few pixels wide around the outline, and mostly follows the ray test even
    // there (a half-texel shift of the outline moves at most about half of it).
    EXPECT_GE(bandAgreeing, band / 2) << band << " band pixels";
    if (!shadowed) {
        EXPECT_EQ(drawnShadowed, 0);
    }
}

namespace {

/** The techniques MaterialNode samples, by class name, as an application would set them up (a
 *  512 x 512 map for the fixed-frustum ones, VDSM's defaults: a 2048 x 2048 map fitted to the
 *  view). */
osg::ref_ptr<osgShadow::ShadowTechnique> makeTechnique(const std::string& name) {
    if (name == "ShadowMap") {
        osg::ref_ptr<osgShadow::ShadowMap> technique = new osgShadow::ShadowMap;
        technique->setTextureSize(osg::Vec2s(512, 512));
        return technique;
    }
    if (name == "SoftShadowMap") {
        osg::ref_ptr<osgShadow::SoftShadowMap> technique = new osgShadow::SoftShadowMap;
        technique->setTextureSize(osg::Vec2s(512, 512));
        return technique;
    }
    return new osgShadow::ViewDependentShadowMap;
}

}  // namespace

// One fixture for the suite: the tests over every supported technique and those of a single
// scene share the name ShadowMapGpu (gtest needs one fixture class per suite name).
class ShadowMapGpu : public ::testing::TestWithParam<std::string> {};

TEST_P(ShadowMapGpu, TheBoxShadowsItsLightAndNothingElse) {
    // The shadowed light adds 0.5 * cos(35 deg) = 0.41 (green): mistaking lit for shadow would
    // be an error of 0.4; the shadow test returns exactly 0 or 1 away from the outline.
    osg::ref_ptr<osgShadow::ShadowTechnique> technique = makeTechnique(GetParam());
    test::ScopedNotifyCapture capture(true);
    expectBoxShadow(constantLambert(0.5f).get(), 0.3, technique.get());
    EXPECT_EQ(capture.text().find("not supported"), std::string::npos) << capture.text();
}

TEST_P(ShadowMapGpu, AMaterialTextureOnTheTechniquesUnitIsKept) {
    // pca keeps its weights on unit 1, where each technique binds its depth texture with
    // OVERRIDE (SoftShadowMap also its jitter texture on 2, VDSM a white texture on 0): the node
    // binds them again PROTECTED (else the lit pixels would differ).
    osg::ref_ptr<osgShadow::ShadowTechnique> technique = makeTechnique(GetParam());
    expectBoxShadow(pcaSample().get(), 0.01, technique.get());
}

INSTANTIATE_TEST_SUITE_P(, ShadowMapGpu,
                         ::testing::Values("ShadowMap", "SoftShadowMap", "ViewDependentShadowMap"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                             return info.param;
                         });

TEST_F(ShadowMapGpu, ViewDependentShadowMapFollowsItsSettings) {
    // Maps from unit 3 without OVERRIDE (the default has it), and light number 1 named while
    // light 0 comes last (VDSM's choice otherwise): the same shadow, of the named light, read
    // through another TexGen unit.
    osg::ref_ptr<osgShadow::ShadowSettings> settings = new osgShadow::ShadowSettings;
    settings->setBaseShadowTextureUnit(3);
    settings->setUseOverrideForShadowMapTexture(false);
    settings->setLightNum(1);
    osg::ref_ptr<osgShadow::ViewDependentShadowMap> technique =
        new osgShadow::ViewDependentShadowMap;
    expectBoxShadow(pcaSample().get(), 0.01, technique.get(), true, settings.get(), true);
}

namespace {

/** A technique MaterialNode does not know: it binds a black texture on units 0 to 3 and a
 *  program that draws black, all with OVERRIDE, and casts no shadow. */
class OverridingTechnique : public osgShadow::ShadowTechnique {
public:
    OverridingTechnique() = default;
    OverridingTechnique(const OverridingTechnique& other,
                        const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : osgShadow::ShadowTechnique(other, copyop) {}
    META_Object(osgBTFTest, OverridingTechnique);

    void init() override {
        _state = programStateSet(
            "", "#version 330 compatibility\nvoid main() { gl_FragColor = vec4(0, 0, 0, 1); }\n");
        _state->setAttribute(_state->getAttribute(osg::StateAttribute::PROGRAM),
                             osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
        osg::ref_ptr<osg::Image> image = new osg::Image;
        image->allocateImage(1, 1, 1, GL_RGBA, GL_FLOAT);
        std::fill_n(reinterpret_cast<float*>(image->data()), 4, 0.0f);
        osg::ref_ptr<osg::Texture2D> black = new osg::Texture2D(image.get());
        for (unsigned unit = 0; unit < 4; ++unit)
            _state->setTextureAttributeAndModes(
                unit, black.get(), osg::StateAttribute::ON | osg::StateAttribute::OVERRIDE);
        _dirty = false;
    }
    void update(osg::NodeVisitor& nv) override { _shadowedScene->osg::Group::traverse(nv); }
    void cull(osgUtil::CullVisitor& cv) override {
        cv.pushStateSet(_state.get());
        _shadowedScene->osg::Group::traverse(cv);
        cv.popStateSet();
    }
    void cleanSceneGraph() override {}
    void resizeGLObjectBuffers(unsigned int maxSize) override {
        if (_state) _state->resizeGLObjectBuffers(maxSize);
    }
    void releaseGLObjects(osg::State* state = nullptr) const override {
        if (_state) _state->releaseGLObjects(state);
    }

private:
    osg::ref_ptr<osg::StateSet> _state;
};

const std::string kNotSupported =
    "' is not supported (osgShadow::ShadowMap, SoftShadowMap and ViewDependentShadowMap are): the "
    "node draws without cast shadows\n";

/** The notice naming `technique`'s class comes exactly once in `text`. */
void expectNamedOnce(const std::string& text, const std::string& className) {
    const std::string message =
        "osgBTF::MaterialNode: shadow technique '" + className + kNotSupported;
    const std::size_t first = text.find(message);
    ASSERT_NE(first, std::string::npos) << text;
    EXPECT_EQ(text.find(message, first + 1), std::string::npos) << "said twice";
}

}  // namespace

TEST_F(ShadowMapGpu, AnUnknownTechniquesOverridesLeaveTheMaterialDrawnWithOneNotice) {
    osg::ref_ptr<OverridingTechnique> technique = new OverridingTechnique;
    test::ScopedNotifyCapture capture(true);
    expectBoxShadow(pcaSample().get(), 0.01, technique.get(), false);
    expectNamedOnce(capture.text(), "OverridingTechnique");
}

TEST_F(ShadowMapGpu, AnotherTechniqueIsNamedOnceAndTheNodeDrawsWithoutCastShadows) {
    osg::ref_ptr<osgShadow::ShadowedScene> scene = new osgShadow::ShadowedScene;
    scene->setShadowTechnique(new osgShadow::ShadowTexture);
    scene->addChild(lightSource(0, directionAt(30)).get());
    scene->addChild(patchNode(constantLambert(0.5f).get()).get());
    const PatchView camera = patchViewFrom(10, 0, 8, 0.3);
    test::ScopedNotifyCapture capture(true);
    sharedRenderer().render(scene.get(), camera.setup);
    osg::ref_ptr<osg::Image> image = sharedRenderer().render(scene.get(), camera.setup);
    expectNamedOnce(capture.text(), "ShadowTexture");
    EXPECT_GT(centre(*image), 0.0f);
}

}  // namespace OSGBTF_TEST_FILE

namespace OSGBTF_TEST_FILE {

namespace {

/** Records, for each draw of the drawable it is set on, the camera drawing it and the program
 *  in use: what each pass runs for that geometry. */
class ProgramRecorder : public osg::Drawable::DrawCallback {
public:
    struct Draw {
        const osg::Camera* camera;
        std::string program;  ///< empty: fixed function
    };
    void drawImplementation(osg::RenderInfo& info, const osg::Drawable* drawable) const override {
        const osg::Program::PerContextProgram* applied =
            info.getState()->getLastAppliedProgramObject();
        std::lock_guard<std::mutex> lock(_mutex);
        _draws.push_back({info.getCurrentCamera(), applied && applied->getProgram()
                                                       ? applied->getProgram()->getName()
                                                       : std::string()});
        drawable->drawImplementation(info);
    }
    std::vector<Draw> draws() const {
        std::lock_guard<std::mutex> lock(_mutex);
        return _draws;
    }

private:
    mutable std::mutex _mutex;
    mutable std::vector<Draw> _draws;
};

/** Wall ms per frame of `scene` (the least of two medians of `frames` frames, so a moment of
 *  load on the machine does not decide it). */
double frameMs(osg::Node* scene, int frames) {
    HeadlessRenderer& renderer = sharedRenderer();
    renderer.setScene(scene);
    double best = 1e30;
    for (int round = 0; round < 2; ++round)
        best = std::min(best, renderer.timePasses(frames).wallMs);
    return best;
}

}  // namespace

class ShadowDepthPass : public ::testing::TestWithParam<std::string> {};

TEST_P(ShadowDepthPass, RunsNoBtfProgram) {
    // The technique with OSG's defaults (VDSM: a 2048 x 2048 map fitted to the view). Each draw of
    // the ground names its camera and program: in the view, the material's shadow-map variant; in
    // any other camera (the technique's depth pass), never a BTF program.
    osg::ref_ptr<PcaMaterial> material = pcaSample();
    const ShadowScene scene = makeShadowScene(material.get(), GetParam());
    osg::ref_ptr<ProgramRecorder> recorder = new ProgramRecorder;
    scene.groundGeometry->setDrawCallback(recorder.get());
    scene.groundGeometry->setUseDisplayList(false);
    HeadlessRenderer& renderer = sharedRenderer();
    renderer.render(scene.root.get(), shadowSceneCamera(96, 72));
    renderer.render();
    const osg::Camera* view = &renderer.camera();
    int viewDraws = 0, depthDraws = 0;
    for (const ProgramRecorder::Draw& draw : recorder->draws()) {
        if (draw.camera == view) {
            ++viewDraws;
            EXPECT_EQ(draw.program, shadowMapProgram("pca", false)->getName());
        } else {
            ++depthDraws;
            EXPECT_TRUE(draw.program.empty() || draw.program == depthOnlyProgram()->getName())
                << "the depth pass ran '" << draw.program << "'";
        }
    }
    EXPECT_EQ(viewDraws, 2);  // once a frame
    // The ground casts shadows too (the default masks): each frame draws it into the map once.
    EXPECT_EQ(depthDraws, 2);
    scene.groundGeometry->setDrawCallback(nullptr);
}

TEST_P(ShadowDepthPass, ABtfGroundCostsAboutWhatItCostsWithoutShadows) {
    // What a BTF ground costs per frame over a plain textured one, under the technique and with
    // none: the technique adds its own passes, and those must not run the BTF (depth passes draw
    // depth only), so the extra cost stays what it is without shadows. Measured (llvmpipe, 2
    // cores, 160 x 120): without shadows ~20 ms extra; under ViewDependentShadowMap 1,720 ms
    // extra before the depth passes ran without the BTF program (its 2048 x 2048 map), ~0-10 ms
    // after. A generous bound (4x + 10 ms) so load on a shared machine does not decide it.
    osg::ref_ptr<PcaMaterial> material = pcaSample();
    const CameraSetup camera = shadowSceneCamera(160, 120);
    sharedRenderer().setCamera(camera);
    const int frames = 3;
    const double plain = frameMs(makeShadowScene(nullptr, GetParam()).root.get(), frames);
    const double btf = frameMs(makeShadowScene(material.get(), GetParam()).root.get(), frames);
    const double plainNone = frameMs(makeShadowScene(nullptr, "none").root.get(), frames);
    const double btfNone = frameMs(makeShadowScene(material.get(), "none").root.get(), frames);
    const double extra = btf - plain, extraNone = btfNone - plainNone;
    ::testing::Test::RecordProperty("btf_extra_us", int(extra * 1000));
    ::testing::Test::RecordProperty("btf_extra_without_shadows_us", int(extraNone * 1000));
    std::printf("%s: BTF ground %.1f ms, plain %.1f ms; without shadows %.1f and %.1f ms\n",
                GetParam().c_str(), btf, plain, btfNone, plainNone);
    EXPECT_LT(extra, 4 * std::max(0.0, extraNone) + 10)
        << "the BTF ground costs " << extra << " ms a frame more than the plain one under "
        << GetParam() << ", " << extraNone << " ms more without shadows";
}

INSTANTIATE_TEST_SUITE_P(, ShadowDepthPass,
                         ::testing::Values("ShadowMap", "SoftShadowMap", "ViewDependentShadowMap"),
                         [](const ::testing::TestParamInfo<std::string>& info) {
                             return info.param;
                         });

}  // namespace OSGBTF_TEST_FILE
