// Headless rendering: float precision of the pipeline, Texture3D filtering against a CPU formula,
// one context for many scenes, timing, and the error paths. Built twice (EGL and OSMesa).
#include "GlTestEnv.h"

#include "core/Error.h"

#include <gtest/gtest.h>

#include <osg/Light>
#include <osg/LightSource>
#include <osg/ShapeDrawable>
#include <osg/State>
#include <osg/Uniform>
#include <osgShadow/ShadowMap>
#include <osgShadow/ShadowedScene>
#include <osgShadow/ViewDependentShadowMap>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <functional>
#include <iostream>
#include <random>
#include <string>

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

/** Sets an environment variable for the scope, restoring the old value (or its absence). */
class ScopedEnv {
public:
    ScopedEnv(const char* name, const char* value) : _name(name) {
        if (const char* old = std::getenv(name)) {
            _had = true;
            _old = old;
        }
        setenv(name, value, 1);
    }
    ~ScopedEnv() {
        if (_had)
            setenv(_name.c_str(), _old.c_str(), 1);
        else
            unsetenv(_name.c_str());
    }

private:
    std::string _name, _old;
    bool _had = false;
};

std::string errorMessage(const std::function<void()>& f) {
    try {
        f();
    } catch (const Error& e) {
        return e.what();
    }
    return "(no osgBTF::Error thrown)";
}

/** A W x H RGBA32F pattern with values far outside [0, 1]. */
std::vector<float> extremeValues(int width, int height) {
    const float specials[] = {-1000.f, 2.5f, 1e6f, -1e-3f, 65504.5f,  -3.25e7f,
                              1e-30f,  0.f,  1.f,  -0.f,   12345.678f};
    std::vector<float> v(4 * static_cast<size_t>(width * height));
    std::mt19937 rng(7);
    std::uniform_real_distribution<float> any(-2000.f, 2000.f);
    for (size_t i = 0; i < v.size(); ++i)
        v[i] = i < std::size(specials) * 3 ? specials[i % std::size(specials)] : any(rng);
    return v;
}

void expectImageEquals(const osg::Image& image, const std::vector<float>& expected, int width,
                       int height) {
    ASSERT_EQ(image.s(), width);
    ASSERT_EQ(image.t(), height);
    ASSERT_EQ(image.getPixelFormat(), static_cast<GLenum>(GL_RGBA));
    ASSERT_EQ(image.getDataType(), static_cast<GLenum>(GL_FLOAT));
    int bad = 0;
    for (int y = 0; y < height; ++y)
        for (int x = 0; x < width; ++x)
            for (int c = 0; c < 4; ++c) {
                const float want =
                    expected[4 * static_cast<size_t>(y * width + x) + static_cast<size_t>(c)];
                const float got = pixel(image, x, y, c);
                const double tol = 1e-6 * std::max(1.0, std::fabs(static_cast<double>(want)));
                if (!(std::fabs(static_cast<double>(got) - want) <= tol) && bad++ < 5)
                    ADD_FAILURE() << "pixel (" << x << "," << y << ") channel " << c << ": got "
                                  << got << ", want " << want;
            }
    EXPECT_EQ(bad, 0) << "mismatching floats";
}

}  // namespace

TEST(HeadlessGl, ReportsRendererAndVersion) {
    HeadlessRenderer& r = sharedRenderer();
    EXPECT_EQ(r.backend(), glTestBackend());
    EXPECT_FALSE(r.glRenderer().empty());
    EXPECT_FALSE(r.glVersion().empty());
    int major = 0, minor = 0;
    ASSERT_EQ(std::sscanf(r.glVersion().c_str(), "%d.%d", &major, &minor), 2) << r.glVersion();
    EXPECT_GE(major * 10 + minor, 33)
        << "need OpenGL 3.3 for #version 330 compatibility: " << r.glVersion();
    ::testing::Test::RecordProperty("GL_RENDERER", r.glRenderer());
    ::testing::Test::RecordProperty("GL_VERSION", r.glVersion());
}

