#include "examples/btf-examples/Gallery.h"

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <fstream>
#include <iomanip>
#include <iostream>
#include <sstream>

#include <osg/Geode>
#include <osg/Geometry>
#include <osg/LightSource>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/Progress.h"
#include "examples/ExampleScenes.h"
#include "examples/btf-examples/SceneBench.h"
#include "harness/Compare.h"
#include "harness/MaterialImage.h"
#include "harness/Pictures.h"
#include "harness/headless/HeadlessRenderer.h"
#include "harness/sample/SampleBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "scene/EnvironmentLight.h"
#include "scene/MaterialNode.h"

namespace osgBTF::examples {

namespace fs = std::filesystem;

const std::vector<GalleryView>& galleryViews() {
    static const std::vector<GalleryView> views = {
        {"close-up", "close-up: 4 x 4 texels fill the picture (magnification)"},
        {"grazing", "grazing: the surface seen 78 degrees from its normal"},
        {"distance",
         "distance: a 60 m floor, one sample repeat per metre, toward the horizon "
         "(minification)"},
        {"environment",
         "environment: the patch lit by the procedural sky (exposure 0.3), seen from 45 degrees, "
         "a pixel per texel"},
        {"shadows",
         "shadows: the draped cloth under osgShadow::ShadowMap and the smooth "
         "terminator"}};
    return views;
}

namespace {

// The sky's sun is bright: at exposure 1 the lit cloth clips to white in an 8-bit picture.
constexpr float kEnvironmentExposure = 0.3f;

/** A flat square of `extent` metres in the XY plane (normal +Z), texture coordinates 0..1 across
 *  it: the surface of the close-up, grazing and distance views. */
osg::ref_ptr<osg::Geode> createFloor(float extent) {
    osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec2Array> coordinates = new osg::Vec2Array;
    for (const osg::Vec2& corner :
         {osg::Vec2(0, 0), osg::Vec2(1, 0), osg::Vec2(1, 1), osg::Vec2(0, 1)}) {
        vertices->push_back(
            osg::Vec3((corner.x() - 0.5f) * extent, (corner.y() - 0.5f) * extent, 0.0f));
        normals->push_back(osg::Vec3(0.0f, 0.0f, 1.0f));
        coordinates->push_back(corner);
    }
    geometry->setVertexArray(vertices.get());
    geometry->setNormalArray(normals.get(), osg::Array::BIND_PER_VERTEX);
    geometry->setTexCoordArray(0, coordinates.get());
    geometry->addPrimitiveSet(new osg::DrawArrays(GL_TRIANGLE_FAN, 0, 4));
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(geometry.get());
    return geode;
}

/** The floor under a MaterialNode (textureScale repeats across it) and the example scenes' two
 *  lights (a warm key light from the upper left front, a cool point light). */
osg::ref_ptr<osg::Group> floorScene(Material& material, float extent, float textureScale) {
    osg::ref_ptr<osg::Group> root = new osg::Group;
    for (const osg::ref_ptr<osg::LightSource>& light : createTwoLights(extent))
        root->addChild(light.get());
    osg::ref_ptr<MaterialNode> node = new MaterialNode(&material);
    node->setTextureScale(textureScale);
    node->addChild(createFloor(extent).get());
    root->addChild(node.get());
    return root;
}

CameraSetup lookAt(const osg::Vec3d& eye, const osg::Vec3d& centre, double fovy, double nearPlane,
                   double farPlane, int size) {
    CameraSetup setup;
    setup.view = osg::Matrixd::lookAt(eye, centre, osg::Vec3d(0.0, 0.0, 1.0));
    setup.projection = osg::Matrixd::perspective(fovy, 1.0, nearPlane, farPlane);
    setup.width = setup.height = size;
    return setup;
}

FloatImage toRgb(const osg::Image& image) {
    const int w = image.s(), h = image.t();
    FloatImage out(w, h, 3);
    out.channelNames = {"R", "G", "B"};
    const float* rgba = reinterpret_cast<const float*>(image.data());
    for (int y = 0; y < h; ++y)  // OSG's rows are bottom-up, an image file's top-down
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c)
                out.at(x, h - 1 - y, c) = rgba[(std::size_t(y) * w + x) * 4 + c];
    return out;
}

FloatImage renderScene(HeadlessRenderer& renderer, osg::Node* scene, const CameraSetup& camera) {
    osg::ref_ptr<osg::Image> image = renderer.render(scene, camera);
    renderer.setScene(nullptr);
    return toRgb(*image);
}

/** Renders one view of `material` (fitted file `materialFile`); `sky` for the environment. */
FloatImage renderView(HeadlessRenderer& renderer, const std::string& view, Material& material,
                      const std::string& materialFile, const EnvironmentMap& sky, int size) {
    const int texels = std::max(
        1, material.mipLayout().mipMapped() ? material.mipLayout().baseWidth() : material.width());
    if (view == "close-up") {
        // A 1 m floor with the sample once across it; the camera straight above its centre sees
        // 4 texels' width.
        const double seen = 4.0 / texels, fovy = 30.0;
        const double height = 0.5 * seen / std::tan(osg::DegreesToRadians(fovy / 2.0));
        osg::ref_ptr<osg::Group> scene = floorScene(material, 1.0f, 1.0f);
        return renderScene(renderer, scene.get(),
                           lookAt(osg::Vec3d(0.0, -1e-3, height), osg::Vec3d(0.0, 0.0, 0.0), fovy,
                                  0.1 * height, 10.0 * height, size));
    }
    if (view == "grazing") {
        // 12 degrees above a 1 m floor repeating the sample 4 times, 0.6 m away.
        const double elevation = osg::DegreesToRadians(12.0), distance = 0.6;
        osg::ref_ptr<osg::Group> scene = floorScene(material, 1.0f, 4.0f);
        return renderScene(
            renderer, scene.get(),
            lookAt(osg::Vec3d(0.0, -distance * std::cos(elevation), distance * std::sin(elevation)),
                   osg::Vec3d(0.0, 0.0, 0.0), 40.0, 0.01, 10.0, size));
    }
    if (view == "distance") {
        // Eye height 1.6 m at one edge of a 60 m floor, looking 20 m ahead.
        osg::ref_ptr<osg::Group> scene = floorScene(material, 60.0f, 60.0f);
        return renderScene(renderer, scene.get(),
                           lookAt(osg::Vec3d(0.0, -28.0, 1.6), osg::Vec3d(0.0, -8.0, 0.0), 50.0,
                                  0.1, 100.0, size));
    }
    if (view == "environment") {
        const std::vector<glm::vec3> g = projectPatchEnvironment(material, sky);
        const FloatImage patch = renderEnvironmentImage(
            renderer, material, g, Direction{45.0f, 0.0f}.toVector(), kEnvironmentExposure);
        return enlarge(patch, std::max(1, size / std::max(1, patch.width)));
    }
    if (view == "shadows") {
        osg::ref_ptr<osg::Group> scene = createShadowedClothScene(materialFile, 4.0f, nullptr);
        return renderScene(renderer, scene.get(), frontCamera(*scene, size, size));
    }
    throw Error("gallery: unknown view '" + view + "'");
}

std::string html(const std::string& text) {
    std::string out;
    for (char c : text) {
        switch (c) {
            case '&':
                out += "&amp;";
                break;
            case '<':
                out += "&lt;";
                break;
            case '>':
                out += "&gt;";
                break;
            case '"':
                out += "&quot;";
                break;
            default:
                out += c;
        }
    }
    return out;
}

std::string significantDigits(double value, int digits) {
    std::ostringstream s;
    s << std::setprecision(digits) << value;
    return s.str();
}

void writeText(const std::string& text, const fs::path& path) {
    std::ofstream out(path);
    out << text;
    if (!out.flush()) fail(path.string(), "cannot write");
}

/** The page: a row per method, its figures, then one picture per view. A small script counts
 *  the pictures the browser could show and says so on the page (and in the body's
 *  data-pictures-shown attribute, which the test reads), so a missing file is visible. */
std::string galleryPage(const CompareResult& result, const std::vector<std::string>& rowMethods,
                        const std::string& renderer, int size, int pictureSize) {
    std::ostringstream page;
    page << "<!DOCTYPE html>\n<html lang=\"en\">\n<head>\n<meta charset=\"utf-8\">\n"
         << "<title>osgBTF gallery</title>\n<style>\n"
         << "body { font-family: sans-serif; background: #202020; color: #e0e0e0; }\n"
         << "table { border-collapse: collapse; }\n"
         << "th, td { padding: 4px; vertical-align: top; text-align: left; }\n"
         << "th { font-weight: normal; color: #b0b0b0; max-width: " << pictureSize << "px; }\n"
         << "img { display: block; width: " << pictureSize << "px; height: " << pictureSize
         << "px; image-rendering: pixelated; }\n"
         << "td.method { white-space: nowrap; }\n.failed { color: #ff8080; }\n"
         << "a { color: #80b0ff; }\n</style>\n</head>\n<body>\n"
         << "<h1>osgBTF gallery</h1>\n<p>The built-in sample (a woven cloth, " << size << " x "
         << size << " texels, 81 x 81 directions) fitted with each method by <code>btf "
         << "compare</code> (<a href=\"compare/report.md\">its report</a>) and rendered "
         << "headless with OpenGL (" << html(renderer) << "). Error: the average per-texel "
         << "error against the measured sample (as the report defines it); bytes per texel as "
         << "stored on the GPU; pass time: one full-screen pass of the material (the report's "
         << "first pass target; a software renderer's times compare methods, not GPUs).</p>\n"
         << "<p id=\"status\">Pictures: loading...</p>\n<table>\n<tr><th>method</th>";
    for (const GalleryView& view : galleryViews()) page << "<th>" << html(view.caption) << "</th>";
    page << "</tr>\n";
    for (const std::string& method : rowMethods) {
        const auto found = std::find_if(result.methods.begin(), result.methods.end(),
                                        [&](const MethodResult& m) { return m.method == method; });
        page << "<tr><td class=\"method\"><b>" << html(method) << "</b><br>";
        if (found == result.methods.end() || found->failed) {
            page << "<span class=\"failed\">"
                 << html(found == result.methods.end() ? "not run" : found->failure)
                 << "</span></td></tr>\n";
            continue;
        }
        page << "error " << significantDigits(found->error.average, 3) << "<br>"
             << significantDigits(found->memory.bytesPerTexel, 4) << " bytes/texel<br>";
        if (const MethodPass* pass = found->primaryPass())
            page << "pass " << significantDigits(pass->pass.ms, 3) << " ms";
        else
            page << "pass not measured";
        page << "</td>";
        for (const GalleryView& view : galleryViews()) {
            const std::string file = "pictures/" + method + "-" + view.name + ".png";
            page << "<td><img src=\"" << html(file) << "\" alt=\""
                 << html(method + ", " + view.name) << "\" width=\"" << pictureSize
                 << "\" height=\"" << pictureSize << "\"></td>";
        }
        page << "</tr>\n";
    }
    page << "</table>\n<script>\n"
         << "window.addEventListener('load', () => {\n"
         << "  const pictures = Array.from(document.images);\n"
         << "  const shown = pictures.filter(p => p.complete && p.naturalWidth > 0).length;\n"
         << "  document.body.dataset.picturesShown = shown;\n"
         << "  document.body.dataset.pictures = pictures.length;\n"
         << "  document.getElementById('status').textContent = shown === pictures.length\n"
         << "      ? 'Pictures: all ' + shown + ' shown.'\n"
         << "      : 'Pictures: only ' + shown + ' of ' + pictures.length + ' could be shown.';\n"
         << "});\n</script>\n</body>\n</html>\n";
    return page.str();
}

}  // namespace

