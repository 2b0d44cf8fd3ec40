// osgBTF: OpenGL contexts without a display (EGL device platform, or OSMesa).
//
// libosgBTF contains the EGL back end only. OSMesa lives in the static library osgBTF_osmesa,
// which a program links explicitly (with PkgConfig::OSMesa FIRST on its link line) and enables
// with registerOSMesaBackend() from harness/headless/OSMesaContext.h: a binary that may render on a
// GPU must never link libOSMesa (docs/headless.md 2.3 Rule 3).
#pragma once

#include <osg/GraphicsContext>
#include <osg/ref_ptr>

#include <string>

namespace osgBTF {

enum class HeadlessBackend { Egl, OSMesa };

/** "egl" or "osmesa". */
const char* toString(HeadlessBackend backend);

/** The back end named by the environment variable OSGBTF_HEADLESS ("egl" or "osmesa", any case);
 *  Egl when the variable is unset or empty. Throws osgBTF::Error for any other value. */
HeadlessBackend headlessBackendFromEnvironment();

/** An OpenGL compatibility-profile context with a small pbuffer-like default framebuffer,
 *  for rendering into FBOs. OSG state (osg::State, context ID) is set up by the constructor,
 *  the context is created by the factory and is ready for use by an osgViewer camera. */
class HeadlessContext : public osg::GraphicsContext {
public:
    const char* libraryName() const override { return "osgBTF"; }
    const char* className() const override { return "HeadlessContext"; }

    HeadlessBackend backend() const { return _backend; }
    /** GL_RENDERER / GL_VERSION / GL_SHADING_LANGUAGE_VERSION, read when the context was created,
     *  e.g. "llvmpipe (LLVM 15.0.6, 256 bits)" and "4.5 (Compatibility Profile) Mesa 22.3.6". */
    const std::string& glRenderer() const { return _glRenderer; }
    const std::string& glVersion() const { return _glVersion; }
    const std::string& glslVersion() const { return _glslVersion; }
    /** True for Mesa's software rasterisers (llvmpipe, softpipe, swrast): GL timer queries are
     *  meaningless there (headless.md 4), time with glFinish and clocks instead. */
    bool isSoftwareRenderer() const;

    // osg::GraphicsContext: a headless context has nothing to realize and no texture binding.
    bool realizeImplementation() override {
        _realized = true;
        return true;
    }
    bool isRealizedImplementation() const override { return _realized; }
    bool makeContextCurrentImplementation(osg::GraphicsContext*) override {
        return makeCurrentImplementation();
    }
    void bindPBufferToTextureImplementation(GLenum) override {}

protected:
    HeadlessContext(HeadlessBackend backend, int width, int height);
    ~HeadlessContext() override;

    /** For the factories: makes the context current once (OSG sets up its extension pointers),
     *  reads the GL strings, logs them at OSG_INFO level and releases the context. Throws
     *  osgBTF::Error if the context cannot be made current or reports no GL_VERSION. */
    void queryGLStrings();

    HeadlessBackend _backend;
    bool _realized = false;
    std::string _glRenderer, _glVersion, _glslVersion;
};

/** Creates a headless context of the given back end, W x H default framebuffer (rendering into
 *  FBOs of any size works whatever W x H is). Throws osgBTF::Error with the failing step, e.g.
 *  "EGL headless context: eglInitialize failed on device 0 (EGL error 0x3001 EGL_NOT_INITIALIZED)"
 *  or "the OSMesa back end is not linked into this program; use OSGBTF_HEADLESS=egl". */
osg::ref_ptr<HeadlessContext> createHeadlessContext(HeadlessBackend backend, int width, int height);

/** Same, with the back end from headlessBackendFromEnvironment(). */
osg::ref_ptr<HeadlessContext> createHeadlessContext(int width, int height);

/** The hook a back end outside libosgBTF plugs into (osgBTF_osmesa calls it for OSMesa). A null
 *  factory unregisters. */
using HeadlessContextFactory = osg::ref_ptr<HeadlessContext> (*)(int width, int height);
void registerHeadlessBackend(HeadlessBackend backend, HeadlessContextFactory factory);
bool isHeadlessBackendAvailable(HeadlessBackend backend);

/** The EGL back end itself (what createHeadlessContext(Egl, ...) calls). Device choice: the first
 *  EGL device without EGL_MESA_device_software (a GPU); Mesa's software device (llvmpipe) when
 *  there is none, when the GPU devices fail, or when OSGBTF_EGL_SOFTWARE=1. */
osg::ref_ptr<HeadlessContext> createEglContext(int width, int height);

}  // namespace osgBTF
