#include "harness/headless/HeadlessContext.h"

#include "core/Error.h"

#include <osg/GL>
#include <osg/Notify>
#include <osg/State>

#include <algorithm>
#include <cctype>
#include <cstdlib>
#include <mutex>

namespace osgBTF {

namespace {

struct Registry {
    std::mutex mutex;
    HeadlessContextFactory factories[2] = {&createEglContext, nullptr};
};

Registry& registry() {
    static Registry r;
    return r;
}

int index(HeadlessBackend backend) {
    return backend == HeadlessBackend::Egl ? 0 : 1;
}

std::string glString(GLenum name) {
    const GLubyte* s = glGetString(name);
    return s ? reinterpret_cast<const char*>(s) : std::string();
}

}  // namespace

const char* toString(HeadlessBackend backend) {
    return backend == HeadlessBackend::Egl ? "egl" : "osmesa";
}

HeadlessBackend headlessBackendFromEnvironment() {
    const char* env = std::getenv("OSGBTF_HEADLESS");
    if (!env || !*env) return HeadlessBackend::Egl;
    std::string value(env);
    std::string lower = value;
    std::transform(lower.begin(), lower.end(), lower.begin(),
                   [](unsigned char c) { return static_cast<char>(std::tolower(c)); });
    if (lower == "egl") return HeadlessBackend::Egl;
    if (lower == "osmesa") return HeadlessBackend::OSMesa;
    throw Error("OSGBTF_HEADLESS='" + value +
                "' names no headless back end; use OSGBTF_HEADLESS=egl or OSGBTF_HEADLESS=osmesa");
}

void registerHeadlessBackend(HeadlessBackend backend, HeadlessContextFactory factory) {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.mutex);
    r.factories[index(backend)] = factory;
}

bool isHeadlessBackendAvailable(HeadlessBackend backend) {
    Registry& r = registry();
    std::lock_guard<std::mutex> lock(r.mutex);
    return r.factories[index(backend)] != nullptr;
}

osg::ref_ptr<HeadlessContext> createHeadlessContext(HeadlessBackend backend, int width,
                                                    int height) {
    if (width <= 0 || height <= 0)
        throw Error("headless context: size " + std::to_string(width) + "x" +
                    std::to_string(height) + " is not positive");
    HeadlessContextFactory factory;
    {
        Registry& r = registry();
        std::lock_guard<std::mutex> lock(r.mutex);
        factory = r.factories[index(backend)];
    }
    if (!factory) {
        if (backend == HeadlessBackend::OSMesa)
            throw Error(
                "the OSMesa back end is not linked into this program; use OSGBTF_HEADLESS=egl");
        throw Error(std::string("the ") + toString(backend) +
                    " headless back end is not registered");
    }
    osg::ref_ptr<HeadlessContext> context = factory(width, height);
    if (!context)
        throw Error(std::string("the ") + toString(backend) + " back end returned no context");
    return context;
}

osg::ref_ptr<HeadlessContext> createHeadlessContext(int width, int height) {
    return createHeadlessContext(headlessBackendFromEnvironment(), width, height);
}

HeadlessContext::HeadlessContext(HeadlessBackend backend, int width, int height)
    : _backend(backend) {
    osg::ref_ptr<Traits> traits = new Traits;
    traits->x = 0;
    traits->y = 0;
    traits->width = width;
    traits->height = height;
    traits->red = traits->green = traits->blue = traits->alpha = 8;
    traits->depth = 24;
    traits->stencil = 8;
    traits->doubleBuffer = false;
    traits->pbuffer = true;
    traits->windowDecoration = false;
    _traits = traits;

    setState(new osg::State);
    getState()->setGraphicsContext(this);
    getState()->setContextID(osg::GraphicsContext::createNewContextID());
}

HeadlessContext::~HeadlessContext() = default;

bool HeadlessContext::isSoftwareRenderer() const {
    for (const char* name : {"llvmpipe", "softpipe", "swrast", "Software Rasterizer"})
        if (_glRenderer.find(name) != std::string::npos) return true;
    return false;
}

void HeadlessContext::queryGLStrings() {
    const std::string what = std::string(toString(_backend)) + " headless context";
    if (!makeCurrent()) throw Error(what + ": the new context cannot be made current");
    _glRenderer = glString(GL_RENDERER);
    _glVersion = glString(GL_VERSION);
    _glslVersion = glString(GL_SHADING_LANGUAGE_VERSION);
    const std::string vendor = glString(GL_VENDOR);
    releaseContext();
    if (_glVersion.empty())
        throw Error(
            what +
            ": glGetString(GL_VERSION) returned nothing; the GL calls do not reach the "
            "context (with OSMesa, libOSMesa must come before libGL/libOpenGL on the link line)");
    OSG_INFO << "osgBTF: " << what << ": GL_RENDERER=\"" << _glRenderer << "\" GL_VERSION=\""
             << _glVersion << "\" GLSL=\"" << _glslVersion << "\" GL_VENDOR=\"" << vendor << "\""
             << std::endl;
}

}  // namespace osgBTF