std::string writeGallery(const GalleryOptions& options) {
    if (options.outputDir.empty()) throw Error("--gallery: no folder given");
    const fs::path dir = fs::absolute(options.outputDir).lexically_normal();
    std::error_code error;
    // Replacing a folder that is not a gallery would delete someone's files.
    if (fs::exists(dir) && !fs::is_empty(dir, error) && !fs::exists(dir / "index.html"))
        fail(dir.string(), "exists and is not a gallery (no index.html): choose another folder");
    fs::create_directories(dir.parent_path(), error);
    const fs::path work =
        dir.parent_path() / ("." + dir.filename().string() + ".tmp" + std::to_string(::getpid()));
    fs::remove_all(work, error);
    fs::create_directories(work / "pictures", error);
    if (error || !fs::is_directory(work / "pictures"))
        fail(work.string(),
             "cannot create the folder" + (error ? ": " + error.message() : std::string()));
    try {
        SampleOptions sampleOptions;
        sampleOptions.width = sampleOptions.height = options.size;
        writeUbo2003Zip(makeSampleBtf(sampleOptions), (work / "sample.zip").string());

        // The sky of the example scenes, for the environment view and compare's picture.
        writeFloatImage(createSkyEnvironment(), (work / "sky.hdr").string());
        CompareOptions compare;
        compare.input = (work / "sample.zip").string();
        compare.outputDir = (work / "compare").string();
        if (!options.methods.empty()) compare.methods = options.methods;
        compare.envFile = (work / "sky.hdr").string();
        const CompareResult result = runCompare(compare);

        osg::ref_ptr<EnvironmentLight> sky = new EnvironmentLight;
        sky->setFile((work / "sky.hdr").string());
        if (!sky->hasMap()) throw Error("gallery: " + sky->getError());
        const EnvironmentMap skyMap = sky->projectionMap();

        std::vector<std::string> rowMethods;
        std::size_t renders = 0;
        for (const MethodResult& m : result.methods) {
            rowMethods.push_back(m.method);
            if (!m.failed) renders += galleryViews().size();
        }
        HeadlessRenderer renderer;
        Progress progress("gallery pictures", renders);
        for (const MethodResult& m : result.methods) {
            if (m.failed) continue;
            const std::string materialFile = (work / "compare" / m.fittedFile).string();
            osg::ref_ptr<Material> material = loadMaterial(materialFile);
            for (const GalleryView& view : galleryViews()) {
                const FloatImage picture = renderView(renderer, view.name, *material, materialFile,
                                                      skyMap, options.pictureSize);
                writeFloatImage(
                    picture, (work / "pictures" / (m.method + "-" + view.name + ".png")).string(),
                    false, true);
                progress.advance();
            }
        }
        writeText(
            galleryPage(result, rowMethods, renderer.glRenderer() + ", " + renderer.glVersion(),
                        options.size, options.pictureSize),
            work / "index.html");
    } catch (...) {
        fs::remove_all(work, error);
        throw;
    }
    // The finished gallery replaces the old one (a folder cannot be renamed over a non-empty
    // one, so the old one goes first).
    fs::remove_all(dir, error);
    fs::rename(work, dir, error);
    if (error) {
        fs::remove_all(work, error);
        fail(dir.string(), "cannot rename the finished gallery into place: " + error.message());
    }
    return (dir / "index.html").string();
}

}  // namespace osgBTF::examples
