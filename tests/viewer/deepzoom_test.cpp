// relight's deep-zoom layout as osgBTF writes it (`btf export --layout deepzoom`), opened by a real
// deep-zoom client: OpenSeadragon (from the npm registry; tools/setup.sh installs it into
// <build>/web/node_modules) in Debian's headless Chromium.
//
// relight numbers its levels from the first that fits one tile (OpenLIME's layout "deepzoom"),
// where Microsoft's own numbering starts at 1 pixel; the page gives OpenSeadragon the pyramid as
// a tile source of those levels (width, height, tile size and overlap read from the .dzi), shows
// the whole image at 4x with nearest-pixel drawing, then compares the drawn canvas with the image
// layout's plane_0.jpg of the same material pixel by pixel and writes the mean and largest
// difference into the body (tests/viewer/Browser.h reads them). The two differ only by JPEG
// coding of tiles against the whole plane: a wrongly placed tile, a missing level or a wrong
// overlap shows as tens of levels. A pyramid with two tiles swapped must fail the same check.
#include <gtest/gtest.h>

#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>
#include <string>

#include "tests/TestUtil.h"
#include "tests/viewer/Browser.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::BrowserView;
using osgBTF::test::openInChromium;
using osgBTF::test::TempDir;
namespace fs = std::filesystem;

namespace {

std::string openSeadragon() {
    return test::buildDir() +
           "/web/node_modules/openseadragon/build/openseadragon/"
           "openseadragon.min.js";
}

int dziNumber(const std::string& dzi, const std::string& name) {
    std::smatch match;
    if (!std::regex_search(dzi, match, std::regex(name + "=\"([0-9]+)\""))) return -1;
    return std::stoi(match[1]);
}

/** The page: OpenSeadragon over plane_0's pyramid in `tiled`, compared with `plane` (a JPEG). */
std::string page(const std::string& tiled, const std::string& plane) {
    const std::string dzi = test::readTextFile(tiled + "/plane_0.dzi");
    const int width = dziNumber(dzi, "Width"), height = dziNumber(dzi, "Height");
    const int tile = dziNumber(dzi, "TileSize"), overlap = dziNumber(dzi, "Overlap");
    int levels = 1;
    for (int w = width, h = height; w > tile || h > tile;
         w = std::max(1, w >> 1), h = std::max(1, h >> 1))
        ++levels;
    const int zoom = 4;
    std::ostringstream html;
    html << "<!DOCTYPE html><html><head><meta charset=\"utf-8\">"
         << "<style>body{margin:0}#v{width:" << width * zoom << "px;height:" << height * zoom
         << "px}</style>"
         << "<script src=\"file://" << openSeadragon() << "\"></script></head><body>"
         << "<div id=\"v\"></div><script>\n"
         << "const viewer = OpenSeadragon({ element: document.getElementById('v'),"
         << " drawer: 'canvas', imageSmoothingEnabled: false, showNavigationControl: false,"
         << " animationTime: 0, blendTime: 0, immediateRender: true, visibilityRatio: 1,"
         << " tileSources: { width: " << width << ", height: " << height << ", tileSize: " << tile
         << ", tileOverlap: " << overlap << ", minLevel: 0, maxLevel: " << levels - 1 << ","
         << " getTileUrl: (level, x, y) => 'file://" << tiled
         << "/plane_0_files/' + level + '/' + x + '_' + y + '.jpg' } });\n"
         << "viewer.addHandler('tile-load-failed', () => document.body.dataset.failed = '1');\n"
         << "const reference = new Image();\n"
         << "reference.src = 'file://" << plane << "';\n"
         << "function compare() {\n"
         << "  const c = document.createElement('canvas');\n"
         << "  c.width = " << width << "; c.height = " << height << ";\n"
         << "  const g = c.getContext('2d'); g.drawImage(reference, 0, 0);\n"
         << "  const want = g.getImageData(0, 0, " << width << ", " << height << ").data;\n"
         << "  const drawn = viewer.drawer.canvas.getContext('2d').getImageData(0, 0, "
         << width * zoom << ", " << height * zoom << ").data;\n"
         << "  let sum = 0, largest = 0;\n"
         << "  for (let y = 0; y < " << height << "; ++y) for (let x = 0; x < " << width
         << "; ++x) for (let k = 0; k < 3; ++k) {\n"
         << "    const got = drawn[((" << zoom << " * y + 2) * " << width * zoom << " + " << zoom
         << " * x + 2) * 4 + k];\n"
         << "    const d = Math.abs(got - want[(y * " << width << " + x) * 4 + k]);\n"
         << "    sum += d; largest = Math.max(largest, d);\n"
         << "  }\n"
         << "  document.body.dataset.mean100 = String(Math.round(100 * sum / (" << width * height
         << " * 3)));\n"
         << "  document.body.dataset.largest = String(largest);\n"
         << "}\n"
         // Polled: the last frames are drawn after the image reports itself loaded, and the
         // DOM is dumped when the virtual time budget runs out; the latest comparison stands.
         << "let loaded = false;\n"
         << "viewer.world.addHandler('add-item', (e) => e.item.addHandler('fully-loaded-change',"
            " (f) => { loaded = f.fullyLoaded; }));\n"
         << "setInterval(() => { if (loaded && reference.complete) compare(); }, 50);\n"
         << "</script></body></html>\n";
    return html.str();
}

BrowserView show(const TempDir& dir, const std::string& tiled, const std::string& plane,
                 const std::string& name) {
    const std::string file = dir.file(name);
    test::writeTextFile(file, page(tiled, plane));
    // The page reads back the pixels OpenSeadragon drew from file:// tiles: without this flag
    // every file is its own origin and the canvas is tainted.
    // On a loaded machine the virtual time budget can run out before the tiles have loaded
    // (then nothing was compared): tried up to three times.
    BrowserView view;
    for (int attempt = 0; attempt < 3 && view.attribute("largest") < 0; ++attempt)
        view = openInChromium(file, dir.path(), "--allow-file-access-from-files");
    return view;
}

}  // namespace

