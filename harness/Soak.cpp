#include "harness/Soak.h"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <fstream>
#include <iomanip>
#include <sstream>

#include <osg/ContextData>
#include <osg/GLExtensions>
#include <osg/Geode>
#include <osg/MatrixTransform>
#include <osg/Texture>
#include <osgDB/ReadFile>
#include <osgViewer/Viewer>

#include "core/Error.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"
#include "scene/MaterialNode.h"

namespace osgBTF {

namespace {

/** The RSS after malloc_trim: free memory the allocator kept (how much depends on what the
 *  process did before, e.g. every other GL test in one process: swings of 7 MiB) goes back to
 *  the system first, so what is left is live memory (within ~0.1 MiB from sample to sample). */
double residentMiB() {
    malloc_trim(0);
    std::ifstream statm("/proc/self/statm");
    long pages = 0, resident = 0;
    statm >> pages >> resident;
    return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

/** Counts the GL objects alive in the context after the frame's draw, when asked: every name up
 *  to beyond the newest one the driver hands out (a fresh name from glGen* bounds the names in
 *  use whether the driver reuses freed names or counts upward). */
class CountObjects : public osg::Camera::DrawCallback {
public:
    mutable bool wanted = false;
    mutable SoakSample counts;

    void operator()(osg::RenderInfo& info) const override {
        if (!wanted) return;
        wanted = false;
        const unsigned id = info.getContextID();
        const osg::GLExtensions* gl = osg::GLExtensions::Get(id, true);
        GLuint probeTexture = 0, probeBuffer = 0;
        glGenTextures(1, &probeTexture);
        gl->glGenBuffers(1, &probeBuffer);
        const GLuint probeShader = gl->glCreateShader(GL_VERTEX_SHADER);
        _bound = std::max({_bound, probeTexture + 4096u, probeBuffer + 4096u, probeShader + 4096u});
        glDeleteTextures(1, &probeTexture);
        gl->glDeleteBuffers(1, &probeBuffer);
        gl->glDeleteShader(probeShader);
        counts = SoakSample();
        for (GLuint name = 1; name < _bound; ++name) {
            counts.textures += glIsTexture(name) ? 1 : 0;
            counts.buffers += gl->glIsBuffer(name) ? 1 : 0;
            counts.programs += gl->glIsProgram(name) ? 1 : 0;
            counts.shaders += gl->glIsShader(name) ? 1 : 0;
        }
        const auto* textures = osg::get<osg::TextureObjectManager>(id);
        counts.osgTextureObjects =
            textures->getNumberActiveTextureObjects() + textures->getNumberOrphanedTextureObjects();
    }

private:
    mutable GLuint _bound = 16384;
};

/** The files read again through osgDB, one patch each in a row along x; their materials. */
osg::ref_ptr<osg::Group> loadScene(const std::vector<std::string>& files,
                                   std::vector<osg::ref_ptr<Material>>& materials,
                                   std::vector<MaterialNode*>& nodes) {
    osg::ref_ptr<osg::Group> root = new osg::Group;
    materials.clear();
    nodes.clear();
    const double width = 1.0 / double(files.size());
    for (std::size_t i = 0; i < files.size(); ++i) {
        osg::ref_ptr<osg::Node> read = osgDB::readRefNodeFile(files[i]);
        auto* node = dynamic_cast<MaterialNode*>(read.get());
        if (!node || !node->getMaterial())
            throw Error(files[i] +
                        ": does not read as a MaterialNode through osgDB (are the "
                        "osgBTF plugins on OSG_LIBRARY_PATH?)");
        node->addChild(createFullScreenQuad().get());
        osg::ref_ptr<osg::MatrixTransform> place = new osg::MatrixTransform(
            osg::Matrix::scale(width, 1, 1) * osg::Matrix::translate(width * double(i), 0, 0));
        place->addChild(node);
        root->addChild(place.get());
        materials.push_back(node->getMaterial());
        nodes.push_back(node);
    }
    return root;
}

}  // namespace

SoakResult runSoak(HeadlessRenderer& renderer, const std::vector<std::string>& materialFiles,
                   const SoakOptions& options) {
    if (materialFiles.empty()) throw Error("soak: no material files");
    if (options.frames < 1 || options.switchEvery < 1 || options.reloadEvery < 1 ||
        options.sampleEvery < 1)
        throw Error("soak: frames and intervals must be at least 1");
    SoakResult result;
    osg::ref_ptr<CountObjects> count = new CountObjects;
    renderer.camera().setPostDrawCallback(count.get());
    std::vector<osg::ref_ptr<Material>> materials;
    std::vector<MaterialNode*> nodes;
    osg::ref_ptr<osg::Group> scene = loadScene(materialFiles, materials, nodes);
    for (const auto& m : materials) result.sceneMiB += double(m->memory().totalBytes) / 1048576.0;
    renderer.render(scene.get(), orthoUnitSquare(64, 64));  // realizes the viewer
    const auto start = std::chrono::steady_clock::now();
    for (int frame = 1; frame <= options.frames; ++frame) {
        if (frame % options.reloadEvery == 0) {
            // The old scene goes first, so the files are opened again (loadSharedMaterial shares
            // only what is still alive) and the old materials' GL objects are released.
            renderer.setScene(nullptr);
            nodes.clear();
            materials.clear();
            scene = nullptr;
            scene = loadScene(materialFiles, materials, nodes);
            renderer.setScene(scene.get());
            ++result.reloads;
            if (frame > options.warmupFrames) ++result.reloadsAfterWarmup;
        } else if (frame % options.switchEvery == 0) {
            const std::size_t shift = std::size_t(frame / options.switchEvery);
            for (std::size_t i = 0; i < nodes.size(); ++i)
                nodes[i]->setMaterial(materials[(i + shift) % materials.size()].get());
            ++result.switches;
        }
        const bool sample = frame % options.sampleEvery == 0;
        count->wanted = sample;
        renderer.viewer().frame();
        if (sample) {
            SoakSample s = count->counts;
            s.frame = frame;
            s.rssMiB = residentMiB();
            result.samples.push_back(s);
        }
    }
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    renderer.camera().setPostDrawCallback(nullptr);

    // Flat: no sample after warm-up above the largest warm-up sample plus the tolerance.
    SoakSample warm;
    bool haveWarm = false, haveLater = false;
    for (const SoakSample& s : result.samples) {
        if (s.frame > options.warmupFrames) {
            haveLater = true;
            continue;
        }
        haveWarm = true;
        warm.rssMiB = std::max(warm.rssMiB, s.rssMiB);
        warm.textures = std::max(warm.textures, s.textures);
        warm.programs = std::max(warm.programs, s.programs);
        warm.shaders = std::max(warm.shaders, s.shaders);
        warm.buffers = std::max(warm.buffers, s.buffers);
        warm.osgTextureObjects = std::max(warm.osgTextureObjects, s.osgTextureObjects);
    }
    if (!haveWarm || !haveLater)
        throw Error("soak: needs samples both within the warm-up (" +
                    std::to_string(options.warmupFrames) + " frames) and after it");
    std::ostringstream growth;
    for (const SoakSample& s : result.samples) {
        if (s.frame <= options.warmupFrames) continue;
        auto judge = [&](const char* what, double now, double before, double tolerance) {
            if (now > before + tolerance)
                growth << "frame " << s.frame << ": " << what << " " << now << " > " << before
                       << " + " << tolerance << "; ";
        };
        judge("RSS MiB", s.rssMiB, warm.rssMiB, options.rssToleranceMiB);
        judge("GL textures", s.textures, warm.textures, options.glObjectTolerance);
        judge("GL programs", s.programs, warm.programs, options.glObjectTolerance);
        judge("GL shaders", s.shaders, warm.shaders, options.glObjectTolerance);
        judge("GL buffers", s.buffers, warm.buffers, options.glObjectTolerance);
        judge("OSG texture objects", s.osgTextureObjects, warm.osgTextureObjects,
              options.glObjectTolerance);
    }
    result.growth = growth.str();
    return result;
}

std::string formatSoak(const SoakResult& result) {
    std::ostringstream out;
    out << "frame     RSS MiB  textures  programs  shaders  buffers  OSG textures\n";
    for (const SoakSample& s : result.samples)
        out << std::setw(5) << s.frame << std::fixed << std::setprecision(1) << std::setw(12)
            << s.rssMiB << std::setw(10) << s.textures << std::setw(10) << s.programs
            << std::setw(9) << s.shaders << std::setw(9) << s.buffers << std::setw(14)
            << s.osgTextureObjects << "\n";
    out << std::setprecision(2) << result.seconds << " s, " << result.switches
        << " material switches, " << result.reloads << " scene reloads ("
        << result.reloadsAfterWarmup << " after warm-up; a scene of " << result.sceneMiB
        << " MiB leaked per reload would add " << result.sceneMiB * result.reloadsAfterWarmup
        << " MiB)\n"
        << (result.growth.empty() ? "flat after warm-up\n" : "GROWTH: " + result.growth + "\n");
    return out.str();
}

}  // namespace osgBTF