// (a) An RGBA32F texture read with texelFetch, and with texture() at texel centres, comes back
// through the RGBA32F FBO unchanged, values far outside [0, 1] included.
TEST(HeadlessGl, Rgba32fTextureRoundTripIsExact) {
    const int w = 16, h = 12;
    const std::vector<float> values = extremeValues(w, h);
    osg::ref_ptr<osg::Texture2D> texture = floatTexture2D(w, h, values);

    osg::ref_ptr<osg::StateSet> fetch = programStateSet("", R"(#version 330 compatibility
uniform sampler2D tex;
void main() { gl_FragColor = texelFetch(tex, ivec2(gl_FragCoord.xy), 0); }
)");
    fetch->setTextureAttributeAndModes(0, texture.get());
    fetch->addUniform(new osg::Uniform("tex", 0));
    osg::ref_ptr<osg::Image> image =
        sharedRenderer().render(createFullScreenQuad(fetch.get()), orthoUnitSquare(w, h));
    SCOPED_TRACE("texelFetch");
    expectImageEquals(*image, values, w, h);

    osg::ref_ptr<osg::StateSet> sample =
        programStateSet(kQuadVertexShader, R"(#version 330 compatibility
uniform sampler2D tex;
in vec2 uv;
void main() { gl_FragColor = texture(tex, uv); }
)");
    sample->setTextureAttributeAndModes(0, texture.get());
    sample->addUniform(new osg::Uniform("tex", 0));
    image = sharedRenderer().render(createFullScreenQuad(sample.get()), orthoUnitSquare(w, h));
    SCOPED_TRACE("texture() at texel centres, NEAREST");
    expectImageEquals(*image, values, w, h);
}

namespace {

/** GL's trilinear filter with CLAMP_TO_EDGE (spec 8.14.2), in double, on an R32F volume stored
 *  s fastest, then t, then r. */
double trilinear(const std::vector<float>& v, int nx, int ny, int nz, double s, double t, double r,
                 double* neighbourRange) {
    auto axis = [](double coord, int n, int& i0, int& i1, double& a) {
        const double u = coord * n - 0.5;
        const double f = std::floor(u);
        a = u - f;
        i0 = std::clamp(static_cast<int>(f), 0, n - 1);
        i1 = std::clamp(static_cast<int>(f) + 1, 0, n - 1);
    };
    int x[2], y[2], z[2];
    double a, b, c;
    axis(s, nx, x[0], x[1], a);
    axis(t, ny, y[0], y[1], b);
    axis(r, nz, z[0], z[1], c);
    double sum = 0, lo = 1e300, hi = -1e300;
    for (int k = 0; k < 2; ++k)
        for (int j = 0; j < 2; ++j)
            for (int i = 0; i < 2; ++i) {
                const double value =
                    v[(static_cast<size_t>(z[k]) * ny + static_cast<size_t>(y[j])) * nx +
                      static_cast<size_t>(x[i])];
                const double weight = (i ? a : 1 - a) * (j ? b : 1 - b) * (k ? c : 1 - c);
                sum += weight * value;
                lo = std::min(lo, value);
                hi = std::max(hi, value);
            }
    if (neighbourRange) *neighbourRange = hi - lo;
    return sum;
}

}  // namespace