TEST(DeepZoom, OpenSeadragonShowsTheWrittenPyramidAsThePlane) {
    if (!test::haveChromium()) GTEST_SKIP() << "chromium is not installed";
    ASSERT_TRUE(fs::exists(openSeadragon()))
        << openSeadragon() << " is missing: tools/setup.sh installs OpenSeadragon from npm";
    TempDir dir;
    const std::string btf = test::shellQuote(test::builtTool("btf"));
    const std::string capture = test::shellQuote(test::sourceDir() + "/tests/data/rti-icon-64");
    const std::string fitted = dir.file("ptm.btfmat");
    ASSERT_EQ(
        test::runCommand(btf + " --no-progress fit " + capture + " -m ptm --no-mipmap -o " + fitted)
            .exitCode,
        0);
    // Tiles of 16 with an overlap of 1 on the 64 x 64 capture: levels of 16, 32 and 64 pixels,
    // 16 tiles at full size.
    const test::CommandResult tiled =
        test::runCommand(btf + " export " + fitted + " " + dir.file("tiled/info.json") +
                         " --layout deepzoom --tile-size 16 --overlap 1 --quality 100");
    ASSERT_EQ(tiled.exitCode, 0) << tiled.output;
    const test::CommandResult image = test::runCommand(
        btf + " export " + fitted + " " + dir.file("image/info.json") + " --quality 100");
    ASSERT_EQ(image.exitCode, 0) << image.output;

    const BrowserView view =
        show(dir, dir.file("tiled"), dir.file("image/plane_0.jpg"), "pyramid.html");
    ASSERT_EQ(view.exitCode, 0) << view.log;
    EXPECT_EQ(view.text("failed"), "") << view.log;
    ASSERT_GE(view.attribute("mean100"), 0) << "the page never compared: " << view.log;
    // Both are the same bytes through two JPEG codings at quality 100: a level or two apart.
    EXPECT_LE(view.attribute("mean100"), 100) << view.dom;
    EXPECT_LE(view.attribute("largest"), 8) << view.dom;

    // The check can fail: two full-size tiles swapped.
    const fs::path level = dir.path() / "tiled" / "plane_0_files" / "2";
    fs::rename(level / "0_0.jpg", level / "swap.jpg");
    fs::rename(level / "2_1.jpg", level / "0_0.jpg");
    fs::rename(level / "swap.jpg", level / "2_1.jpg");
    const BrowserView swapped =
        show(dir, dir.file("tiled"), dir.file("image/plane_0.jpg"), "swapped.html");
    EXPECT_GT(swapped.attribute("largest"), 8) << swapped.dom;
}

}  // namespace OSGBTF_TEST_FILE
