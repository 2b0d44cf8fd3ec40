// EGL back end of the headless context: EGL device platform + pbuffer + compatibility profile
// (docs/headless.md 2.1, docs/gpu.md). Links only libEGL and libOpenGL (glvnd).
#include "harness/headless/HeadlessContext.h"

#include "core/Error.h"

#include <EGL/egl.h>
#include <EGL/eglext.h>

#include <osg/Notify>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <map>
#include <mutex>
#include <vector>

namespace osgBTF {

namespace {

std::string eglErrorText(EGLint code) {
    static const char* const names[] = {
        "EGL_SUCCESS",       "EGL_NOT_INITIALIZED",     "EGL_BAD_ACCESS",
        "EGL_BAD_ALLOC",     "EGL_BAD_ATTRIBUTE",       "EGL_BAD_CONFIG",
        "EGL_BAD_CONTEXT",   "EGL_BAD_CURRENT_SURFACE", "EGL_BAD_DISPLAY",
        "EGL_BAD_MATCH",     "EGL_BAD_NATIVE_PIXMAP",   "EGL_BAD_NATIVE_WINDOW",
        "EGL_BAD_PARAMETER", "EGL_BAD_SURFACE",         "EGL_CONTEXT_LOST"};
    char hex[16];
    std::snprintf(hex, sizeof hex, "0x%04X", static_cast<unsigned>(code));
    std::string text = std::string("EGL error ") + hex;
    if (code >= EGL_SUCCESS && code <= EGL_CONTEXT_LOST)
        text += std::string(" ") + names[code - EGL_SUCCESS];
    return text;
}

/** "step failed (EGL error 0x3001 EGL_NOT_INITIALIZED)", with the error eglGetError() reports now.
 */
std::string failed(const std::string& step) {
    return step + " failed (" + eglErrorText(eglGetError()) + ")";
}

bool hasExtension(const char* list, const char* name) {
    if (!list) return false;
    const size_t n = std::strlen(name);
    for (const char* p = list; (p = std::strstr(p, name)) != nullptr; p += n)
        if ((p == list || p[-1] == ' ') && (p[n] == ' ' || p[n] == '\0')) return true;
    return false;
}

/** eglTerminate() on a device display ends every context on it, so count the users per display. */
std::mutex displayMutex;
std::map<EGLDisplay, int> displayUsers;

bool acquireDisplay(EGLDisplay display) {
    std::lock_guard<std::mutex> lock(displayMutex);
    int& users = displayUsers[display];
    if (users == 0) {
        EGLint major = 0, minor = 0;
        if (!eglInitialize(display, &major, &minor)) {
            displayUsers.erase(display);
            return false;
        }
    }
    ++users;
    return true;
}

void releaseDisplay(EGLDisplay display) {
    std::lock_guard<std::mutex> lock(displayMutex);
    auto it = displayUsers.find(display);
    if (it == displayUsers.end()) return;
    if (--it->second == 0) {
        eglTerminate(display);
        displayUsers.erase(it);
    }
}

class EglContext : public HeadlessContext {
public:
    EglContext(int width, int height) : HeadlessContext(HeadlessBackend::Egl, width, height) {}

    const char* className() const override { return "EglContext"; }

