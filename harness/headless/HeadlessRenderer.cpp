#include "harness/headless/HeadlessRenderer.h"

#include "core/Error.h"
#include "materials/MaterialState.h"
#include "materials/MethodPrograms.h"

#include <osg/Drawable>
#include <osg/GL>
#include <osg/GLExtensions>
#include <osg/Notify>
#include <osg/State>
#include <osg/Texture>
#include <osgUtil/RenderStage>
#include <osgUtil/SceneView>
#include <osgUtil/StateGraph>
#include <osgViewer/Renderer>
#include <osgViewer/Viewer>

#include <algorithm>
#include <chrono>
#include <ctime>

namespace osgBTF {

namespace {

double processCpuMs() {
    timespec ts{};
    clock_gettime(CLOCK_PROCESS_CPUTIME_ID, &ts);
    return static_cast<double>(ts.tv_sec) * 1e3 + static_cast<double>(ts.tv_nsec) * 1e-6;
}

double median(std::vector<double> v) {
    if (v.empty()) return -1;
    std::sort(v.begin(), v.end());
    const size_t n = v.size();
    return n % 2 ? v[n / 2] : 0.5 * (v[n / 2 - 1] + v[n / 2]);
}

}  // namespace

CameraSetup orthoUnitSquare(int width, int height) {
    CameraSetup setup;
    setup.view.makeIdentity();
    setup.projection = osg::Matrixd::ortho(0.0, 1.0, 0.0, 1.0, -1.0, 1.0);
    setup.width = width;
    setup.height = height;
    return setup;
}

osg::ref_ptr<osg::Geometry> createFullScreenQuadGeometry() {
    osg::ref_ptr<osg::Geometry> quad =
        osg::createTexturedQuadGeometry(osg::Vec3(0.f, 0.f, 0.f), osg::Vec3(1.f, 0.f, 0.f),
                                        osg::Vec3(0.f, 1.f, 0.f), 0.f, 0.f, 1.f, 1.f);
    quad->setUseDisplayList(false);
    quad->setUseVertexBufferObjects(true);
    return quad;
}

osg::ref_ptr<osg::Geode> createFullScreenQuad(osg::StateSet* stateSet) {
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(createFullScreenQuadGeometry());
    geode->setCullingActive(false);
    if (stateSet) geode->setStateSet(stateSet);
    return geode;
}

/** What the camera's initial and final draw callbacks share: the GL_TIME_ELAPSED query and the
 *  glFinish that ends every frame. */
namespace detail {
struct FrameTimer : osg::Referenced {
    bool gpuWanted = false;  // time this frame with a GL query
    bool gpuRunning = false;
    GLuint query = 0;
    double gpuMs = -1;  // result of the last timed frame, -1 if none

protected:
    ~FrameTimer() override = default;
};
}  // namespace detail

namespace {

struct BeginFrame : osg::Camera::DrawCallback {
    explicit BeginFrame(detail::FrameTimer* s) : state(s) {}
    void operator()(osg::RenderInfo& info) const override;
    osg::observer_ptr<detail::FrameTimer> state;

protected:
    ~BeginFrame() override = default;
};

struct EndFrame : osg::Camera::DrawCallback {
    explicit EndFrame(detail::FrameTimer* s) : state(s) {}
    void operator()(osg::RenderInfo& info) const override;
    osg::observer_ptr<detail::FrameTimer> state;

protected:
    ~EndFrame() override = default;
};

void BeginFrame::operator()(osg::RenderInfo& info) const {
    osg::ref_ptr<detail::FrameTimer> s;
    if (!state.lock(s)) return;
    s->gpuMs = -1;
    s->gpuRunning = false;
    if (!s->gpuWanted) return;
    const osg::GLExtensions* ext = info.getState()->get<osg::GLExtensions>();
    if (!ext || !ext->isTimerQuerySupported || !ext->glGenQueries || !ext->glBeginQuery) return;
    if (s->query == 0) ext->glGenQueries(1, &s->query);
    ext->glBeginQuery(GL_TIME_ELAPSED, s->query);
    s->gpuRunning = true;
}

void EndFrame::operator()(osg::RenderInfo& info) const {
    osg::ref_ptr<detail::FrameTimer> s;
    const bool timing = state.lock(s) && s->gpuRunning;
    const osg::GLExtensions* ext = info.getState()->get<osg::GLExtensions>();
    if (timing) ext->glEndQuery(GL_TIME_ELAPSED);
    glFinish();
    if (timing) {
        GLuint64 ns = 0;
        ext->glGetQueryObjectui64v(s->query, GL_QUERY_RESULT, &ns);
        s->gpuMs = static_cast<double>(ns) * 1e-6;
        s->gpuRunning = false;
    }
}

}  // namespace

HeadlessRenderer::HeadlessRenderer(osg::ref_ptr<HeadlessContext> context)
    : _context(std::move(context)) {
    if (!_context) throw Error("HeadlessRenderer: no context");
    init();
}

HeadlessRenderer::HeadlessRenderer(HeadlessBackend backend)
    : _context(createHeadlessContext(backend, 64, 64)) {
    init();
}

HeadlessRenderer::HeadlessRenderer() : _context(createHeadlessContext(64, 64)) {
    init();
}

HeadlessRenderer::~HeadlessRenderer() {
    // The scenes were taken out after each render, so closing the context releases nothing of
    // them; the process-wide method programs would keep this context's program objects and hand
    // them to the next context with the same ID (materials/MaterialState.h).
    if (_context && _context->valid() && _context->makeCurrent()) {
        releaseCachedPrograms(_context->getState());
        _context->releaseContext();
    }
    // The viewer closes the context it draws with; then the context is released.
    _viewer = nullptr;
    _context = nullptr;
}

void HeadlessRenderer::init() {
    _timer = new detail::FrameTimer;
    _root = new osg::Group;
    _viewer = new osgViewer::Viewer;
    _viewer->setThreadingModel(osgViewer::ViewerBase::SingleThreaded);
    _viewer->setKeyEventSetsDone(0);
    _viewer->setQuitEventSetsDone(false);

    osg::Camera* cam = _viewer->getCamera();
    cam->setGraphicsContext(_context.get());
    cam->setReferenceFrame(osg::Transform::ABSOLUTE_RF);
    cam->setComputeNearFarMode(osg::CullSettings::DO_NOT_COMPUTE_NEAR_FAR);
    cam->setCullingMode(cam->getCullingMode() & ~osg::CullSettings::SMALL_FEATURE_CULLING);
    cam->setClearMask(GL_COLOR_BUFFER_BIT | GL_DEPTH_BUFFER_BIT);
    cam->setClearColor(osg::Vec4(0.f, 0.f, 0.f, 0.f));
    cam->setRenderTargetImplementation(osg::Camera::FRAME_BUFFER_OBJECT);
    cam->setInitialDrawCallback(new BeginFrame(_timer.get()));
    cam->setFinalDrawCallback(new EndFrame(_timer.get()));
    _viewer->setSceneData(_root.get());
}

osg::Camera& HeadlessRenderer::camera() {
    return *_viewer->getCamera();
}

void HeadlessRenderer::setScene(osg::Node* scene) {
    _root->removeChildren(0, _root->getNumChildren());
    if (scene) _root->addChild(scene);
    // The last frame's render graph outlives it until the next cull prunes it, its StateGraph
    // nodes keyed by the addresses of the StateSets that made them. OSG 3.6.5's
    // ViewDependentShadowMap gives its node another StateSet (ViewDependentShadowMap.cpp:1094),
    // so once the previous scene is deleted that key is a freed address, and a StateSet the
    // next cull allocates there (ShadowMap makes its own in its first cull) is drawn with the
    // deleted technique's state. The new scene starts from an empty graph instead.
    if (auto* renderer = dynamic_cast<osgViewer::Renderer*>(_viewer->getCamera()->getRenderer()))
        for (unsigned i = 0; i < 2; ++i)
            if (osgUtil::SceneView* view = renderer->getSceneView(i)) {
                if (view->getRenderStage()) view->getRenderStage()->reset();
                if (osgUtil::StateGraph* graph = view->getStateGraph()) {
                    graph->clean();
                    graph->prune();
                }
            }
}

void HeadlessRenderer::setClearColor(const osg::Vec4& colour) {
    _viewer->getCamera()->setClearColor(colour);
}

void HeadlessRenderer::setCamera(const CameraSetup& setup) {
    if (setup.width <= 0 || setup.height <= 0)
        throw Error("HeadlessRenderer: viewport " + std::to_string(setup.width) + "x" +
                    std::to_string(setup.height) + " is not positive");
    osg::Camera* cam = _viewer->getCamera();
    cam->setViewMatrix(setup.view);
    cam->setProjectionMatrix(setup.projection);
    if (setup.width == _width && setup.height == _height && _image) return;
    _width = setup.width;
    _height = setup.height;
    cam->setViewport(0, 0, _width, _height);
    attachTarget();
}

void HeadlessRenderer::setColorTarget(GLenum internalFormat, bool readBack) {
    if (readBack && internalFormat != GL_RGBA32F_ARB)
        throw Error("HeadlessRenderer: only the GL_RGBA32F target is read back");
    if (internalFormat == _targetFormat && readBack == _readBack) return;
    _targetFormat = internalFormat;
    _readBack = readBack;
    if (_width > 0) attachTarget();
}

void HeadlessRenderer::attachTarget() {
    osg::Camera* cam = _viewer->getCamera();
    // headless.md pitfall 1: without the internal format OSG makes an RGBA8 renderbuffer. The
    // image is kept either way: it also marks that a camera size was set.
    _image = new osg::Image;
    _image->allocateImage(_width, _height, 1, GL_RGBA, GL_FLOAT);
    _image->setInternalTextureFormat(GL_RGBA32F_ARB);
    cam->detach(osg::Camera::COLOR_BUFFER0);
    cam->detach(osg::Camera::DEPTH_BUFFER);
    if (_readBack)
        cam->attach(osg::Camera::COLOR_BUFFER0, _image.get());
    else
        cam->attach(osg::Camera::COLOR_BUFFER0, _targetFormat);
    cam->attach(osg::Camera::DEPTH_BUFFER, GL_DEPTH_COMPONENT24);
    cam->dirtyAttachmentMap();
}

void HeadlessRenderer::frame() {
    if (!_image) throw Error("HeadlessRenderer: no camera set (call setCamera first)");
    if (!_viewer->isRealized()) {
        _viewer->realize();
        if (!_viewer->isRealized())
            throw Error("HeadlessRenderer: osgViewer could not realize the context");
    }
    _viewer->frame();
}

osg::ref_ptr<osg::Image> HeadlessRenderer::render() {
    if (!_readBack)
        throw Error("HeadlessRenderer: render() needs the read-back target (setColorTarget)");
    frame();
    return new osg::Image(*_image, osg::CopyOp::DEEP_COPY_ALL);
}

osg::ref_ptr<osg::Image> HeadlessRenderer::render(osg::Node* scene, const CameraSetup& setup) {
    setScene(scene);
    setCamera(setup);
    return render();
}

PassTiming HeadlessRenderer::timePasses(int frames, GpuTimer gpu, int warmupFrames) {
    if (frames < 1) throw Error("HeadlessRenderer::timePasses: frames must be at least 1");
    if (warmupFrames < 0)
        throw Error("HeadlessRenderer::timePasses: warm-up frames must be at least 0");
    const bool useGpu = gpu == GpuTimer::On || (gpu == GpuTimer::Auto && !isSoftwareRenderer());
    for (int i = 0; i < warmupFrames; ++i) frame();
    PassTiming timing;
    timing.frames = frames;
    _timer->gpuWanted = useGpu;
    for (int i = 0; i < frames; ++i) {
        const double cpu0 = processCpuMs();
        const auto wall0 = std::chrono::steady_clock::now();
        frame();
        const auto wall1 = std::chrono::steady_clock::now();
        const double cpu1 = processCpuMs();
        timing.wallMsPerFrame.push_back(
            std::chrono::duration<double, std::milli>(wall1 - wall0).count());
        timing.cpuMsPerFrame.push_back(cpu1 - cpu0);
        if (useGpu && _timer->gpuMs >= 0) timing.gpuMsPerFrame.push_back(_timer->gpuMs);
    }
    _timer->gpuWanted = false;
    timing.wallMs = median(timing.wallMsPerFrame);
    timing.cpuMs = median(timing.cpuMsPerFrame);
    timing.gpuMs = median(timing.gpuMsPerFrame);
    return timing;
}

}  // namespace osgBTF
