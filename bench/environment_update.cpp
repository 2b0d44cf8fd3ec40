// Benchmark: Sattler et al. 2003 Table 2's environment update and visibility times on our CPU path.
// Usage: bench_environment_update [--vertices N] [--width W] [--components C]
//                                 [--illumination-pca on|off]
//   A UV sphere of about N vertices standing on a ground plane (self-occlusion by the ground
//   below the equator), a smooth sky with a sun lobe of W x W/2 texels, a PCA material with C
//   components on the 81 x 81 Bonn sampling (fitted on an 8 x 8 sample: the per-vertex work does
//   not depend on the texel count). Prints: per-vertex projection with Embree visibility,
//   the same without visibility, folding (views x (C + 1) RGB per vertex), the folded data's
//   size, the illumination-PCA rebuild of one rotation from 30 samples with 5 components, and
//   the frame time of the lit sphere and ground at 1920x1080 into an RGBA8 target (Sattler et al.
//   2003 Table 2's fps; --fps-frames N timed frames, 0 skips it; the GL renderer is printed).
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <string>

#include <tbb/parallel_for.h>
#include <glm/geometric.hpp>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Group>

#include "environment/VertexEnvironment.h"
#include "harness/headless/HeadlessRenderer.h"
#include "harness/sample/SampleBtf.h"
#include "materials/EnvironmentState.h"
#include "materials/IlluminationPca.h"
#include "materials/MethodOptions.h"
#include "materials/pca/Pca.h"
#include "scene/MaterialNode.h"

using namespace osgBTF;

namespace {

double seconds(std::chrono::steady_clock::time_point since) {
    return std::chrono::duration<double>(std::chrono::steady_clock::now() - since).count();
}

osg::ref_ptr<osg::Geometry> sphere(int rings, int sectors) {
    osg::ref_ptr<osg::Geometry> g = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> v = new osg::Vec3Array, n = new osg::Vec3Array;
    for (int r = 0; r <= rings; ++r)
        for (int s = 0; s <= sectors; ++s) {
            const double t = M_PI * r / rings, p = 2 * M_PI * s / sectors;
            const osg::Vec3 d(std::sin(t) * std::cos(p), std::sin(t) * std::sin(p), std::cos(t));
            v->push_back(d + osg::Vec3(0, 0, 1));
            n->push_back(d);
        }
    g->setVertexArray(v);
    g->setNormalArray(n, osg::Array::BIND_PER_VERTEX);
    osg::ref_ptr<osg::DrawElementsUInt> e = new osg::DrawElementsUInt(GL_TRIANGLES);
    for (int r = 0; r < rings; ++r)
        for (int s = 0; s < sectors; ++s) {
            const unsigned a = r * (sectors + 1) + s, b = a + 1, c = a + sectors + 1, d = c + 1;
            for (unsigned k : {a, c, d, a, d, b}) e->push_back(k);
        }
    g->addPrimitiveSet(e);
    return g;
}

osg::ref_ptr<osg::Geometry> ground() {
    osg::ref_ptr<osg::Geometry> g = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> v = new osg::Vec3Array;
    for (const osg::Vec3& p :
         {osg::Vec3(-5, -5, 0), osg::Vec3(5, -5, 0), osg::Vec3(5, 5, 0), osg::Vec3(-5, 5, 0)})
        v->push_back(p);
    g->setVertexArray(v);
    g->addPrimitiveSet(new osg::DrawArrays(GL_QUADS, 0, 4));
    return g;
}

EnvironmentMap sky(int width) {
    EnvironmentMap m;
    m.width = width;
    m.height = width / 2;
    m.rgb.resize(std::size_t(m.width) * m.height * 3);
    const glm::vec3 sun = glm::normalize(glm::vec3(0.6f, 0.2f, 0.5f));
    for (int r = 0; r < m.height; ++r)
        for (int c = 0; c < m.width; ++c) {
            const glm::vec3 d = m.direction(c + 0.5, r + 0.5);
            const float lobe = std::exp((glm::dot(d, sun) - 1.0f) / 0.02f);
            float* p = m.rgb.data() + (std::size_t(r) * m.width + c) * 3;
            p[0] = 0.4f + 0.3f * d.z + 50.0f * lobe;
            p[1] = 0.5f + 0.3f * d.z + 45.0f * lobe;
            p[2] = 0.8f + 0.2f * d.z + 40.0f * lobe;
        }
    return m;
}

}  // namespace