// (b) Hardware trilinear filtering of an R32F Texture3D equals the CPU formula.
TEST(HeadlessGl, Texture3DTrilinearMatchesCpuFormula) {
    const int nx = 8, ny = 6, nz = 5;
    std::mt19937 rng(12345);
    std::uniform_real_distribution<float> valueDist(-4.f, 4.f);
    std::vector<float> volume(static_cast<size_t>(nx * ny * nz));
    for (float& x : volume) x = valueDist(rng);

    osg::ref_ptr<osg::Image> volumeImage = new osg::Image;
    volumeImage->allocateImage(nx, ny, nz, GL_RED, GL_FLOAT);
    volumeImage->setInternalTextureFormat(GL_R32F);
    std::copy(volume.begin(), volume.end(), reinterpret_cast<float*>(volumeImage->data()));
    osg::ref_ptr<osg::Texture3D> texture3d = new osg::Texture3D(volumeImage.get());
    texture3d->setInternalFormat(GL_R32F);
    texture3d->setSourceFormat(GL_RED);
    texture3d->setSourceType(GL_FLOAT);
    texture3d->setResizeNonPowerOfTwoHint(false);
    texture3d->setFilter(osg::Texture::MIN_FILTER, osg::Texture::LINEAR);
    texture3d->setFilter(osg::Texture::MAG_FILTER, osg::Texture::LINEAR);
    for (auto wrap : {osg::Texture::WRAP_S, osg::Texture::WRAP_T, osg::Texture::WRAP_R})
        texture3d->setWrap(wrap, osg::Texture::CLAMP_TO_EDGE);

    // One random coordinate per output pixel, slightly outside [0, 1] too (clamping).
    const int w = 32, h = 32;
    std::uniform_real_distribution<float> coordDist(-0.1f, 1.1f);
    std::vector<float> coords(4 * static_cast<size_t>(w * h));
    for (size_t i = 0; i < coords.size(); i += 4) {
        coords[i] = coordDist(rng);
        coords[i + 1] = coordDist(rng);
        coords[i + 2] = coordDist(rng);
        coords[i + 3] = 1.f;
    }
    osg::ref_ptr<osg::Texture2D> coordTexture = floatTexture2D(w, h, coords);

    osg::ref_ptr<osg::StateSet> ss = programStateSet("", R"(#version 330 compatibility
uniform sampler3D volume;
uniform sampler2D coords;
void main() {
    vec3 c = texelFetch(coords, ivec2(gl_FragCoord.xy), 0).xyz;
    gl_FragColor = vec4(texture(volume, c).r, c);
}
)");
    ss->setTextureAttributeAndModes(0, texture3d.get());
    ss->setTextureAttributeAndModes(1, coordTexture.get());
    ss->addUniform(new osg::Uniform("volume", 0));
    ss->addUniform(new osg::Uniform("coords", 1));
    osg::ref_ptr<osg::Image> image =
        sharedRenderer().render(createFullScreenQuad(ss.get()), orthoUnitSquare(w, h));
    ASSERT_EQ(image->s(), w);
    ASSERT_EQ(image->t(), h);

    // llvmpipe filters float textures with float weights (headless.md: 5e-7 measured); GPUs use
    // fixed-point weights with 8 fractional bits, off by about 1/256 of the neighbour difference.
    const bool llvmpipe = isLlvmpipe();
    double maxError = 0;
    int bad = 0;
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x) {
            const size_t i = 4 * static_cast<size_t>(y * w + x);
            ASSERT_EQ(pixel(*image, x, y, 1), coords[i])
                << "coordinate did not survive at " << x << "," << y;
            double range = 0;
            const double want =
                trilinear(volume, nx, ny, nz, coords[i], coords[i + 1], coords[i + 2], &range);
            const double got = pixel(*image, x, y, 0);
            const double tol = llvmpipe ? 1e-5 : 1e-5 + range * (2.0 / 256.0);
            maxError = std::max(maxError, std::fabs(got - want));
            if (!(std::fabs(got - want) <= tol) && bad++ < 5)
                ADD_FAILURE() << "at (" << coords[i] << ", " << coords[i + 1] << ", "
                              << coords[i + 2] << "): GPU " << got << ", CPU " << want
                              << ", tolerance " << tol;
        }
    EXPECT_EQ(bad, 0);
    std::cerr << "[gl] Texture3D trilinear: max |GPU - CPU| = " << maxError << " over " << w * h
              << " samples (renderer " << sharedRenderer().glRenderer() << ")" << std::endl;
    ::testing::Test::RecordProperty("max_abs_error", std::to_string(maxError));
}