    /** Creates display, pbuffer and context on the given device. Returns "" or what failed. */
    std::string create(EGLDisplay display, int width, int height) {
        if (!acquireDisplay(display)) return failed("eglInitialize");
        _display = display;
        if (!eglBindAPI(EGL_OPENGL_API)) return failed("eglBindAPI(EGL_OPENGL_API)");
        const EGLint configAttribs[] = {EGL_SURFACE_TYPE,
                                        EGL_PBUFFER_BIT,
                                        EGL_RENDERABLE_TYPE,
                                        EGL_OPENGL_BIT,
                                        EGL_RED_SIZE,
                                        8,
                                        EGL_GREEN_SIZE,
                                        8,
                                        EGL_BLUE_SIZE,
                                        8,
                                        EGL_ALPHA_SIZE,
                                        8,
                                        EGL_DEPTH_SIZE,
                                        24,
                                        EGL_STENCIL_SIZE,
                                        8,
                                        EGL_NONE};
        EGLConfig config = nullptr;
        EGLint numConfigs = 0;
        if (!eglChooseConfig(display, configAttribs, &config, 1, &numConfigs))
            return failed("eglChooseConfig");
        if (numConfigs < 1)
            return "eglChooseConfig found no pbuffer config with OpenGL, RGBA8, depth 24 and "
                   "stencil 8 (" +
                   eglErrorText(eglGetError()) + ")";
        const EGLint surfaceAttribs[] = {EGL_WIDTH, width, EGL_HEIGHT, height, EGL_NONE};
        _surface = eglCreatePbufferSurface(display, config, surfaceAttribs);
        if (_surface == EGL_NO_SURFACE) return failed("eglCreatePbufferSurface");
        const EGLint contextAttribs[] = {EGL_CONTEXT_OPENGL_PROFILE_MASK,
                                         EGL_CONTEXT_OPENGL_COMPATIBILITY_PROFILE_BIT, EGL_NONE};
        _context = eglCreateContext(display, config, EGL_NO_CONTEXT, contextAttribs);
        if (_context == EGL_NO_CONTEXT)
            return failed("eglCreateContext (OpenGL compatibility profile)");
        return {};
    }

    bool valid() const override { return _context != EGL_NO_CONTEXT; }

    bool makeCurrentImplementation() override {
        if (!valid()) return false;
        if (!eglMakeCurrent(_display, _surface, _surface, _context)) {
            OSG_WARN << "osgBTF: " << failed("eglMakeCurrent") << std::endl;
            return false;
        }
        return true;
    }

    bool releaseContextImplementation() override {
        if (!valid()) return false;
        return eglMakeCurrent(_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT) == EGL_TRUE;
    }

    void swapBuffersImplementation() override {
        if (valid()) eglSwapBuffers(_display, _surface);
    }

    void closeImplementation() override {
        if (_display == EGL_NO_DISPLAY) return;
        if (eglGetCurrentContext() == _context && _context != EGL_NO_CONTEXT)
            eglMakeCurrent(_display, EGL_NO_SURFACE, EGL_NO_SURFACE, EGL_NO_CONTEXT);
        if (_context != EGL_NO_CONTEXT) eglDestroyContext(_display, _context);
        if (_surface != EGL_NO_SURFACE) eglDestroySurface(_display, _surface);
        releaseDisplay(_display);
        _context = EGL_NO_CONTEXT;
        _surface = EGL_NO_SURFACE;
        _display = EGL_NO_DISPLAY;
        _realized = false;
    }

    void finishCreation() { queryGLStrings(); }

protected:
    ~EglContext() override { close(true); }

private:
    EGLDisplay _display = EGL_NO_DISPLAY;
    EGLSurface _surface = EGL_NO_SURFACE;
    EGLContext _context = EGL_NO_CONTEXT;
};

}  // namespace

osg::ref_ptr<HeadlessContext> createEglContext(int width, int height) {
    const std::string what = "EGL headless context: ";
    const char* clientExtensions = eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS);
    if (!clientExtensions)
        throw Error(what + failed("eglQueryString(EGL_NO_DISPLAY, EGL_EXTENSIONS)"));
    const std::string clientList =
        *clientExtensions
            ? std::string(clientExtensions)
            : "none: glvnd found no EGL vendor library; install libegl-mesa0 or a GPU "
              "driver's EGL, or check __EGL_VENDOR_LIBRARY_FILENAMES";
    if (!hasExtension(clientExtensions, "EGL_EXT_device_enumeration") &&
        !hasExtension(clientExtensions, "EGL_EXT_device_base"))
        throw Error(what + "EGL lacks EGL_EXT_device_enumeration (" + eglErrorText(eglGetError()) +
                    "; client extensions: " + clientList + ")");
    if (!hasExtension(clientExtensions, "EGL_EXT_platform_device"))
        throw Error(what + "EGL lacks EGL_EXT_platform_device (" + eglErrorText(eglGetError()) +
                    "; client extensions: " + clientList + ")");

