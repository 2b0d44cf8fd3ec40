#include "GlTestEnv.h"

#include "core/Directions.h"

#include <gtest/gtest.h>

#include <osg/Program>
#include <osg/Shader>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <iostream>
#include <memory>

#ifdef OSGBTF_GL_TEST_OSMESA
#include "harness/headless/OSMesaContext.h"
#endif

namespace osgBTF::test {

namespace {

std::unique_ptr<HeadlessRenderer>& rendererSlot() {
    static std::unique_ptr<HeadlessRenderer> renderer;
    return renderer;
}

class GlEnvironment : public ::testing::Environment {
public:
    void TearDown() override { rendererSlot().reset(); }
};

}  // namespace

HeadlessBackend glTestBackend() {
#ifdef OSGBTF_GL_TEST_OSMESA
    return HeadlessBackend::OSMesa;
#else
    return HeadlessBackend::Egl;
#endif
}

HeadlessRenderer& sharedRenderer() {
    auto& slot = rendererSlot();
    if (!slot) {
        slot = std::make_unique<HeadlessRenderer>(glTestBackend());
        // Written to stderr: a sanitizer that fails the process discards buffered stdout.
        std::cerr << "[gl] backend=" << toString(slot->backend()) << " GL_RENDERER=\""
                  << slot->glRenderer() << "\" GL_VERSION=\"" << slot->glVersion() << "\""
                  << std::endl;
    }
    return *slot;
}

bool isLlvmpipe() {
    return sharedRenderer().glRenderer().find("llvmpipe") != std::string::npos;
}

const char* const kQuadVertexShader = R"(#version 330 compatibility
out vec2 uv;
void main() {
    uv = gl_MultiTexCoord0.xy;
    gl_Position = gl_ModelViewProjectionMatrix * gl_Vertex;
}
)";

osg::ref_ptr<osg::StateSet> programStateSet(const std::string& vertex,
                                            const std::string& fragment) {
    osg::ref_ptr<osg::Program> program = new osg::Program;
    if (!vertex.empty()) program->addShader(new osg::Shader(osg::Shader::VERTEX, vertex));
    program->addShader(new osg::Shader(osg::Shader::FRAGMENT, fragment));
    osg::ref_ptr<osg::StateSet> ss = new osg::StateSet;
    ss->setAttributeAndModes(program.get(), osg::StateAttribute::ON);
    return ss;
}

osg::ref_ptr<osg::Texture2D> floatTexture2D(int width, int height, const std::vector<float>& rgba) {
    osg::ref_ptr<osg::Image> image = new osg::Image;
    image->allocateImage(width, height, 1, GL_RGBA, GL_FLOAT);
    image->setInternalTextureFormat(GL_RGBA32F_ARB);  // headless.md pitfall 2
    std::memcpy(image->data(), rgba.data(),
                sizeof(float) * 4 * static_cast<size_t>(width * height));
    osg::ref_ptr<osg::Texture2D> texture = new osg::Texture2D(image.get());
    texture->setInternalFormat(GL_RGBA32F_ARB);
    texture->setSourceFormat(GL_RGBA);
    texture->setSourceType(GL_FLOAT);
    texture->setResizeNonPowerOfTwoHint(false);  // pitfall 5
    texture->setFilter(osg::Texture::MIN_FILTER, osg::Texture::NEAREST);
    texture->setFilter(osg::Texture::MAG_FILTER, osg::Texture::NEAREST);
    texture->setWrap(osg::Texture::WRAP_S, osg::Texture::CLAMP_TO_EDGE);
    texture->setWrap(osg::Texture::WRAP_T, osg::Texture::CLAMP_TO_EDGE);
    return texture;
}

float pixel(const osg::Image& image, int x, int y, int channel) {
    const float* data = reinterpret_cast<const float*>(image.data());
    return data[4 * (static_cast<size_t>(y) * static_cast<size_t>(image.s()) +
                     static_cast<size_t>(x)) +
                static_cast<size_t>(channel)];
}

double maxDifference(const osg::Image& a, const osg::Image& b) {
    const float* pa = reinterpret_cast<const float*>(a.data());
    const float* pb = reinterpret_cast<const float*>(b.data());
    double worst = 0;
    for (int k = 0; k < a.s() * a.t() * 4; ++k)
        worst = std::max(worst, double(std::abs(pa[k] - pb[k])));
    return worst;
}

PatchView patchViewFrom(float thetaDeg, float phiDeg, int imageSize, double halfExtent) {
    PatchView view;
    view.toEye = Direction{thetaDeg, phiDeg}.toVector();
    const osg::Vec3d v(view.toEye.x, view.toEye.y, view.toEye.z), centre(0.5, 0.5, 0);
    view.setup.view = osg::Matrixd::lookAt(centre + v * 2.0, centre, osg::Vec3d(0, 0, 1));
    view.setup.projection =
        osg::Matrixd::ortho(-halfExtent, halfExtent, -halfExtent, halfExtent, 0.1, 10.0);
    view.setup.width = view.setup.height = imageSize;
    return view;
}

}  // namespace osgBTF::test

int main(int argc, char** argv) {
    ::testing::InitGoogleTest(&argc, argv);
#ifdef OSGBTF_GL_TEST_OSMESA
    osgBTF::registerOSMesaBackend();
#endif
    ::testing::AddGlobalTestEnvironment(new osgBTF::test::GlEnvironment);
    return RUN_ALL_TESTS();
}
