// Shared set-up of the OpenGL tests. The same sources build osgBTF_gl_tests (EGL) and
// osgBTF_osmesa_tests (OSMesa, compile definition OSGBTF_GL_TEST_OSMESA).
#pragma once

#include "harness/headless/HeadlessRenderer.h"

#include <osg/StateSet>
#include <osg/Texture2D>
#include <osg/Texture3D>

#include <glm/vec3.hpp>
#include <string>
#include <vector>

namespace osgBTF::test {

/** The back end this executable tests. */
HeadlessBackend glTestBackend();

/** One renderer (one context) per test process, created on first use, destroyed by the gtest
 *  environment before main returns (llvmpipe leaks JIT memory per context; headless.md 8). */
HeadlessRenderer& sharedRenderer();

/** True when GL_RENDERER names llvmpipe (float filter weights; GPUs use 8-bit fixed point). */
bool isLlvmpipe();

/** A state set with a GLSL program from the given sources (vertex source may be empty). */
osg::ref_ptr<osg::StateSet> programStateSet(const std::string& vertex, const std::string& fragment);

/** Pass-through vertex shader for the full-screen quad: `out vec2 uv` = texture coordinate 0. */
extern const char* const kQuadVertexShader;

/** RGBA32F 2D texture, W x H, rows bottom-up, NEAREST, CLAMP_TO_EDGE, no power-of-two resize. */
osg::ref_ptr<osg::Texture2D> floatTexture2D(int width, int height, const std::vector<float>& rgba);

/** Pixel (x, y) channel c of a GL_RGBA/GL_FLOAT image as OSG gives it (bottom-up rows). */
float pixel(const osg::Image& image, int x, int y, int channel);

/** The largest absolute difference between two GL_RGBA/GL_FLOAT images of the same size. */
double maxDifference(const osg::Image& a, const osg::Image& b);

/** An orthographic camera looking at the centre of the unit patch (z = 0) from (theta, phi) in
 *  degrees, theta > 0 (up vector +Z), with an image of `imageSize` squared pixels showing
 *  [-halfExtent, halfExtent] around the centre. `toEye` is the world (= patch-local) direction
 *  toward the eye, what the CPU evaluator needs as the view direction. */
struct PatchView {
    CameraSetup setup;
    glm::vec3 toEye;
};
PatchView patchViewFrom(float thetaDeg, float phiDeg, int imageSize, double halfExtent);

}  // namespace osgBTF::test