    auto queryDevices =
        reinterpret_cast<PFNEGLQUERYDEVICESEXTPROC>(eglGetProcAddress("eglQueryDevicesEXT"));
    auto queryDeviceString = reinterpret_cast<PFNEGLQUERYDEVICESTRINGEXTPROC>(
        eglGetProcAddress("eglQueryDeviceStringEXT"));
    auto getPlatformDisplay = reinterpret_cast<PFNEGLGETPLATFORMDISPLAYEXTPROC>(
        eglGetProcAddress("eglGetPlatformDisplayEXT"));
    if (!queryDevices || !queryDeviceString || !getPlatformDisplay)
        throw Error(what +
                    "eglGetProcAddress found no eglQueryDevicesEXT, eglQueryDeviceStringEXT or "
                    "eglGetPlatformDisplayEXT");

    EGLint numDevices = 0;
    if (!queryDevices(0, nullptr, &numDevices)) throw Error(what + failed("eglQueryDevicesEXT"));
    if (numDevices <= 0)
        throw Error(
            what + "eglQueryDevicesEXT found no EGL device (" + eglErrorText(eglGetError()) +
            "); install libegl-mesa0 for Mesa's software device or a GPU driver's EGL vendor");
    std::vector<EGLDeviceEXT> devices(static_cast<size_t>(numDevices));
    if (!queryDevices(numDevices, devices.data(), &numDevices))
        throw Error(what + failed("eglQueryDevicesEXT"));
    devices.resize(static_cast<size_t>(numDevices));

    // Order of preference: GPU devices in EGL's order, then Mesa's software device.
    const char* forceEnv = std::getenv("OSGBTF_EGL_SOFTWARE");
    const bool forceSoftware = forceEnv && std::strcmp(forceEnv, "1") == 0;
    std::vector<int> hardware, software;
    for (int i = 0; i < numDevices; ++i) {
        const char* extensions = queryDeviceString(devices[static_cast<size_t>(i)], EGL_EXTENSIONS);
        (hasExtension(extensions, "EGL_MESA_device_software") ? software : hardware).push_back(i);
    }
    std::vector<int> order = software;
    if (!forceSoftware) order.insert(order.begin(), hardware.begin(), hardware.end());
    if (order.empty())
        throw Error(what + "OSGBTF_EGL_SOFTWARE=1 but none of the " + std::to_string(numDevices) +
                    " EGL devices is a software device (EGL_MESA_device_software)");

    std::string failures;
    for (int i : order) {
        const bool isSoftware = std::find(software.begin(), software.end(), i) != software.end();
        const std::string device =
            "device " + std::to_string(i) + (isSoftware ? " (software)" : " (GPU)");
        EGLDisplay display =
            getPlatformDisplay(EGL_PLATFORM_DEVICE_EXT, devices[static_cast<size_t>(i)], nullptr);
        std::string problem;
        osg::ref_ptr<EglContext> context;
        if (display == EGL_NO_DISPLAY) {
            problem = failed("eglGetPlatformDisplayEXT(EGL_PLATFORM_DEVICE_EXT)");
        } else {
            context = new EglContext(width, height);
            problem = context->create(display, width, height);
        }
        if (problem.empty()) {
            context->finishCreation();
            if (!failures.empty())
                OSG_WARN << "osgBTF: EGL fell back to " << device << " (\"" << context->glRenderer()
                         << "\") after:" << failures << std::endl;
            OSG_INFO << "osgBTF: EGL uses " << device << " of " << numDevices << std::endl;
            return context;
        }
        failures += "\n  " + device + ": " + problem;
        context = nullptr;  // destroys what was created
    }
    throw Error(what + "no EGL device gave an OpenGL context:" + failures);
}

}  // namespace osgBTF
