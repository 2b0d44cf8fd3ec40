#include "harness/SoakSampling.h"

#include <malloc.h>
#include <unistd.h>

#include <algorithm>
#include <fstream>
#include <sstream>

#include <osg/ContextData>
#include <osg/GLExtensions>
#include <osg/RenderInfo>
#include <osg/Texture>

#include "core/Error.h"

namespace osgBTF {

double trimmedResidentMiB() {
    malloc_trim(0);
    std::ifstream statm("/proc/self/statm");
    long pages = 0, resident = 0;
    statm >> pages >> resident;
    return double(resident) * double(sysconf(_SC_PAGESIZE)) / (1024.0 * 1024.0);
}

void CountGlObjects::operator()(osg::RenderInfo& info) const {
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

std::string judgeGrowth(const std::vector<const SoakSample*>& warmSamples,
                        const std::vector<const SoakSample*>& laterSamples, double rssToleranceMiB,
                        int glObjectTolerance) {
    if (warmSamples.empty() || laterSamples.empty())
        throw Error("soak: needs samples both within the warm-up and after it");
    // Flat: no sample after warm-up above the largest warm-up sample plus the tolerance.
    SoakSample warm;
    for (const SoakSample* s : warmSamples) {
        warm.rssMiB = std::max(warm.rssMiB, s->rssMiB);
        warm.textures = std::max(warm.textures, s->textures);
        warm.programs = std::max(warm.programs, s->programs);
        warm.shaders = std::max(warm.shaders, s->shaders);
        warm.buffers = std::max(warm.buffers, s->buffers);
        warm.osgTextureObjects = std::max(warm.osgTextureObjects, s->osgTextureObjects);
    }
    std::ostringstream growth;
    for (const SoakSample* s : laterSamples) {
        auto judge = [&](const char* what, double now, double before, double tolerance) {
            if (now > before + tolerance)
                growth << "frame " << s->frame << ": " << what << " " << now << " > " << before
                       << " + " << tolerance << "; ";
        };
        judge("RSS MiB", s->rssMiB, warm.rssMiB, rssToleranceMiB);
        judge("GL textures", s->textures, warm.textures, glObjectTolerance);
        judge("GL programs", s->programs, warm.programs, glObjectTolerance);
        judge("GL shaders", s->shaders, warm.shaders, glObjectTolerance);
        judge("GL buffers", s->buffers, warm.buffers, glObjectTolerance);
        judge("OSG texture objects", s->osgTextureObjects, warm.osgTextureObjects,
              glObjectTolerance);
    }
    return growth.str();
}

}  // namespace osgBTF