// (c) One context renders different scenes, and sizes, one after another.
TEST(HeadlessGl, OneContextRendersSeveralScenes) {
    HeadlessRenderer& r = sharedRenderer();
    const HeadlessContext* context = &r.context();
    std::cerr << "[gl] GL_RENDERER=\"" << r.glRenderer() << "\"" << std::endl;
    ASSERT_FALSE(r.glRenderer().empty());

    osg::ref_ptr<osg::StateSet> constant = programStateSet("", R"(#version 330 compatibility
uniform vec4 colour;
void main() { gl_FragColor = colour; }
)");
    constant->addUniform(new osg::Uniform("colour", osg::Vec4(1.5f, -2.f, 1e5f, 0.25f)));
    osg::ref_ptr<osg::Node> sceneA = createFullScreenQuad(constant.get());

    osg::ref_ptr<osg::StateSet> coordinates =
        programStateSet(kQuadVertexShader, R"(#version 330 compatibility
in vec2 uv;
void main() { gl_FragColor = vec4(gl_FragCoord.xy, uv * 100.0); }
)");
    osg::ref_ptr<osg::Node> sceneB = createFullScreenQuad(coordinates.get());

    auto checkA = [](const osg::Image& image, int w, int h) {
        ASSERT_EQ(image.s(), w);
        ASSERT_EQ(image.t(), h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                ASSERT_EQ(pixel(image, x, y, 0), 1.5f);
                ASSERT_EQ(pixel(image, x, y, 1), -2.f);
                ASSERT_EQ(pixel(image, x, y, 2), 1e5f);
                ASSERT_EQ(pixel(image, x, y, 3), 0.25f);
            }
    };
    auto checkB = [](const osg::Image& image, int w, int h) {
        ASSERT_EQ(image.s(), w);
        ASSERT_EQ(image.t(), h);
        for (int y = 0; y < h; ++y)
            for (int x = 0; x < w; ++x) {
                ASSERT_EQ(pixel(image, x, y, 0), x + 0.5f);
                ASSERT_EQ(pixel(image, x, y, 1), y + 0.5f);
                ASSERT_NEAR(pixel(image, x, y, 2), 100.0 * (x + 0.5) / w, 1e-3);
                ASSERT_NEAR(pixel(image, x, y, 3), 100.0 * (y + 0.5) / h, 1e-3);
            }
    };

    osg::ref_ptr<osg::Image> a = r.render(sceneA.get(), orthoUnitSquare(20, 10));
    osg::ref_ptr<osg::Image> b = r.render(sceneB.get(), orthoUnitSquare(20, 10));
    checkA(*a, 20, 10);  // still intact: render() returns copies
    checkB(*b, 20, 10);
    checkB(*r.render(sceneB.get(), orthoUnitSquare(7, 33)), 7, 33);  // new size, new FBO
    checkA(*r.render(sceneA.get(), orthoUnitSquare(64, 48)), 64, 48);
    r.setClearColor(osg::Vec4(-1.f, 2.f, 3.f, 4.f));
    osg::ref_ptr<osg::Image> empty = r.render(nullptr, orthoUnitSquare(8, 8));
    r.setClearColor(osg::Vec4(0.f, 0.f, 0.f, 0.f));
    EXPECT_EQ(pixel(*empty, 3, 3, 0), -1.f);
    EXPECT_EQ(pixel(*empty, 3, 3, 3), 4.f);
    EXPECT_EQ(&r.context(), context);
}

// Nothing of a replaced scene reaches the next one. OSG 3.6.5's ViewDependentShadowMap leaves a
// render-graph node keyed by the address of a StateSet that is deleted with its scene; a ShadowMap
// scene drawn next, whose own StateSet landed at that address, was drawn with the deleted
// technique's program and depth texture (HeadlessRenderer::setScene).
TEST(HeadlessGl, ASceneAfterAViewDependentShadowMapRendersAsInAFreshRenderer) {
    auto shadowed = [](osgShadow::ShadowTechnique* technique) {
        osg::ref_ptr<osgShadow::ShadowedScene> scene = new osgShadow::ShadowedScene;
        scene->setShadowTechnique(technique);
        osg::ref_ptr<osg::Light> light = new osg::Light(0);
        light->setPosition(osg::Vec4(0.57f, 0.0f, 0.82f, 0.0f));
        osg::ref_ptr<osg::LightSource> source = new osg::LightSource;
        source->setLight(light.get());
        scene->addChild(source.get());
        scene->addChild(createFullScreenQuad().get());
        osg::ref_ptr<osg::Geode> box = new osg::Geode;
        box->addDrawable(
            new osg::ShapeDrawable(new osg::Box(osg::Vec3(0.5f, 0.5f, 0.3f), 0.2f, 0.3f, 0.1f)));
        scene->addChild(box.get());
        return scene;
    };
    HeadlessRenderer& shared = sharedRenderer();
    shared.render(shadowed(new osgShadow::ViewDependentShadowMap).get(),
                  patchViewFrom(10, 0, 8, 0.3).setup);
    // Made while the ViewDependentShadowMap scene is still shown, as by a test that follows one
    // that drew it; it is deleted when this one replaces it.
    osg::ref_ptr<osgShadow::ShadowedScene> scene = shadowed(new osgShadow::ShadowMap);
    const PatchView camera = patchViewFrom(5, 0, 48, 0.6);
    osg::ref_ptr<osg::Image> image = shared.render(scene.get(), camera.setup);
    HeadlessRenderer fresh(glTestBackend());
    osg::ref_ptr<osg::Image> expected =
        fresh.render(shadowed(new osgShadow::ShadowMap).get(), camera.setup);
    EXPECT_GT(pixel(*expected, 24, 8, 0), 0.5f);  // the lit patch
    EXPECT_LE(maxDifference(*image, *expected), 1e-6);
}

