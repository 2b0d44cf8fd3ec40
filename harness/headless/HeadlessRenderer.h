// osgBTF: render an OSG subgraph headless into a float image, and time passes.
#pragma once

#include "harness/headless/HeadlessContext.h"

#include <osg/Camera>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Group>
#include <osg/Image>
#include <osg/Matrixd>
#include <osg/ref_ptr>

#include <string>
#include <vector>

namespace osgViewer {
class Viewer;
}

namespace osgBTF {

namespace detail {
struct FrameTimer;  // HeadlessRenderer.cpp
}

/** Where the camera looks from and what it sees: view and projection matrices, viewport W x H. */
struct CameraSetup {
    osg::Matrixd view;        // identity by default
    osg::Matrixd projection;  // identity by default
    int width = 0;
    int height = 0;
};

/** View = identity, projection = ortho(0..1, 0..1, -1..1), viewport W x H: with
 *  createFullScreenQuad() pixel (i, j) is centred at texture coordinate ((i+0.5)/W, (j+0.5)/H). */
CameraSetup orthoUnitSquare(int width, int height);

/** The unit square (0,0,0)-(1,1,0) in the XY plane, normal +Z, texture coordinates 0..1 on unit
 *  0, white colour; for orthoUnitSquare(). */
osg::ref_ptr<osg::Geometry> createFullScreenQuadGeometry();
/** A Geode holding createFullScreenQuadGeometry(), with the given state set (may be null). */
osg::ref_ptr<osg::Geode> createFullScreenQuad(osg::StateSet* stateSet = nullptr);

/** Medians over the timed frames (warm-up frames are never timed). */
struct PassTiming {
    int frames = 0;
    double wallMs = 0;  // steady_clock around a frame that ends with glFinish (includes read-back)
    double cpuMs = 0;   // CLOCK_PROCESS_CPUTIME_ID: all threads, llvmpipe's raster threads included
    double gpuMs = -1;  // GL_TIME_ELAPSED around the camera's draw; -1 when not measured
    std::vector<double> wallMsPerFrame, cpuMsPerFrame, gpuMsPerFrame;
};

enum class GpuTimer {
    Auto,  // GL timer queries only when the renderer is not software (llvmpipe's are wrong)
    On,    // always (when GL_ARB_timer_query is there)
    Off
};

/** One headless context plus one osgViewer::Viewer whose master camera renders into a float FBO
 *  (FRAME_BUFFER_OBJECT, colour GL_RGBA32F read back into a GL_RGBA/GL_FLOAT osg::Image, depth 24).
 *  Reusable: create it once per process and render many scenes, sizes and frames; creating a
 *  context per render is slow and leaks under ASan. One renderer per context (OSG draws every
 *  camera attached to a context), single-threaded, on the thread that created it. Destroying the
 *  renderer closes the context. */
class HeadlessRenderer {
public:
    /** Takes over the context. */
    explicit HeadlessRenderer(osg::ref_ptr<HeadlessContext> context);
    /** Creates its own context (64 x 64 default framebuffer; the FBO size is the viewport's). */
    explicit HeadlessRenderer(HeadlessBackend backend);
    /** Same, back end from OSGBTF_HEADLESS (default EGL). */
    HeadlessRenderer();
    ~HeadlessRenderer();
    HeadlessRenderer(const HeadlessRenderer&) = delete;
    HeadlessRenderer& operator=(const HeadlessRenderer&) = delete;

    HeadlessContext& context() const { return *_context; }
    HeadlessBackend backend() const { return _context->backend(); }
    const std::string& glRenderer() const { return _context->glRenderer(); }
    const std::string& glVersion() const { return _context->glVersion(); }
    bool isSoftwareRenderer() const { return _context->isSoftwareRenderer(); }

    /** The subgraph to render (replaces the previous one; null renders nothing but the clear).
     *  Also empties the viewer's render graph of the last frame, so nothing of the previous
     *  scene's state reaches the next frame (HeadlessRenderer.cpp says how it could). */
    void setScene(osg::Node* scene);
    /** Camera matrices and viewport; a new size reallocates the FBO on the next frame. */
    void setCamera(const CameraSetup& setup);
    /** Default (0, 0, 0, 0). */
    void setClearColor(const osg::Vec4& colour);
    /** The colour buffer the camera draws into. Default GL_RGBA32F_ARB read back after every
     *  frame into the float image render() returns (what GPU == CPU checks need). With readBack
     *  false the target is a renderbuffer of `internalFormat` (GL_RGBA8, GL_RGBA16F_ARB, ...) that
     *  is never read: a viewer's frame, for timePasses(); render() then throws. Takes effect on
     *  the next frame. */
    void setColorTarget(GLenum internalFormat, bool readBack);
    GLenum colorTargetFormat() const { return _targetFormat; }

    /** Renders one frame and returns a copy of the GL_RGBA / GL_FLOAT image, W x H, rows
     *  bottom-up as OSG gives them: pixel (x, y) is at getDataPointer() + 4 * (y * W + x) floats.
     *  Throws osgBTF::Error if no camera size was set. */
    osg::ref_ptr<osg::Image> render();
    osg::ref_ptr<osg::Image> render(osg::Node* scene, const CameraSetup& setup);

    /** Renders `warmupFrames` untimed frames (shader compilation, uploads, caches), then
     *  `frames` timed frames of the current scene and camera, each ending with glFinish. Throws
     *  osgBTF::Error for frames < 1 or warmupFrames < 0. */
    PassTiming timePasses(int frames, GpuTimer gpu = GpuTimer::Auto, int warmupFrames = 1);

    /** For what this class does not offer (state sets on the master camera, lighting mode). */
    osgViewer::Viewer& viewer() { return *_viewer; }
    osg::Camera& camera();

private:
    void init();
    void frame();
    void attachTarget();

    osg::ref_ptr<HeadlessContext> _context;
    osg::ref_ptr<osgViewer::Viewer> _viewer;
    osg::ref_ptr<osg::Group> _root;
    osg::ref_ptr<osg::Image> _image;
    osg::ref_ptr<detail::FrameTimer> _timer;
    int _width = 0, _height = 0;
    GLenum _targetFormat = GL_RGBA32F_ARB;
    bool _readBack = true;
};

}  // namespace osgBTF
