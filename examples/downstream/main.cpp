// osgbtf-downstream MODEL MATERIAL [OUT.ppm]: loads MODEL, renders it once plain and once under an
// osgBTF::MaterialNode with the fitted MATERIAL (a .btfmat or fitted .exr), one frame each, in a
// 256x256 window (run it under xvfb-run on a machine without a display), and checks that the
// material was applied: its shader program linked in this context, the model covers the image
// both times, and the material changed the colours. Prints what it measured; exit status 0 only
// when all of that holds. OUT.ppm keeps the material frame.
#include <cmath>
#include <cstdio>
#include <fstream>
#include <iostream>
#include <string>

#include <osg/ComputeBoundsVisitor>
#include <osg/Image>
#include <osg/Program>
#include <osgDB/ReadFile>
#include <osgViewer/Viewer>

#include <osgBTF/Error>
#include <osgBTF/Material>
#include <osgBTF/MaterialNode>
#include <osgBTF/Version>

namespace {

constexpr int kSize = 256;

struct Frame {
    osg::ref_ptr<osg::Image> image;
    int covered = 0;       // pixels brighter than the black background
    osg::Vec3d meanColor;  // over the covered pixels, 0..1
};

/** Renders `scene` into `target` (attached to the camera once, before realize: the camera reads
 *  each frame back into it) and measures a copy. */
Frame renderOnce(osgViewer::Viewer& viewer, osg::Image& target, osg::Node* scene) {
    viewer.setSceneData(scene);
    viewer.frame();
    Frame frame;
    frame.image = new osg::Image(target, osg::CopyOp::DEEP_COPY_ALL);
    for (int y = 0; y < kSize; ++y)
        for (int x = 0; x < kSize; ++x) {
            const unsigned char* p = frame.image->data(x, y);
            if (p[0] + p[1] + p[2] <= 6) continue;
            ++frame.covered;
            frame.meanColor += osg::Vec3d(p[0], p[1], p[2]) / 255.0;
        }
    if (frame.covered) frame.meanColor /= frame.covered;
    return frame;
}

void writePpm(const osg::Image& image, const std::string& path) {
    std::ofstream out(path, std::ios::binary);
    out << "P6\n" << image.s() << " " << image.t() << "\n255\n";
    for (int y = image.t() - 1; y >= 0; --y)  // OSG's row 0 is the bottom
        for (int x = 0; x < image.s(); ++x)
            out.write(reinterpret_cast<const char*>(image.data(x, y)), 3);
}

}  // namespace

int main(int argc, char** argv) {
    if (argc < 3) {
        std::cerr << "usage: osgbtf-downstream MODEL MATERIAL [OUT.ppm]\n";
        return 2;
    }
    std::cout << "osgBTF " << OSGBTF_VERSION_STRING << "\n";
    osg::ref_ptr<osg::Node> model = osgDB::readRefNodeFile(argv[1]);
    if (!model) {
        std::cerr << argv[1] << ": cannot read the model\n";
        return 1;
    }
    osg::ref_ptr<osgBTF::Material> material;
    try {
        material = osgBTF::loadMaterial(argv[2]);
    } catch (const osgBTF::Error& e) {
        std::cerr << e.what() << "\n";
        return 1;
    }
    osg::ref_ptr<osgBTF::MaterialNode> node = new osgBTF::MaterialNode(material.get());
    node->setTextureScale(4);

    osg::ref_ptr<osg::GraphicsContext::Traits> traits = new osg::GraphicsContext::Traits;
    traits->readDISPLAY();  // the X display xvfb-run (or the desktop) gives us
    traits->setUndefinedScreenDetailsToDefaultScreen();
    traits->width = traits->height = kSize;
    traits->doubleBuffer = true;
    traits->windowDecoration = false;
    osg::ref_ptr<osg::GraphicsContext> context =
        osg::GraphicsContext::createGraphicsContext(traits.get());
    if (!context) {
        std::cerr << "no OpenGL window (no X display? run under xvfb-run)\n";
        return 1;
    }
    osgViewer::Viewer viewer;
    viewer.setThreadingModel(osgViewer::Viewer::SingleThreaded);
    osg::Camera* camera = viewer.getCamera();
    camera->setGraphicsContext(context.get());
    camera->setViewport(0, 0, kSize, kSize);
    camera->setClearColor(osg::Vec4(0, 0, 0, 1));
    osg::ComputeBoundsVisitor bounds;
    model->accept(bounds);
    const osg::BoundingSphere sphere(bounds.getBoundingBox());
    const double r = sphere.radius();
    camera->setViewMatrixAsLookAt(sphere.center() + osg::Vec3d(0, -3.2 * r, 1.2 * r),
                                  sphere.center(), osg::Vec3d(0, 0, 1));
    camera->setProjectionMatrixAsPerspective(30, 1, 0.1 * r, 10 * r);
    osg::ref_ptr<osg::Image> target = new osg::Image;
    target->allocateImage(kSize, kSize, 1, GL_RGBA, GL_UNSIGNED_BYTE);
    camera->attach(osg::Camera::COLOR_BUFFER, target.get());
    viewer.realize();

    const Frame plain = renderOnce(viewer, *target, model.get());
    node->addChild(model.get());  // after the plain frame: this adds tangents to the model
    const Frame textured = renderOnce(viewer, *target, node.get());

    const auto* program = dynamic_cast<const osg::Program*>(
        material->sharedStateSet()->getAttribute(osg::StateAttribute::PROGRAM));
    osg::Program::PerContextProgram* pcp =
        program ? program->getPCP(*context->getState()) : nullptr;
    const bool linked = pcp && pcp->isLinked();
    const double change = (textured.meanColor - plain.meanColor).length();
    std::printf("model %s: %d of %d pixels, mean colour %.3f %.3f %.3f\n", argv[1], plain.covered,
                kSize * kSize, plain.meanColor.x(), plain.meanColor.y(), plain.meanColor.z());
    std::printf("under MaterialNode (%s, %s): %d pixels, mean colour %.3f %.3f %.3f, program %s\n",
                material->methodName().c_str(), argv[2], textured.covered, textured.meanColor.x(),
                textured.meanColor.y(), textured.meanColor.z(), linked ? "linked" : "NOT linked");
    if (argc > 3) writePpm(*textured.image, argv[3]);

    const int minimum = kSize * kSize / 50;  // the model fills at least 2% of the frame
    bool ok = true;
    if (!linked) ok = false, std::cerr << "the material's shader program did not link\n";
    if (plain.covered < minimum || textured.covered < minimum)
        ok = false, std::cerr << "the model is (nearly) invisible\n";
    if (change < 0.05)
        ok = false, std::cerr << "the material did not change the colours (" << change << ")\n";
    std::printf("%s: colour change %.3f\n", ok ? "material applied" : "FAILED", change);
    return ok ? 0 : 1;
}