// Double uniforms reach the shader. Under OSMesa this needs the extension-pointer fix-up
// (headless.md 2.3 Rule 2): without it glUniform1d is a glvnd no-op and the shader reads 0.
TEST(HeadlessGl, DoubleUniformReachesShader) {
    osg::ref_ptr<osg::StateSet> ss = programStateSet("", R"(#version 400 compatibility
uniform double d;
void main() { gl_FragColor = vec4(float(d), float(d * 2.0), 0.0, 1.0); }
)");
    ss->addUniform(new osg::Uniform("d", 300000.25));
    osg::ref_ptr<osg::Image> image =
        sharedRenderer().render(createFullScreenQuad(ss.get()), orthoUnitSquare(4, 4));
    EXPECT_EQ(pixel(*image, 1, 2, 0), 300000.25f);
    EXPECT_EQ(pixel(*image, 1, 2, 1), 600000.5f);
}

// timePasses: a trivial 512 x 512 pass, wall, process CPU and (forced) GL timer-query times.
TEST(HeadlessGl, TimePassesOfTrivialPass) {
    HeadlessRenderer& r = sharedRenderer();
    osg::ref_ptr<osg::StateSet> ss = programStateSet("", R"(#version 330 compatibility
void main() { gl_FragColor = vec4(gl_FragCoord.xy, 0.0, 1.0); }
)");
    r.setScene(createFullScreenQuad(ss.get()));
    r.setCamera(orthoUnitSquare(512, 512));
    const PassTiming timing = r.timePasses(10, GpuTimer::On);
    EXPECT_EQ(timing.frames, 10);
    EXPECT_EQ(timing.wallMsPerFrame.size(), 10u);
    EXPECT_GT(timing.wallMs, 0.0);
    EXPECT_GE(timing.cpuMs, 0.0);
    // llvmpipe's numbers are meaningless (headless.md 4) but non-zero when the query works; under
    // OSMesa they are 0 or absent without the extension-pointer fix-up.
    EXPECT_EQ(timing.gpuMsPerFrame.size(), 10u);
    EXPECT_GT(timing.gpuMs, 0.0);
    const PassTiming automatic = r.timePasses(3);
    EXPECT_EQ(automatic.gpuMsPerFrame.empty(), r.isSoftwareRenderer());
    std::cerr << "[gl] 512x512 trivial pass, median of 10: wall " << timing.wallMs << " ms, CPU "
              << timing.cpuMs << " ms, GL_TIME_ELAPSED " << timing.gpuMs << " ms ("
              << r.glRenderer() << ")" << std::endl;
    ::testing::Test::RecordProperty("wall_ms", std::to_string(timing.wallMs));
    ::testing::Test::RecordProperty("cpu_ms", std::to_string(timing.cpuMs));
    osg::ref_ptr<osg::Image> image = r.render();
    EXPECT_EQ(pixel(*image, 300, 200, 0), 300.5f);
    EXPECT_EQ(pixel(*image, 300, 200, 1), 200.5f);
}

// The colour target: a renderbuffer of a viewer's format for timing (never read back), and back
// to the read-back RGBA32F one for images.
TEST(HeadlessGl, ColorTargetForTimingAndBackForImages) {
    HeadlessRenderer& r = sharedRenderer();
    osg::ref_ptr<osg::StateSet> ss = programStateSet("", R"(#version 330 compatibility
void main() { gl_FragColor = vec4(gl_FragCoord.xy, 0.0, 1.0); }
)");
    r.setScene(createFullScreenQuad(ss.get()));
    r.setCamera(orthoUnitSquare(64, 32));
    EXPECT_EQ(errorMessage([&] { r.setColorTarget(GL_RGBA16F_ARB, true); }),
              "HeadlessRenderer: only the GL_RGBA32F target is read back");
    for (GLenum format : {GLenum(GL_RGBA8), GLenum(GL_RGBA16F_ARB), GLenum(GL_RGBA32F_ARB)}) {
        r.setColorTarget(format, false);
        EXPECT_EQ(r.colorTargetFormat(), format);
        EXPECT_EQ(errorMessage([&] { r.render(); }),
                  "HeadlessRenderer: render() needs the read-back target (setColorTarget)");
        const PassTiming timing = r.timePasses(2, GpuTimer::Auto, 0);
        EXPECT_EQ(timing.wallMsPerFrame.size(), 2u);
    }
    EXPECT_EQ(errorMessage([&] { r.timePasses(1, GpuTimer::Auto, -1); }),
              "HeadlessRenderer::timePasses: warm-up frames must be at least 0");
    r.setColorTarget(GL_RGBA32F_ARB, true);
    osg::ref_ptr<osg::Image> image = r.render();
    EXPECT_EQ(pixel(*image, 40, 20, 0), 40.5f);  // unclamped: a float target again
    EXPECT_EQ(pixel(*image, 40, 20, 1), 20.5f);
}

