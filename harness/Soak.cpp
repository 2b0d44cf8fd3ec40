#include "harness/Soak.h"

#include <algorithm>
#include <chrono>
#include <cstdio>
#include <iomanip>
#include <sstream>

#include <osg/Geode>
#include <osg/MatrixTransform>
#include <osgDB/ReadFile>
#include <osgViewer/Viewer>

#include "core/Error.h"
#include "harness/SoakSampling.h"
#include "harness/headless/HeadlessRenderer.h"
#include "materials/Material.h"
#include "scene/MaterialNode.h"

namespace osgBTF {

namespace {

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
    osg::ref_ptr<CountGlObjects> count = new CountGlObjects;
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
            s.rssMiB = trimmedResidentMiB();
            result.samples.push_back(s);
        }
    }
    result.seconds =
        std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
    renderer.camera().setPostDrawCallback(nullptr);

    try {
        result.growth = growthAfterWarmup(
            result.samples, [&](const SoakSample& s) { return s.frame <= options.warmupFrames; },
            options.rssToleranceMiB, options.glObjectTolerance);
    } catch (const Error&) {
        throw Error("soak: needs samples both within the warm-up (" +
                    std::to_string(options.warmupFrames) + " frames) and after it");
    }
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
