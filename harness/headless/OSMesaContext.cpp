// OSMesa back end of the headless context (docs/headless.md 2.3). Compiled into the static
// library osgBTF_osmesa only; see OSMesaContext.h for the link-order rule.
#include "harness/headless/OSMesaContext.h"

#include "core/Error.h"

#include <GL/osmesa.h>

#include <osg/GLExtensions>
#include <osg/Notify>
#include <osg/State>

#include <vector>

namespace osgBTF {

namespace {

class OSMesaContextImpl : public HeadlessContext {
public:
    OSMesaContextImpl(int width, int height)
        : HeadlessContext(HeadlessBackend::OSMesa, width, height),
          _width(width),
          _height(height),
          _buffer(static_cast<size_t>(width) * static_cast<size_t>(height) * 4u) {
        const int attribs[] = {OSMESA_FORMAT,
                               OSMESA_RGBA,
                               OSMESA_DEPTH_BITS,
                               24,
                               OSMESA_STENCIL_BITS,
                               8,
                               OSMESA_PROFILE,
                               OSMESA_COMPAT_PROFILE,
                               0};
        _context = OSMesaCreateContextAttribs(attribs, nullptr);
    }

    const char* className() const override { return "OSMesaContext"; }

    bool valid() const override { return _context != nullptr; }

    bool makeCurrentImplementation() override {
        if (!_context) return false;
        if (!OSMesaMakeCurrent(_context, _buffer.data(), GL_UNSIGNED_BYTE, _width, _height)) {
            OSG_WARN << "osgBTF: OSMesaMakeCurrent failed" << std::endl;
            return false;
        }
        OSMesaPixelStore(OSMESA_Y_UP, 1);
        if (!_extensionsFixed) fixExtensionPointers();
        return true;
    }

    bool releaseContextImplementation() override {
        return OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0) == GL_TRUE;
    }

    void swapBuffersImplementation() override {}

    void closeImplementation() override {
        if (!_context) return;
        if (OSMesaGetCurrentContext() == _context) OSMesaMakeCurrent(nullptr, nullptr, 0, 0, 0);
        OSMesaDestroyContext(_context);
        _context = nullptr;
        _realized = false;
    }

    void finishCreation() { queryGLStrings(); }

    int fixedPointers() const { return _fixedPointers; }

protected:
    ~OSMesaContextImpl() override { close(true); }

private:
    /** OSG 3.6.5 resolves its extension pointers with dlsym(0, name). Where libOSMesa does not
     *  export a name but glvnd's libGL does (about 90 of them: timer queries, texture storage,
     *  double uniforms, ...), OSG gets a libGL stub that goes nowhere, because only EGL/GLX make
     *  glvnd's dispatch current. Redirect every non-null pointer to OSMesa's own entry point. */
    void fixExtensionPointers() {
        _extensionsFixed = true;
        getState()
            ->initializeExtensionProcs();  // idempotent; GraphicsContext::makeCurrent calls it too
        osg::GLExtensions* ext = getState()->get<osg::GLExtensions>();
        if (!ext) {
            OSG_WARN << "osgBTF: OSMesa context has no osg::GLExtensions to fix" << std::endl;
            return;
        }
        int changed = 0, total = 0;
#define OSGBTF_GLEXT(name)                                            \
    if (ext->name) {                                                  \
        ++total;                                                      \
        if (OSMESAproc proc = OSMesaGetProcAddress(#name)) {          \
            auto fixed = reinterpret_cast<decltype(ext->name)>(proc); \
            if (fixed != ext->name) {                                 \
                ext->name = fixed;                                    \
                ++changed;                                            \
            }                                                         \
        }                                                             \
    }
#include "harness/headless/OSMesaExtensionNames.inc"
#undef OSGBTF_GLEXT
        _fixedPointers = changed;
        OSG_INFO << "osgBTF: OSMesa: redirected " << changed << " of " << total
                 << " OSG extension pointers to OSMesaGetProcAddress" << std::endl;
    }

    OSMesaContext _context = nullptr;
    int _width, _height;
    std::vector<unsigned char> _buffer;
    bool _extensionsFixed = false;
    int _fixedPointers = 0;
};

const bool registeredAtStartup = (registerOSMesaBackend(), true);

}  // namespace

void registerOSMesaBackend() {
    (void)registeredAtStartup;
    registerHeadlessBackend(HeadlessBackend::OSMesa, &createOSMesaContext);
}

osg::ref_ptr<HeadlessContext> createOSMesaContext(int width, int height) {
    osg::ref_ptr<OSMesaContextImpl> context = new OSMesaContextImpl(width, height);
    if (!context->valid())
        throw Error(
            "OSMesa headless context: OSMesaCreateContextAttribs (RGBA, depth 24, stencil 8, "
            "compatibility profile) failed");
    context->finishCreation();
    return context;
}

}  // namespace osgBTF