// A second context can be created and closed while the shared one lives on (EGL: the device
// display is shared, so closing must not eglTerminate it under the first context's feet).
TEST(HeadlessGl, SecondContextComesAndGoes) {
    HeadlessRenderer& shared = sharedRenderer();
    {
        ScopedEnv env("OSGBTF_EGL_SOFTWARE",
                      "1");  // Mesa's software device (EGL); ignored by OSMesa
        osg::ref_ptr<HeadlessContext> second = createHeadlessContext(glTestBackend(), 32, 32);
        ASSERT_TRUE(second.valid());
        EXPECT_TRUE(second->valid());
        EXPECT_TRUE(second->isSoftwareRenderer()) << second->glRenderer();
        EXPECT_NE(second->getState()->getContextID(), shared.context().getState()->getContextID());
        HeadlessRenderer renderer(second);
        osg::ref_ptr<osg::StateSet> ss = programStateSet("", R"(#version 330 compatibility
void main() { gl_FragColor = vec4(7.0, -7.0, 0.5, 1e4); }
)");
        osg::ref_ptr<osg::Image> image =
            renderer.render(createFullScreenQuad(ss.get()), orthoUnitSquare(9, 9));
        EXPECT_EQ(pixel(*image, 4, 4, 0), 7.f);
        EXPECT_EQ(pixel(*image, 4, 4, 3), 1e4f);
    }
    osg::ref_ptr<osg::StateSet> ss = programStateSet("", R"(#version 330 compatibility
void main() { gl_FragColor = vec4(-3.5, 3.5, 0.0, 2.0); }
)");
    osg::ref_ptr<osg::Image> image =
        shared.render(createFullScreenQuad(ss.get()), orthoUnitSquare(5, 5));
    EXPECT_EQ(pixel(*image, 2, 2, 0), -3.5f);
    EXPECT_EQ(pixel(*image, 2, 2, 3), 2.f);
}

// (d) The error paths say what is wrong and what to do.
TEST(HeadlessGl, BogusBackendInEnvironmentIsAClearError) {
    ScopedEnv env("OSGBTF_HEADLESS", "bogus");
    const std::string message = errorMessage([] { createHeadlessContext(16, 16); });
    EXPECT_NE(message.find("OSGBTF_HEADLESS"), std::string::npos) << message;
    EXPECT_NE(message.find("bogus"), std::string::npos) << message;
    EXPECT_NE(message.find("egl"), std::string::npos) << message;
    EXPECT_NE(message.find("osmesa"), std::string::npos) << message;
    EXPECT_THROW(HeadlessRenderer renderer, Error);
}

TEST(HeadlessGl, BackendNamesInEnvironment) {
    {
        ScopedEnv env("OSGBTF_HEADLESS", "OSMesa");
        EXPECT_EQ(headlessBackendFromEnvironment(), HeadlessBackend::OSMesa);
    }
    {
        ScopedEnv env("OSGBTF_HEADLESS", "egl");
        EXPECT_EQ(headlessBackendFromEnvironment(), HeadlessBackend::Egl);
    }
    {
        ScopedEnv env("OSGBTF_HEADLESS", "");
        EXPECT_EQ(headlessBackendFromEnvironment(), HeadlessBackend::Egl);
    }
}

#ifndef OSGBTF_GL_TEST_OSMESA
TEST(HeadlessGl, OSMesaNotLinkedIsAClearError) {
    EXPECT_FALSE(isHeadlessBackendAvailable(HeadlessBackend::OSMesa));
    const std::string message =
        errorMessage([] { createHeadlessContext(HeadlessBackend::OSMesa, 16, 16); });
    EXPECT_EQ(message,
              "the OSMesa back end is not linked into this program; use OSGBTF_HEADLESS=egl");
}
#else
TEST(HeadlessGl, OSMesaIsRegistered) {
    EXPECT_TRUE(isHeadlessBackendAvailable(HeadlessBackend::OSMesa));
}
#endif

}  // namespace OSGBTF_TEST_FILE