int main(int argc, char** argv) {
    int vertices = 900, width = 128, components = 16, fpsFrames = 30;
    bool illumination = true;
    for (int i = 1; i + 1 < argc; i += 2) {
        const std::string a = argv[i];
        if (a == "--vertices")
            vertices = std::atoi(argv[i + 1]);
        else if (a == "--width")
            width = std::atoi(argv[i + 1]);
        else if (a == "--components")
            components = std::atoi(argv[i + 1]);
        else if (a == "--fps-frames")
            fpsFrames = std::atoi(argv[i + 1]);
        else if (a == "--illumination-pca")
            illumination = std::string(argv[i + 1]) != "off";
    }
    const int rings = std::max(2, int(std::sqrt(vertices / 2.0)));
    const int sectors = std::max(3, vertices / (rings + 1) - 1);
    osg::ref_ptr<osg::Geode> object = new osg::Geode;
    object->addDrawable(sphere(rings, sectors));
    osg::ref_ptr<osg::Group> scene = new osg::Group;
    scene->addChild(object);
    osg::ref_ptr<osg::Geode> floor = new osg::Geode;
    floor->addDrawable(ground());
    scene->addChild(floor);
    const int n = (rings + 1) * (sectors + 1);

    SampleOptions sample;
    sample.width = sample.height = 8;
    const osg::ref_ptr<PcaMaterial> pca = PcaMaterial::fit(
        makeSampleBtf(sample), FitOptions::parse("components=" + std::to_string(components)));
    const EnvironmentMap map = sky(width);

    auto t0 = std::chrono::steady_clock::now();
    VertexEnvironmentOptions options;
    std::vector<GeometryEnvironment> lit =
        computeVertexEnvironment(*object, scene.get(), pca->lights(), map, options);
    const double withVisibility = seconds(t0);
    t0 = std::chrono::steady_clock::now();
    options.visibility = false;
    computeVertexEnvironment(*object, scene.get(), pca->lights(), map, options);
    const double without = seconds(t0);
    t0 = std::chrono::steady_clock::now();
    std::vector<std::vector<float>> folded(lit[0].g.size());
    tbb::parallel_for(std::size_t(0), folded.size(),
                      [&](std::size_t i) { folded[i] = foldEnvironment(*pca, lit[0].g[i]); });
    const double fold = seconds(t0);
    double occluded = 0;
    for (double omega : lit[0].visibleSolidAngle) occluded += 1.0 - omega / (2 * M_PI);

    std::vector<float> all;
    for (const auto& f : folded) all.insert(all.end(), f.begin(), f.end());
    std::printf("vertices %d, map %d x %d, pca %d components, %zu lights\n", n, map.width,
                map.height, components, pca->lights().size());
    std::printf(
        "projection + Embree visibility: %.2f s (%.2f ms per vertex), mean occluded "
        "share %.3f\n",
        withVisibility, 1e3 * withVisibility / n, occluded / n);
    std::printf("projection without visibility:  %.2f s\n", without);
    std::printf("folding (gamma*):               %.2f s, %.1f MiB of folded data\n", fold,
                double(all.size()) * 4.0 / (1024.0 * 1024.0));
    std::fflush(stdout);
    if (fpsFrames > 0) {
        // The lit sphere as a viewer draws it: under a MaterialNode with the material, the folded
        // data in its geometry's StateSet, the ground plain OSG geometry.
        osg::ref_ptr<MaterialNode> node = new MaterialNode;
        node->setMaterial(pca.get());
        node->addChild(object);
        lit[0].geometry->setStateSet(environmentStateSet(*pca, folded).get());
        osg::ref_ptr<osg::Group> drawn = new osg::Group;
        drawn->addChild(node);
        drawn->addChild(floor);
        HeadlessRenderer renderer;
        renderer.setColorTarget(GL_RGBA8, false);
        renderer.setScene(drawn.get());
        CameraSetup camera;
        camera.width = 1920;
        camera.height = 1080;
        const osg::BoundingSphere bound = object->getBound();
        camera.view =
            osg::Matrixd::lookAt(bound.center() + osg::Vec3(0.0f, -3.0f, 1.2f) * bound.radius(),
                                 bound.center(), osg::Vec3(0, 0, 1));
        camera.projection = osg::Matrixd::perspective(40.0, 1920.0 / 1080.0, 0.1, 100.0);
        renderer.setCamera(camera);
        const PassTiming timing = renderer.timePasses(fpsFrames, GpuTimer::Auto, 3);
        const double ms = timing.gpuMs >= 0 ? timing.gpuMs : timing.wallMs;
        std::printf("render 1920x1080 RGBA8 (%s): %.2f ms per frame (%s, median of %d), %.1f fps\n",
                    renderer.glRenderer().c_str(), ms,
                    timing.gpuMs >= 0 ? "GL_TIME_ELAPSED" : "wall time with glFinish",
                    timing.frames, 1000.0 / ms);
        std::fflush(stdout);
    }
    // Illumination PCA of the folded data of all vertices: the rebuild of one rotation. It holds
    // the 30 samples (30 x the folded data: 4 GB at 9000 vertices; --illumination-pca off).
    if (!illumination) return 0;
    const IlluminationPca ipca = IlluminationPca::build(
        [&](float degrees) {
            std::vector<float> v(all);
            const float s = 1.0f + 0.1f * std::sin(degrees * float(M_PI) / 180.0f);
            for (float& x : v) x *= s;  // the rebuild's cost does not depend on the data
            return v;
        },
        30, 5);
    t0 = std::chrono::steady_clock::now();
    const std::vector<float> rebuilt = ipca.reconstruct(17.0f);
    std::printf("illumination PCA rebuild (30 rotations, 5 components): %.1f ms for %zu values\n",
                1e3 * seconds(t0), rebuilt.size());
    return 0;
}
