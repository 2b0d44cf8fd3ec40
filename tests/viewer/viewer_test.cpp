// Viewer tests: the example scenes (btf-examples), `cmake --install` with stock osgconv using the
// installed plugins, and stock osgviewer and btfviewer showing the examples under Xvfb.
//
// Screenshots of stock osgviewer come from Xvfb itself: started with -fbdir, Xvfb keeps its
// screen in a file (XWD format) that always holds what is on the display, so the test needs no
// window manager, no key injection and no screenshot tool. osgviewer runs until a frame with the
// expected content is on screen (or a time limit), then the test stops it and checks that
// frame. btfviewer writes its own capture (--capture). Every GL test skips when Xvfb is absent.
//
// Needs the ctest fixture viewer.make_examples (tests/viewer/CMakeLists.txt), which writes the
// example scenes (sample 8x8, lambert and pca) into <build>/tests/viewer/examples.
#include <fcntl.h>
#include <poll.h>
#include <signal.h>
#include <sys/wait.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <functional>
#include <map>
#include <memory>
#include <sstream>
#include <thread>

#include <gtest/gtest.h>
#include <osg/Geode>
#include <osg/Geometry>
#include <osg/LightSource>
#include <osg/MatrixTransform>
#include <osg/NodeVisitor>
#include <osg/ProxyNode>
#include <osgDB/ReadFile>
#include <osgDB/WriteFile>
#include <osgShadow/ShadowMap>
#include <osgShadow/ShadowedScene>

#include "core/FloatImage.h"
#include "harness/sample/BlockMap.h"
#include "scene/MaterialNode.h"
#include "tests/HandWrittenUbo2014.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using osgBTF::test::buildDir;
using osgBTF::test::builtTool;
using osgBTF::test::CommandResult;
using osgBTF::test::runCommand;
using osgBTF::test::shellQuote;
using osgBTF::test::TempDir;

namespace {

const std::string kBuildDir = buildDir();
const std::string kExamplesDir = buildDir() + "/tests/viewer/examples";
const std::string kScreensDir = buildDir() + "/tests/viewer/screens";
const std::string kPluginDir = kBuildDir + "/lib";
const std::vector<std::string> kMethods = {"lambert", "pca"};  // what the fixture fitted

bool onPath(const std::string& program) {
    return runCommand("command -v " + program + " >/dev/null").exitCode == 0;
}

// ---- processes ---------------------------------------------------------------------------

/** A child process: argv, extra environment, working folder; output into a log file. */
class ChildProcess {
public:
    ChildProcess(const std::vector<std::string>& argv, const std::vector<std::string>& environment,
                 const std::string& workingDir, const std::string& logFile, int keepOpenFd = -1) {
        _log = logFile;
        _pid = ::fork();
        if (_pid == 0) {
            if (!workingDir.empty() && ::chdir(workingDir.c_str()) != 0) ::_exit(126);
            for (const std::string& assignment : environment) {
                const auto equals = assignment.find('=');
                ::setenv(assignment.substr(0, equals).c_str(),
                         assignment.substr(equals + 1).c_str(), 1);
            }
            const int log = ::open(logFile.c_str(), O_WRONLY | O_CREAT | O_TRUNC, 0644);
            if (log >= 0) {
                ::dup2(log, STDOUT_FILENO);
                ::dup2(log, STDERR_FILENO);
            }
            for (int fd = 3; fd < 256; ++fd)
                if (fd != keepOpenFd) ::close(fd);
            std::vector<char*> args;
            for (const std::string& arg : argv) args.push_back(const_cast<char*>(arg.c_str()));
            args.push_back(nullptr);
            ::execvp(args[0], args.data());
            ::_exit(127);
        }
    }
    ~ChildProcess() { stop(); }
    ChildProcess(const ChildProcess&) = delete;
    ChildProcess& operator=(const ChildProcess&) = delete;

    bool running() {
        if (_pid <= 0) return false;
        int status = 0;
        if (::waitpid(_pid, &status, WNOHANG) == _pid) {
            _exitCode = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
            _pid = -1;
            return false;
        }
        return true;
    }
    /** Stops it (SIGTERM, then SIGKILL after 3 s) if it still runs. */
    void stop() {
        if (!running()) return;
        ::kill(_pid, SIGTERM);
        for (int i = 0; i < 30 && running(); ++i)
            std::this_thread::sleep_for(std::chrono::milliseconds(100));
        if (running()) {
            ::kill(_pid, SIGKILL);
            ::waitpid(_pid, nullptr, 0);
            _pid = -1;
        }
    }
    int exitCode() const { return _exitCode; }
    std::string output() const { return osgBTF::test::readTextFile(_log); }

private:
    pid_t _pid = -1;
    int _exitCode = -1;
    std::string _log;
};

// ---- screenshots -------------------------------------------------------------------------

struct RgbImage {
    int width = 0, height = 0;
    std::vector<std::uint8_t> rgb;  // rows top-down
    const std::uint8_t* at(int x, int y) const { return &rgb[3 * (std::size_t(y) * width + x)]; }
};

/** Reads the XWD file Xvfb keeps its screen in (-fbdir): a big-endian header of 25 CARD32,
 *  the window name, the colour map, then the pixels (TrueColor, 32 bits per pixel at depth 24,
 *  in the header's byte order). Returns an empty image if the file is not such a file. */
RgbImage readXvfbScreen(const std::string& path) {
    std::ifstream in(path, std::ios::binary);
    std::vector<std::uint8_t> data((std::istreambuf_iterator<char>(in)),
                                   std::istreambuf_iterator<char>());
    RgbImage image;
    if (data.size() < 100) return image;
    auto card32 = [&](std::size_t index) {
        const std::uint8_t* p = &data[4 * index];
        return std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 | std::uint32_t(p[2]) << 8 |
               p[3];
    };
    const std::uint32_t headerSize = card32(0), version = card32(1), width = card32(4),
                        height = card32(5), byteOrder = card32(7), bitsPerPixel = card32(11),
                        bytesPerLine = card32(12), redMask = card32(14), greenMask = card32(15),
                        blueMask = card32(16), colours = card32(19);
    const std::size_t pixelsAt = std::size_t(headerSize) + std::size_t(colours) * 12;
    if (version != 7 || bitsPerPixel != 32 || redMask != 0xff0000 || greenMask != 0xff00 ||
        blueMask != 0xff || data.size() < pixelsAt + std::size_t(bytesPerLine) * height)
        return image;
    image.width = int(width);
    image.height = int(height);
    image.rgb.resize(std::size_t(width) * height * 3);
    for (std::uint32_t y = 0; y < height; ++y)
        for (std::uint32_t x = 0; x < width; ++x) {
            const std::uint8_t* p = &data[pixelsAt + std::size_t(y) * bytesPerLine + 4 * x];
            const std::uint32_t littleEndian = std::uint32_t(p[0]) | std::uint32_t(p[1]) << 8 |
                                               std::uint32_t(p[2]) << 16 |
                                               std::uint32_t(p[3]) << 24;
            const std::uint32_t bigEndian = std::uint32_t(p[0]) << 24 | std::uint32_t(p[1]) << 16 |
                                            std::uint32_t(p[2]) << 8 | p[3];
            const std::uint32_t value = byteOrder == 0 ? littleEndian : bigEndian;  // 0: LSBFirst
            std::uint8_t* out = &image.rgb[3 * (std::size_t(y) * width + x)];
            out[0] = std::uint8_t(value >> 16);
            out[1] = std::uint8_t(value >> 8);
            out[2] = std::uint8_t(value);
        }
    return image;
}

RgbImage crop(const RgbImage& image, int width, int height) {
    RgbImage out;
    out.width = std::min(width, image.width);
    out.height = std::min(height, image.height);
    for (int y = 0; y < out.height; ++y)
        out.rgb.insert(out.rgb.end(), image.at(0, y), image.at(0, y) + 3 * out.width);
    return out;
}

/** An osg::Image (rows bottom-up, RGB or RGBA bytes, as the png plugin reads) as RgbImage. */
RgbImage fromOsgImage(const osg::Image& image) {
    RgbImage out;
    out.width = image.s();
    out.height = image.t();
    const unsigned components = osg::Image::computeNumComponents(image.getPixelFormat());
    for (int y = out.height - 1; y >= 0; --y)
        for (int x = 0; x < out.width; ++x) {
            const unsigned char* p = image.data(x, y);
            out.rgb.insert(out.rgb.end(), p, p + std::min(3u, components));
        }
    return out;
}

/** What the checks look at: spread of the luminance, the share of pixels that differ from the
 *  most common colour (the background), and the share of "material-coloured" pixels: the
 *  sample's red and gold threads, lit, are warm (red clearly above blue); osgviewer's
 *  background is blue, a model without the material grey, labels white. */
struct ScreenStats {
    double luminanceStdDev = 0;
    double foregroundShare = 0;
    double warmShare = 0;
};

ScreenStats analyse(const RgbImage& image) {
    ScreenStats stats;
    const std::size_t count = std::size_t(image.width) * image.height;
    if (count == 0) return stats;
    std::map<std::uint32_t, std::size_t> histogram;
    double sum = 0, sum2 = 0;
    std::size_t warm = 0;
    for (std::size_t i = 0; i < count; ++i) {
        const int r = image.rgb[3 * i], g = image.rgb[3 * i + 1], b = image.rgb[3 * i + 2];
        ++histogram[std::uint32_t(r) << 16 | std::uint32_t(g) << 8 | std::uint32_t(b)];
        const double luminance = 0.2126 * r + 0.7152 * g + 0.0722 * b;
        sum += luminance;
        sum2 += luminance * luminance;
        if (r > 50 && r >= g && r > b + 35) ++warm;
    }
    const double mean = sum / double(count);
    stats.luminanceStdDev = std::sqrt(std::max(0.0, sum2 / double(count) - mean * mean));
    std::uint32_t background = 0;
    std::size_t most = 0;
    for (const auto& [colour, n] : histogram)
        if (n > most) most = n, background = colour;
    std::size_t foreground = 0;
    for (std::size_t i = 0; i < count; ++i) {
        const int dr = image.rgb[3 * i] - int(background >> 16 & 255),
                  dg = image.rgb[3 * i + 1] - int(background >> 8 & 255),
                  db = image.rgb[3 * i + 2] - int(background & 255);
        if (std::abs(dr) + std::abs(dg) + std::abs(db) > 30) ++foreground;
    }
    stats.foregroundShare = double(foreground) / double(count);
    stats.warmShare = double(warm) / double(count);
    return stats;
}

bool notBlank(const ScreenStats& stats) {
    return stats.luminanceStdDev > 8.0 && stats.foregroundShare > 0.02;
}
bool materialColoured(const ScreenStats& stats) {
    return stats.warmShare > 0.01;
}

std::string describe(const ScreenStats& stats) {
    return "luminance std dev " + std::to_string(stats.luminanceStdDev) + ", foreground " +
           std::to_string(100 * stats.foregroundShare) + "%, material-coloured " +
           std::to_string(100 * stats.warmShare) + "%";
}

/** Keeps a screenshot for people (build/tests/viewer/screens/NAME.png). */
void keepScreenshot(const RgbImage& image, const std::string& name) {
    if (image.width == 0) return;
    osg::ref_ptr<osg::Image> out = new osg::Image;
    out->allocateImage(image.width, image.height, 1, GL_RGB, GL_UNSIGNED_BYTE);
    for (int y = 0; y < image.height; ++y)
        std::memcpy(out->data(0, image.height - 1 - y), image.at(0, y), 3 * image.width);
    fs::create_directories(kScreensDir);
    osgDB::writeImageFile(*out, kScreensDir + "/" + name + ".png");
}

/** Xvfb on a free display (-displayfd), its screen kept in a file (-fbdir). With `resets`, it
 *  runs as xvfb-run starts it (no -noreset): the server resets whenever its last client
 *  disconnects, and refuses connections for a moment meanwhile. */
class Xvfb {
public:
    static constexpr int kWidth = 480, kHeight = 360;

    explicit Xvfb(int width = kWidth, int height = kHeight, bool resets = false) : _dir() {
        int fds[2];
        if (::pipe(fds) != 0) return;
        std::vector<std::string> argv = {
            "Xvfb",
            "-displayfd",
            std::to_string(fds[1]),
            "-screen",
            "0",
            std::to_string(width) + "x" + std::to_string(height) + "x24",
            "-fbdir",
            _dir.path().string(),
            "-nolisten",
            "tcp",
            "-br"};
        if (!resets) argv.push_back("-noreset");
        _server = std::make_unique<ChildProcess>(argv, std::vector<std::string>{}, "",
                                                 _dir.file("xvfb.log"), fds[1]);
        ::close(fds[1]);
        // Xvfb writes the display number once it accepts clients.
        pollfd waitFor{fds[0], POLLIN, 0};
        std::string number;
        char c;
        while (::poll(&waitFor, 1, 15000) > 0 && ::read(fds[0], &c, 1) == 1 && c != '\n')
            number += c;
        ::close(fds[0]);
        if (!number.empty()) _display = ":" + number;
    }
    bool ok() const { return !_display.empty(); }
    std::string log() const { return osgBTF::test::readTextFile(_dir.file("xvfb.log")); }
    const std::string& display() const { return _display; }
    RgbImage screen() const { return readXvfbScreen(_dir.file("Xvfb_screen0")); }

private:
    TempDir _dir;
    std::unique_ptr<ChildProcess> _server;
    std::string _display;
};

#define REQUIRE_XVFB()                                                                     \
    if (!onPath("Xvfb"))                                                                   \
    GTEST_SKIP() << "Xvfb is not installed (Debian package xvfb; tools/setup.sh installs " \
                    "it): the viewer tests need an X server"

struct OsgviewerRun {
    RgbImage screen;  // the viewer's window (top left of the display)
    ScreenStats stats;
    std::string output;
    bool exitedEarly = false;
};

/** Runs stock osgviewer on `arguments` (in `workingDir`, osgBTF's plugins from the build)
 *  in a 320x240 window until `ready` holds for the screen or 30 s passed, then stops it. */
/** `ready` is asked of every screenshot; with `outputMarker`, the viewer's output must also
 *  contain it (work that finishes in the background) before `seconds` pass. */
OsgviewerRun runOsgviewer(const Xvfb& xvfb, const std::vector<std::string>& arguments,
                          const std::string& workingDir,
                          const std::function<bool(const ScreenStats&)>& ready,
                          const std::string& outputMarker = "", int seconds = 30) {
    // Line-buffered: notices must reach the log while it runs (it is stopped, never exits).
    std::vector<std::string> argv = {"stdbuf", "-oL", "osgviewer"};
    argv.insert(argv.end(), arguments.begin(), arguments.end());
    for (const char* option : {"--window", "0", "0", "320", "240"}) argv.push_back(option);
    TempDir logDir;
    ChildProcess viewer(argv, {"DISPLAY=" + xvfb.display(), "OSG_LIBRARY_PATH=" + kPluginDir},
                        workingDir, logDir.file("osgviewer.log"));
    OsgviewerRun run;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(seconds);
    bool marked = outputMarker.empty();
    while (std::chrono::steady_clock::now() < deadline) {
        std::this_thread::sleep_for(std::chrono::milliseconds(200));
        if (!viewer.running()) {
            run.exitedEarly = true;
            break;
        }
        // The marker first: the screenshot after it shows what the marked work installed.
        const bool markedBefore = marked;
        marked = marked || viewer.output().find(outputMarker) != std::string::npos;
        if (marked && !markedBefore) std::this_thread::sleep_for(std::chrono::milliseconds(500));
        run.screen = crop(xvfb.screen(), 320, 240);
        run.stats = analyse(run.screen);
        if (marked && ready(run.stats)) break;
    }
    viewer.stop();
    run.output = viewer.output();
    return run;
}

// ---- the example scenes ------------------------------------------------------------------

template <typename T>
class Collector : public osg::NodeVisitor {
public:
    Collector() : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN) {}
    void apply(osg::Node& node) override {
        if (auto* found = dynamic_cast<T*>(&node)) nodes.push_back(found);
        traverse(node);
    }
    std::vector<osg::ref_ptr<T>> nodes;
};

TEST(Examples, AnUnknownMethodFailsBeforeAnythingIsWritten) {
    TempDir dir;
    const std::string out = dir.file("out");
    const CommandResult result = runCommand(builtTool("btf-examples") + " --out " +
                                            shellQuote(out) + " --size 8 --methods lambert,nosuch");
    EXPECT_EQ(result.exitCode, 1) << result.output;
    EXPECT_NE(result.output.find("btf-examples: unknown method 'nosuch' (known: "),
              std::string::npos)
        << result.output;
    EXPECT_FALSE(fs::exists(out));
}

// --bench-fps: the command runs and prints a well-formed table (timings never pass or fail).
TEST(Examples, BenchFpsWritesOneRowPerSceneAndMethod) {
    TempDir dir;
    const std::string out = dir.file("bench");
    const CommandResult result = runCommand(
        builtTool("btf-examples") + " --no-progress --out " + shellQuote(out) +
        " --size 8 --methods lambert,pca --bench-fps --bench-resolution 64x36 --bench-frames 1 "
        "--bench-warmup 0 --bench-lights 1,8");
    ASSERT_EQ(result.exitCode, 0) << result.output;
    const std::string table = osgBTF::test::readTextFile(out + "/bench-fps.md");
    const auto count = [](const std::string& text, const std::string& what) {
        std::size_t n = 0;
        for (auto at = text.find(what); at != std::string::npos; at = text.find(what, at + 1)) ++n;
        return n;
    };
    EXPECT_NE(result.output.find(table), std::string::npos) << "printed as written";
    EXPECT_NE(table.find("Example scenes at 64x36, RGBA8 target, median of 1 frames after 0 "
                         "warm-up frames; renderer "),
              std::string::npos)
        << table;
    EXPECT_NE(table.find("| scene | method | fps 1 light | frame ms |"), std::string::npos);
    EXPECT_NE(table.find(" fps 8 lights | frame ms |"), std::string::npos);
    for (const std::string scene : {"spheres", "cloth", "vases"})
        for (const std::string method : {"lambert", "pca"})
            EXPECT_EQ(count(table, "| " + scene + " | " + method + " | "), 1u)
                << scene << " " << method << "\n"
                << table;
    std::ifstream csv(out + "/bench-fps.csv");
    std::string line;
    std::getline(csv, line);
    EXPECT_EQ(line, "scene,method,lights,frame_ms,fps,gpu_ms");
    int rows = 0;
    while (std::getline(csv, line)) {
        ++rows;
        std::vector<std::string> fields;
        std::stringstream fieldStream(line);
        std::string field;
        while (std::getline(fieldStream, field, ',')) fields.push_back(field);
        ASSERT_GE(fields.size(), 5u) << line;
        EXPECT_TRUE(fields[2] == "1" || fields[2] == "8") << line;
        EXPECT_GT(std::stod(fields[3]), 0.0) << line;
        EXPECT_NEAR(std::stod(fields[4]), 1000.0 / std::stod(fields[3]),
                    1e-3 * std::stod(fields[4]) + 1e-3)
            << line;
    }
    EXPECT_EQ(rows, 3 * 2 * 2);
}

TEST(Examples, BadBenchOptionsFailBeforeAnythingIsWritten) {
    TempDir dir;
    const std::string out = dir.file("out");
    const std::pair<std::string, std::string> cases[] = {
        {"--bench-lights 1,9", "btf-examples: --bench-lights: '9' is not a light count in 1..8"},
        {"--bench-resolution 640",
         "btf-examples: --bench-resolution: '640' is not WxH "
         "(positive integers)"},
        {"--bench-target rgba9",
         "btf-examples: --bench-target: pass target 'rgba9': must be "
         "rgba8, rgba16f or rgba32f"}};
    for (const auto& [option, message] : cases) {
        const CommandResult result =
            runCommand(builtTool("btf-examples") + " --out " + shellQuote(out) +
                       " --size 8 --methods lambert --bench-fps " + option);
        EXPECT_EQ(result.exitCode, 1) << result.output;
        EXPECT_NE(result.output.find(message), std::string::npos) << result.output;
        EXPECT_FALSE(fs::exists(out)) << option;
    }
}

TEST(Examples, ScenesPutEachMaterialSideBySideUnderTwoLights) {
    for (const std::string scene : {"spheres.osgt", "cloth.osgt", "vases.osgt"}) {
        SCOPED_TRACE(scene);
        osg::ref_ptr<osg::Node> root = osgDB::readRefNodeFile(kExamplesDir + "/" + scene);
        ASSERT_TRUE(root.valid()) << "cannot read " << kExamplesDir << "/" << scene;

        Collector<osg::LightSource> lights;
        root->accept(lights);
        ASSERT_EQ(lights.nodes.size(), 2u);
        EXPECT_EQ(lights.nodes[0]->getLight()->getPosition().w(), 0.0f);  // directional
        EXPECT_EQ(lights.nodes[1]->getLight()->getPosition().w(), 1.0f);  // point

        Collector<osgBTF::MaterialNode> materials;
        root->accept(materials);
        ASSERT_EQ(materials.nodes.size(), kMethods.size());
        std::vector<osg::Vec3d> places;
        for (std::size_t i = 0; i < kMethods.size(); ++i) {
            const osgBTF::MaterialNode& node = *materials.nodes[i];
            // Relative names, found next to the scene: the folder can move.
            EXPECT_EQ(node.getMaterialFile(), "sample-" + kMethods[i] + ".btfmat");
            ASSERT_NE(node.getMaterial(), nullptr) << node.getMaterialError();
            EXPECT_EQ(node.getMaterial()->methodName(), kMethods[i]);
            ASSERT_EQ(node.getNumParents(), 1u);
            auto* place = dynamic_cast<const osg::MatrixTransform*>(node.getParent(0));
            ASSERT_NE(place, nullptr);
            places.push_back(place->getMatrix().getTrans());

            // The model below: normals and texture coordinates per vertex, tangents added.
            Collector<osg::Geometry> geometries;
            const_cast<osgBTF::MaterialNode&>(node).accept(geometries);
            ASSERT_EQ(geometries.nodes.size(), 1u);
            const osg::Geometry& geometry = *geometries.nodes[0];
            const unsigned vertices = geometry.getVertexArray()->getNumElements();
            EXPECT_GT(vertices, 1000u);
            ASSERT_NE(geometry.getNormalArray(), nullptr);
            EXPECT_EQ(geometry.getNormalArray()->getNumElements(), vertices);
            ASSERT_NE(geometry.getTexCoordArray(0), nullptr);
            EXPECT_EQ(geometry.getTexCoordArray(0)->getNumElements(), vertices);
            ASSERT_NE(geometry.getVertexAttribArray(6), nullptr);
        }
        // Side by side: along +X, apart.
        for (std::size_t i = 1; i < places.size(); ++i)
            EXPECT_GT(places[i].x() - places[i - 1].x(), 1.0) << "object " << i;
    }
}

TEST(Examples, TheVaseModelIsPlainOsgGeometryReadThroughAProxyNode) {
    osg::ref_ptr<osg::Node> model = osgDB::readRefNodeFile(kExamplesDir + "/vase.osgt");
    ASSERT_TRUE(model.valid());
    Collector<osgBTF::MaterialNode> materials;
    model->accept(materials);
    EXPECT_TRUE(materials.nodes.empty());
    Collector<osg::Geometry> geometries;
    model->accept(geometries);
    ASSERT_EQ(geometries.nodes.size(), 1u);
    EXPECT_EQ(geometries.nodes[0]->getVertexAttribArray(6), nullptr);  // no tangents stored

    osg::ref_ptr<osg::Node> scene = osgDB::readRefNodeFile(kExamplesDir + "/vases.osgt");
    ASSERT_TRUE(scene.valid());
    Collector<osg::ProxyNode> proxies;
    scene->accept(proxies);
    ASSERT_EQ(proxies.nodes.size(), kMethods.size());
    for (const osg::ref_ptr<osg::ProxyNode>& proxy : proxies.nodes) {
        EXPECT_EQ(proxy->getFileName(0), "vase.osgt");
        EXPECT_EQ(proxy->getNumChildren(), 1u);  // loaded when the scene was read
    }
}

TEST(Examples, TheShadowedClothSceneAndTheSky) {
    osg::ref_ptr<osg::Node> root = osgDB::readRefNodeFile(kExamplesDir + "/cloth-shadows.osgt");
    ASSERT_TRUE(root.valid());
    auto* scene = dynamic_cast<osgShadow::ShadowedScene*>(root.get());
    ASSERT_NE(scene, nullptr);
    EXPECT_NE(dynamic_cast<osgShadow::ShadowMap*>(scene->getShadowTechnique()), nullptr);
    Collector<osg::LightSource> lights;
    root->accept(lights);
    ASSERT_EQ(lights.nodes.size(), 2u);
    // The key light, last (the one ShadowMap shadows), is the sky's sun: azimuth 210 degrees,
    // elevation 35 (examples/README.md).
    const osg::Vec4 key = lights.nodes[1]->getLight()->getPosition();
    const double azimuth = osg::DegreesToRadians(210.0), elevation = osg::DegreesToRadians(35.0);
    const osg::Vec3 sun(float(std::cos(elevation) * std::cos(azimuth)),
                        float(std::cos(elevation) * std::sin(azimuth)), float(std::sin(elevation)));
    EXPECT_EQ(key.w(), 0.0f);
    EXPECT_NEAR((osg::Vec3(key.x(), key.y(), key.z()) - sun).length(), 0.0f, 1e-6f);
    Collector<osgBTF::MaterialNode> materials;
    root->accept(materials);
    ASSERT_EQ(materials.nodes.size(), 1u);
    EXPECT_EQ(materials.nodes[0]->getMaterialFile(), "sample-pca.btfmat");
    EXPECT_TRUE(materials.nodes[0]->getShadowTerminator());
    Collector<osg::Geometry> geometries;
    materials.nodes[0]->accept(geometries);
    ASSERT_EQ(geometries.nodes.size(), 1u);
    EXPECT_EQ(geometries.nodes[0]->getVertexArray()->getNumElements(), 57u * 57u);
    EXPECT_NE(geometries.nodes[0]->getVertexAttribArray(6), nullptr);  // tangents

    // sky.hdr: the lat-long map as written, its brightest texel where the sun is.
    const osgBTF::FloatImage sky = osgBTF::readFloatImage(kExamplesDir + "/sky.hdr");
    ASSERT_EQ(sky.width, 512);
    ASSERT_EQ(sky.height, 256);
    ASSERT_EQ(sky.channels, 3);
    EXPECT_EQ(osgBTF::countNonFinite(sky), 0u);
    std::size_t brightest = 0;
    for (std::size_t i = 0; i < sky.pixels.size(); i += 3)
        if (sky.pixels[i] > sky.pixels[brightest]) brightest = i;
    const int x = int(brightest / 3) % sky.width, y = int(brightest / 3) / sky.width;
    EXPECT_NEAR(360.0 * (x + 0.5) / sky.width, 210.0, 1.0);
    EXPECT_NEAR(90.0 - 180.0 * (y + 0.5) / sky.height, 35.0, 1.0);
    EXPECT_GT(sky.at(x, y, 0), 100.0f);                        // HDR: far above 1
    EXPECT_LT(sky.at(0, sky.height - 1, 2), sky.at(0, 0, 2));  // ground darker than the zenith
}

// ---- install -----------------------------------------------------------------------------

TEST(Install, PutsLibraryPluginsAndToolsWhereStockOsgFindsThem) {
    TempDir prefix;
    const CommandResult install =
        runCommand(std::string(OSGBTF_CMAKE_COMMAND) + " --install " + shellQuote(kBuildDir) +
                   " --prefix " + shellQuote(prefix.path().string()));
    ASSERT_EQ(install.exitCode, 0) << install.output;
    const fs::path lib = prefix.path() / OSGBTF_INSTALL_LIBDIR;  // lib, or lib/<multiarch>
    const fs::path plugins = lib / ("osgPlugins-" + std::string(OSGBTF_OSG_VERSION));
    const fs::path include = prefix.path() / "include" / "osgBTF";
    for (const fs::path& file : {lib / "libosgBTF.so",
                                 lib / "libosgBTFEnvironment.so",
                                 plugins / "osgdb_btfmat.so",
                                 plugins / "osgdb_btf.so",
                                 plugins / "osgdb_btfzip.so",
                                 plugins / "osgdb_btfmaterial.so",
                                 plugins / "osgdb_btfexr.so",
                                 plugins / "osgdb_serializers_osgbtf.so",
                                 plugins / "osgdb_bsvtf.so",
                                 plugins / "osgdb_osgbtf.so",
                                 prefix.path() / "bin" / "btf",
                                 prefix.path() / "bin" / "btfviewer",
                                 prefix.path() / "bin" / "btf-examples",
                                 include / "MaterialNode",
                                 include / "scene" / "MaterialNode.h",
                                 include / "Version",
                                 lib / "cmake" / "osgBTF" / "osgBTFConfig.cmake",
                                 lib / "cmake" / "osgBTF" / "osgBTFConfigVersion.cmake",
                                 lib / "cmake" / "osgBTF" / "osgBTFTargets.cmake",
                                 lib / "pkgconfig" / "osgBTF.pc",
                                 lib / "pkgconfig" / "osgBTFEnvironment.pc"})
        EXPECT_TRUE(fs::exists(file)) << file << " was not installed";
    // The SDK is the runtime only: the harness (static, inside the tools) is not installed.
    EXPECT_FALSE(fs::exists(include / "harness"));
    EXPECT_FALSE(fs::exists(lib / "libosgBTFHarness.a"));
    // Installed headers refer to each other as <osgBTF/...>, never by source-tree paths.
    const std::string node =
        osgBTF::test::readTextFile((include / "scene" / "MaterialNode.h").string());
    EXPECT_NE(node.find("#include <osgBTF/materials/Material.h>"), std::string::npos);
    EXPECT_EQ(node.find("#include \""), std::string::npos);
    // Nothing else is needed: no shader files lie around (they are embedded).
    EXPECT_FALSE(fs::exists(prefix.path() / "share" / "osgBTF" / "shaders"));

    // The installed tools find the installed libosgBTF by themselves (RPATH).
    const std::string clean = "env -u LD_LIBRARY_PATH -u OSG_LIBRARY_PATH -u OSG_FILE_PATH ";
    const CommandResult help =
        runCommand(clean + shellQuote((prefix.path() / "bin" / "btf").string()) + " --help");
    EXPECT_EQ(help.exitCode, 0) << help.output;

    // Stock osgconv with OSG_LIBRARY_PATH=P/lib reads through the installed plugins: a missing
    // material first (the plugin's message proves which reader answered), then the real thing.
    const std::string osgconv = "cd " + shellQuote(kExamplesDir) + " && " + clean +
                                "OSG_LIBRARY_PATH=" + shellQuote(lib.string()) + " osgconv ";
    const CommandResult missing = runCommand(osgconv + "'vase.osgt.(nosuch.btfmat).btfmaterial' " +
                                             shellQuote(prefix.file("missing.osgt")));
    EXPECT_NE(missing.exitCode, 0) << missing.output;
    EXPECT_NE(missing.output.find("nosuch.btfmat: no such file"), std::string::npos)
        << missing.output;

    const CommandResult converted =
        runCommand(osgconv + "'vase.osgt.(sample-pca.btfmat,scale=3).btfmaterial' " +
                   shellQuote(prefix.file("converted.osgt")));
    ASSERT_EQ(converted.exitCode, 0) << converted.output;
    const std::string text = osgBTF::test::readTextFile(prefix.file("converted.osgt"));
    EXPECT_NE(text.find("osgBTF::MaterialNode"), std::string::npos);
    EXPECT_NE(text.find("MaterialFile \"sample-pca.btfmat\""), std::string::npos);
    EXPECT_NE(text.find("TextureScale 3"), std::string::npos);

    // A scene with MaterialNodes: OSG finds their serializers in the installed libosgBTF.
    const CommandResult scene =
        runCommand(osgconv + "spheres.osgt " + shellQuote(prefix.file("spheres.osgt")) + " 2>&1");
    ASSERT_EQ(scene.exitCode, 0) << scene.output;
    EXPECT_EQ(scene.output.find("Unsupported wrapper class osgBTF::MaterialNode"),
              std::string::npos)
        << scene.output;
    EXPECT_NE(osgBTF::test::readTextFile(prefix.file("spheres.osgt")).find("osgBTF::MaterialNode"),
              std::string::npos);

    // Where OSG cannot find "libosgBTF.so" by name (Debian's OSG does not search
    // /usr/lib/<multiarch>, where the .deb puts it), osgdb_serializers_osgbtf brings it in.
    fs::remove(lib / "libosgBTF.so");
    const CommandResult shim =
        runCommand(osgconv + "spheres.osgt " + shellQuote(prefix.file("shim.osgt")) + " 2>&1");
    ASSERT_EQ(shim.exitCode, 0) << shim.output;
    EXPECT_EQ(shim.output.find("Unsupported wrapper class osgBTF::MaterialNode"), std::string::npos)
        << shim.output;
    // EnvironmentLitGroup's wrapper is in libosgBTFEnvironment, which osgDB never loads by name:
    // osgdb_serializers_osgbtf links it.
    const CommandResult lit = runCommand(osgconv + "cloth-sky.osgt " +
                                         shellQuote(prefix.file("cloth-sky.osgt")) + " 2>&1");
    ASSERT_EQ(lit.exitCode, 0) << lit.output;
    EXPECT_EQ(lit.output.find("Unsupported wrapper"), std::string::npos) << lit.output;
    EXPECT_NE(osgBTF::test::readTextFile(prefix.file("cloth-sky.osgt"))
                  .find("osgBTF::EnvironmentLitGroup"),
              std::string::npos);
}

// ---- stock osgviewer under Xvfb ----------------------------------------------------------

TEST(StockOsgviewer, TheScreenshotChecksRejectABlankScreenAndAModelWithoutMaterial) {
    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    const ScreenStats blank = analyse(crop(xvfb.screen(), 320, 240));
    EXPECT_FALSE(notBlank(blank)) << describe(blank);

    // The plain model (no material): osgviewer draws it grey; not material-coloured.
    const OsgviewerRun run = runOsgviewer(xvfb, {"vase.osgt"}, kExamplesDir, notBlank);
    keepScreenshot(run.screen, "osgviewer-plain-vase");
    EXPECT_FALSE(run.exitedEarly) << run.output;
    EXPECT_TRUE(notBlank(run.stats)) << describe(run.stats) << "\n" << run.output;
    EXPECT_FALSE(materialColoured(run.stats)) << describe(run.stats);
}

TEST(StockOsgviewer, ShowsAnExampleScene) {
    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    const OsgviewerRun run =
        runOsgviewer(xvfb, {kExamplesDir + "/spheres.osgt"}, "",
                     [](const ScreenStats& s) { return notBlank(s) && materialColoured(s); });
    keepScreenshot(run.screen, "osgviewer-spheres");
    EXPECT_FALSE(run.exitedEarly) << run.output;
    EXPECT_TRUE(notBlank(run.stats)) << describe(run.stats) << "\n" << run.output;
    EXPECT_TRUE(materialColoured(run.stats)) << describe(run.stats) << "\n" << run.output;
    EXPECT_EQ(run.output.find("osgBTF::MaterialNode:"), std::string::npos) << run.output;
}

TEST(StockOsgviewer, ShowsTheClothLitByTheSkyOnceTheSceneHasComputedIt) {
    // cloth-sky.osgt: an osgBTF::EnvironmentLitGroup computes its per-vertex lighting on a
    // worker thread when osgviewer first updates it, and installs it itself.
    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    const OsgviewerRun run = runOsgviewer(
        xvfb, {kExamplesDir + "/cloth-sky.osgt"}, "",
        [](const ScreenStats& s) { return notBlank(s) && materialColoured(s); },
        "osgBTF::EnvironmentLitGroup: lighting installed (1 geometries)", 90);
    keepScreenshot(run.screen, "osgviewer-cloth-sky");
    EXPECT_FALSE(run.exitedEarly) << run.output;
    EXPECT_NE(run.output.find("osgBTF::EnvironmentLitGroup: lighting 1 material node(s) by "
                              "sky.hdr, rotation 0 degrees"),
              std::string::npos)
        << run.output;
    EXPECT_NE(run.output.find("lighting installed (1 geometries)"), std::string::npos)
        << run.output;
    EXPECT_TRUE(notBlank(run.stats)) << describe(run.stats) << "\n" << run.output;
    EXPECT_TRUE(materialColoured(run.stats)) << describe(run.stats) << "\n" << run.output;
}

TEST(StockOsgviewer, ShowsAModelThroughThePseudoLoader) {
    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    const OsgviewerRun run =
        runOsgviewer(xvfb, {"vase.osgt.(sample-pca.btfmat,scale=4).btfmaterial"}, kExamplesDir,
                     [](const ScreenStats& s) { return notBlank(s) && materialColoured(s); });
    keepScreenshot(run.screen, "osgviewer-pseudo-loader");
    EXPECT_FALSE(run.exitedEarly) << run.output;
    EXPECT_TRUE(notBlank(run.stats)) << describe(run.stats) << "\n" << run.output;
    EXPECT_TRUE(materialColoured(run.stats)) << describe(run.stats) << "\n" << run.output;
}

// The RTI field's files as stock osgviewer users open them: `osgviewer icon.ptm` (a lit patch,
// osgdb_ptm) and an .rti under a model through the pseudo-loader, both written by `btf fit` from
// the real capture in tests/data/rti-icon-64; and a hand-written 2 x 1 .ptm and 2 x 2 .rti.
TEST(StockOsgviewer, ShowsPtmAndRtiFiles) {
    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    TempDir dir;
    const std::string capture = osgBTF::test::sourceDir() + "/tests/data/rti-icon-64";
    for (const std::string& args : {"-m ptm -o " + shellQuote(dir.file("icon.ptm")),
                                    "-m hsh -o " + shellQuote(dir.file("icon.rti"))}) {
        const CommandResult fit = runCommand(shellQuote(builtTool("btf")) + " --no-progress fit " +
                                             shellQuote(capture) + " " + args);
        ASSERT_EQ(fit.exitCode, 0) << fit.output;
    }
    std::string hand = "PTM_1.2\nPTM_FORMAT_RGB\n2 1\n1 1 1 1 1 1\n0 0 0 0 0 0\n";
    for (const int byte : {0, 0, 0, 0, 0, 250, 0, 0, 0, 0, 0, 90,   // R: a5 per pixel
                           0, 0, 0, 0, 0, 120, 0, 0, 0, 0, 0, 200,  // G
                           0, 0, 0, 0, 0, 30,  0, 0, 0, 0, 0, 60})  // B
        hand += char(byte);
    osgBTF::test::writeTextFile(dir.file("hand.ptm"), hand);
    // And a hand-written 2 x 2 .rti of 4 terms: only c0 (the constant harmonic, 1/sqrt(2 pi))
    // varies, ranges [0, 2] for c0 and [0, 0] for the others, top row red and green, bottom
    // row blue and white.
    std::string rti = "#HSH1.2\n3\n2 2 3\n4 2 1\n";
    for (const float v : {0.0f, 0.0f, 0.0f, 0.0f, 2.0f, 0.0f, 0.0f, 0.0f}) {
        std::uint32_t bits;
        std::memcpy(&bits, &v, 4);
        for (int i = 0; i < 4; ++i) rti += char((bits >> (8 * i)) & 0xFF);
    }
    for (const int c0 : {255, 0, 0, 0, 255, 0, 0, 0, 255, 255, 255, 255})  // R, G, B per pixel
        rti += std::string{char(c0), 0, 0, 0};
    osgBTF::test::writeTextFile(dir.file("hand.rti"), rti);
    for (const auto& [name, file] : std::vector<std::pair<std::string, std::string>>{
             {"osgviewer-icon-ptm", "icon.ptm"},
             {"osgviewer-hand-ptm", "hand.ptm"},
             {"osgviewer-hand-rti", "hand.rti"},
             {"osgviewer-vase-icon-rti",
              kExamplesDir + "/vase.osgt.(icon.rti,scale=2).btfmaterial"}}) {
        const std::vector<std::string> arguments{file};
        const OsgviewerRun run = runOsgviewer(xvfb, arguments, dir.path().string(),
                                              [](const ScreenStats& s) { return notBlank(s); });
        keepScreenshot(run.screen, name);
        EXPECT_FALSE(run.exitedEarly) << arguments.front() << "\n" << run.output;
        EXPECT_TRUE(notBlank(run.stats)) << arguments.front() << ": " << describe(run.stats) << "\n"
                                         << run.output;
    }
}

TEST(StockOsgviewer, ShowsAModelUnderAUbo2014FileAsStored) {
    // The line: osgviewer "model.osgt.(carpet.btf,scale=4).btfmaterial", with a
    // hand-written DFMF file (tests/HandWrittenUbo2014.h) opened as an fmf material.
    REQUIRE_XVFB();
    TempDir dir;
    const std::string btf = dir.file("carpet.btf");
    osgBTF::test::writeTextFile(btf, osgBTF::test::handWrittenDfmf11().bytes);
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    const OsgviewerRun run =
        runOsgviewer(xvfb, {"vase.osgt.(" + btf + ",scale=4).btfmaterial"}, kExamplesDir, notBlank);
    keepScreenshot(run.screen, "osgviewer-ubo2014");
    EXPECT_FALSE(run.exitedEarly) << run.output;
    EXPECT_TRUE(notBlank(run.stats)) << describe(run.stats) << "\n" << run.output;
}

TEST(StockOsgviewer, ShowsAModelUnderAStreamedTileSet) {
    // A BSVTF tile set (btf tiles of an fmf fit of the built-in sample) under a model through
    // the pseudo-loader: osgdb_bsvtf's StreamingGroup streams it from the folder while osgviewer
    // runs its update and feedback passes, until the sample's colours show.
    REQUIRE_XVFB();
    TempDir dir;
    const std::string btf = builtTool("btf") + " --no-progress ";
    for (const std::string& command :
         {btf + "sample -o " + shellQuote(dir.file("s.zip")) + " --size 32",
          btf + "fit " + shellQuote(dir.file("s.zip")) + " -m fmf --no-mipmap -o " +
              shellQuote(dir.file("f.btfmat")),
          btf + "tiles " + shellQuote(dir.file("f.btfmat")) + " -o " + shellQuote(dir.file("set")) +
              " --tile-size 16"}) {
        const CommandResult result = runCommand(command);
        ASSERT_EQ(result.exitCode, 0) << command << "\n" << result.output;
    }
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    const OsgviewerRun run = runOsgviewer(
        xvfb, {"vase.osgt.(" + dir.file("set") + "/index.bsvtf,scale=4).btfmaterial"}, kExamplesDir,
        [](const ScreenStats& s) { return notBlank(s) && materialColoured(s); });
    keepScreenshot(run.screen, "osgviewer-streamed");
    EXPECT_FALSE(run.exitedEarly) << run.output;
    EXPECT_TRUE(notBlank(run.stats)) << describe(run.stats) << "\n" << run.output;
    EXPECT_TRUE(materialColoured(run.stats)) << describe(run.stats) << "\n" << run.output;
    EXPECT_EQ(run.output.find("osgBTF"), std::string::npos) << run.output;
}

// ---- btfviewer ---------------------------------------------------------------------------

const std::string kBtfviewer = builtTool("btfviewer");

CommandResult runBtfviewer(const std::string& display, const std::string& arguments) {
    return runCommand("cd " + shellQuote(kExamplesDir) + " && DISPLAY=" + display +
                      " OSG_LIBRARY_PATH=" + shellQuote(kPluginDir) + " " + shellQuote(kBtfviewer) +
                      " " + arguments);
}

TEST(Btfviewer, BadInputFailsWithAClearMessage) {
    // All of these fail before a window opens: no X server needed.
    CommandResult result = runBtfviewer(":none", "nosuch.osgt");
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(result.output.find("btfviewer: nosuch.osgt: no such file"), std::string::npos)
        << result.output;

    result = runBtfviewer(":none", "sample-pca.btfmat --bogus");
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(result.output.find("btfviewer: "), std::string::npos) << result.output;
    EXPECT_NE(result.output.find("--bogus"), std::string::npos) << result.output;

    result = runBtfviewer(":none", "");
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(result.output.find("btfviewer: no input files (btfviewer --help)"), std::string::npos)
        << result.output;

    result = runBtfviewer(":none", "spheres.osgt --material 5");
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(result.output.find("btfviewer: --material 5: there are 2 materials (0 = own)"),
              std::string::npos)
        << result.output;

    result = runBtfviewer(":none", "'vase.osgt.(nosuch.btfmat).btfmaterial'");
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(result.output.find("nosuch.btfmat: no such file"), std::string::npos)
        << result.output;

    result = runBtfviewer(":none", "sample-pca.btfmat --env nosuch.hdr");
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(result.output.find("btfviewer: --env: nosuch.hdr: file not found"), std::string::npos)
        << result.output;

    result = runBtfviewer(":none", "--help");
    EXPECT_EQ(result.exitCode, 0) << result.output;
    for (const char* documented : {"--capture FILE", "--frames N", "--material N", "Shift + drag",
                                   "GL_ARB_timer_query", "--env FILE", "--env: exposure"})
        EXPECT_NE(result.output.find(documented), std::string::npos) << documented;
}

RgbImage readCapture(const std::string& path) {
    osg::ref_ptr<osg::Image> image = osgDB::readRefImageFile(path);
    return image.valid() ? fromOsgImage(*image) : RgbImage();
}

TEST(Btfviewer, CapturesAnExampleScene) {
    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    TempDir out;
    const CommandResult result = runBtfviewer(
        xvfb.display(), "cloth.osgt --window 0 0 320 240 --frames 3 --stats --capture " +
                            shellQuote(out.file("cloth.png")));
    ASSERT_EQ(result.exitCode, 0) << result.output;
    const RgbImage image = readCapture(out.file("cloth.png"));
    keepScreenshot(image, "btfviewer-cloth");
    ASSERT_EQ(image.width, 320);
    ASSERT_EQ(image.height, 240);
    const ScreenStats stats = analyse(image);
    EXPECT_TRUE(notBlank(stats)) << describe(stats);
    EXPECT_TRUE(materialColoured(stats)) << describe(stats);
}

// Without --window, osgViewer's default (AcrossAllScreens) asks the server for the screen's size
// on a connection of its own and opens a window of whatever came back: 0 x 0 when the server
// was resetting after its previous client left (xvfb-run's Xvfb), which X refuses (BadValue in
// CreateWindow): stock osgviewer failed 4 to 5 times in 8 so on a 640x480 screen here.
// btfviewer asks again and opens a window that fits the screen. Five runs in a row on such a
// server, each after the previous client left: every one opens the whole screen.
TEST(Btfviewer, OpensAWindowThatFitsASmallScreenWithoutWindowOption) {
    REQUIRE_XVFB();
    Xvfb xvfb(640, 480, /*resets=*/true);
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    TempDir out;
    for (int run = 0; run < 5; ++run) {
        SCOPED_TRACE("run " + std::to_string(run));
        const std::string file = out.file("spheres" + std::to_string(run) + ".png");
        const CommandResult result = runBtfviewer(
            xvfb.display(), "spheres.osgt --no-hud --frames 2 --capture " + shellQuote(file));
        ASSERT_EQ(result.exitCode, 0) << result.output;
        EXPECT_NE(result.output.find("btfviewer: window 640x480 (the whole screen)"),
                  std::string::npos)
            << result.output;
        const RgbImage image = readCapture(file);
        if (run == 0) keepScreenshot(image, "btfviewer-default-window");
        ASSERT_EQ(image.width, 640);
        ASSERT_EQ(image.height, 480);
        const ScreenStats stats = analyse(image);
        EXPECT_TRUE(notBlank(stats)) << describe(stats);
        EXPECT_TRUE(materialColoured(stats)) << describe(stats);
    }
}

TEST(Btfviewer, SaysWhyNoWindowOpens) {
    // No server on that display: the message names the display and X's own words, not a guess.
    CommandResult result = runBtfviewer(":4242", "spheres.osgt --frames 1");
    EXPECT_EQ(result.exitCode, 1) << result.output;
    EXPECT_NE(result.output.find("btfviewer: cannot open a window on DISPLAY=:4242: no X server "
                                 "answered"),
              std::string::npos)
        << result.output;
    EXPECT_NE(result.output.find("Unable to open display \":4242"), std::string::npos)
        << result.output;
    EXPECT_EQ(result.output.find("is DISPLAY set?"), std::string::npos) << result.output;

    result = runCommand("cd " + shellQuote(kExamplesDir) +
                        " && env -u DISPLAY OSG_LIBRARY_PATH=" + shellQuote(kPluginDir) + " " +
                        shellQuote(kBtfviewer) + " spheres.osgt --frames 1");
    EXPECT_EQ(result.exitCode, 1) << result.output;
    EXPECT_NE(result.output.find("btfviewer: cannot open a window: DISPLAY is not set"),
              std::string::npos)
        << result.output;
}

// The terminator itself is tested in tests/gl/shadow_test.cpp; here the scene and the options.
TEST(Btfviewer, TheShadowedClothShowsItsShadowAndTheKeysOptionsWork) {
    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    TempDir out;
    auto capture = [&](const std::string& options, const std::string& name) {
        const CommandResult result =
            runBtfviewer(xvfb.display(), "cloth-shadows.osgt --no-orbit-light --no-hud " + options +
                                             " --window 0 0 320 240 --frames 3 --capture " +
                                             shellQuote(out.file(name)));
        EXPECT_EQ(result.exitCode, 0) << result.output;
        return readCapture(out.file(name));
    };
    const RgbImage shadowed = capture("", "shadows.png");
    const RgbImage unshadowed = capture("--no-shadows", "no-shadows.png");
    keepScreenshot(shadowed, "btfviewer-cloth-shadows");
    ASSERT_EQ(shadowed.width, 320);
    ASSERT_EQ(unshadowed.width, 320);
    EXPECT_TRUE(materialColoured(analyse(shadowed))) << describe(analyse(shadowed));
    // The shadow darkens part of the floor and cloth: many pixels darker with shadows than
    // without, none brighter by much.
    auto darker = [](const RgbImage& a, const RgbImage& b) {
        int count = 0;
        for (std::size_t i = 0; i + 2 < a.rgb.size(); i += 3) {
            const int sa = a.rgb[i] + a.rgb[i + 1] + a.rgb[i + 2];
            const int sb = b.rgb[i] + b.rgb[i + 1] + b.rgb[i + 2];
            if (sa + 30 < sb) ++count;
        }
        return count;
    };
    EXPECT_GT(darker(shadowed, unshadowed), 500);
    EXPECT_LT(darker(unshadowed, shadowed), 50);

    for (const auto& [options, message] :
         {std::pair<std::string, std::string>{
              "--terminator-alpha 70", "btfviewer: --terminator-alpha: must be 0..60 degrees"},
          {"--shadows --no-shadows", "btfviewer: --shadows and --no-shadows: give one of them"}}) {
        const CommandResult bad = runBtfviewer(":none", "cloth-shadows.osgt " + options);
        EXPECT_EQ(bad.exitCode, 1) << options;
        EXPECT_NE(bad.output.find(message), std::string::npos) << bad.output;
    }
}

TEST(Btfviewer, ShowsAUbo2014FileAsStored) {
    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    TempDir out;
    const std::string btf = out.file("carpet.btf");
    osgBTF::test::writeTextFile(btf, osgBTF::test::handWrittenDfmf11().bytes);
    const CommandResult result =
        runBtfviewer(xvfb.display(), shellQuote(btf) + " --window 0 0 320 240 --capture " +
                                         shellQuote(out.file("carpet.png")));
    ASSERT_EQ(result.exitCode, 0) << result.output;
    EXPECT_NE(result.output.find("1: carpet.btf (fmf)"), std::string::npos) << result.output;
    const RgbImage image = readCapture(out.file("carpet.png"));
    keepScreenshot(image, "btfviewer-ubo2014");
    EXPECT_TRUE(notBlank(analyse(image))) << describe(analyse(image));
}

/** Pixels whose colours differ by more than a small amount (sum over RGB > 12). */
std::size_t differingPixels(const RgbImage& a, const RgbImage& b) {
    if (a.rgb.size() != b.rgb.size()) return std::max(a.rgb.size(), b.rgb.size()) / 3;
    std::size_t differing = 0;
    for (std::size_t i = 0; i < a.rgb.size(); i += 3) {
        int difference = 0;
        for (int c = 0; c < 3; ++c) difference += std::abs(a.rgb[i + c] - b.rgb[i + c]);
        if (difference > 12) ++differing;
    }
    return differing;
}

TEST(Btfviewer, MaterialFilesGoOnSpheresAndTheMaterialKeysSwitchThem) {
    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    TempDir out;
    // Material 1 (lambert) on both spheres, then 2 (pca), then 1 again: the repeat shows how
    // much two identical runs differ (nothing: the view and lights are fixed), so the
    // difference between 1 and 2 is the switch.
    std::vector<RgbImage> images;
    for (int material : {1, 2, 1}) {
        const std::string file = out.file("m" + std::to_string(images.size()) + ".png");
        const CommandResult result = runBtfviewer(
            xvfb.display(), "sample-lambert.btfmat sample-pca.btfmat --no-hud --material " +
                                std::to_string(material) +
                                " --window 0 0 320 240 --frames 2 --capture " + shellQuote(file));
        ASSERT_EQ(result.exitCode, 0) << result.output;
        EXPECT_NE(result.output.find("2 object(s) with a BTF material, 2 material(s)"),
                  std::string::npos)
            << result.output;
        images.push_back(readCapture(file));
        keepScreenshot(images.back(), "btfviewer-material-" + std::to_string(material));
        const ScreenStats stats = analyse(images.back());
        EXPECT_TRUE(notBlank(stats)) << describe(stats);
        EXPECT_TRUE(materialColoured(stats)) << describe(stats);
    }
    const std::size_t pixels = images[0].rgb.size() / 3;
    EXPECT_LE(differingPixels(images[0], images[2]), pixels / 2000) << "runs are not repeatable";
    EXPECT_GT(differingPixels(images[0], images[1]), pixels / 200)
        << "material 1 and 2 look the same";
}

// An RTI capture by its light file (osgdb_lp): RTI mode by itself (one view), the patch seen as
// captured; light from the right and from the left give different pictures, a fixed view the same
// picture twice.
TEST(Btfviewer, ShowsAnRtiCaptureInRtiMode) {
    const std::string lp = osgBTF::test::sourceDir() + "/tests/data/rti-icon-64/dirs.lp";
    CommandResult result = runBtfviewer(
        ":none", shellQuote(lp) + " -O \"method=lambert cache=off\" --rti --model x.osgt");
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(result.output.find("btfviewer: --rti: needs exactly one material file or capture, "
                                 "without --model, --surface-size or --map"),
              std::string::npos)
        << result.output;

    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    TempDir out;
    std::vector<RgbImage> images;
    for (const std::string light : {"90 30", "-90 30", "90 30"}) {
        const std::string file = out.file("rti" + std::to_string(images.size()) + ".png");
        result = runBtfviewer(xvfb.display(),
                              shellQuote(lp) + " -O \"method=hsh cache=off\" --no-hud --light " +
                                  light + " --window 0 0 320 240 --capture " + shellQuote(file));
        ASSERT_EQ(result.exitCode, 0) << result.output;
        EXPECT_NE(result.output.find("btfviewer: RTI mode (64x64, 1 view(s), 72 lights)"),
                  std::string::npos)
            << result.output;
        images.push_back(readCapture(file));
        const ScreenStats stats = analyse(images.back());
        EXPECT_TRUE(notBlank(stats)) << describe(stats);
    }
    keepScreenshot(images[0], "btfviewer-rti-light-right");
    keepScreenshot(images[1], "btfviewer-rti-light-left");
    const std::size_t pixels = images[0].rgb.size() / 3;
    EXPECT_LE(differingPixels(images[0], images[2]), pixels / 2000) << "runs are not repeatable";
    EXPECT_GT(differingPixels(images[0], images[1]), pixels / 50)
        << "the light's side changed nothing";
}

TEST(Btfviewer, CoversASurfaceThroughACoordinateMap) {
    TempDir out;
    // The fixture's sample is 8x8: a 64x64 block map into it, and one into another size.
    const std::string map = out.file("map.exr"), other = out.file("other.exr");
    osgBTF::writeCoordinateMap(osgBTF::makeBlockCoordinateMap(64, 64, 8, 8, 2, 1), map);
    osgBTF::writeCoordinateMap(osgBTF::makeBlockCoordinateMap(64, 64, 16, 16, 2, 1), other);
    CommandResult result =
        runBtfviewer(":none", "sample-pca.btfmat --surface-size 16 --map " + shellQuote(other));
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(
        result.output.find("btfviewer: " + other + ": made for a 16x16 sample, but material '"),
        std::string::npos)
        << result.output;
    result = runBtfviewer(":none", "sample-pca.btfmat --surface-size 0");
    EXPECT_EQ(result.exitCode, 1);
    EXPECT_NE(result.output.find("btfviewer: --surface-size: must be positive (metres)"),
              std::string::npos)
        << result.output;

    REQUIRE_XVFB();
    Xvfb xvfb;
    ASSERT_TRUE(xvfb.ok()) << "Xvfb did not start: " << xvfb.log();
    // The same texel size both ways: the map (64 texels per repeat, once over the surface) and
    // the sample tiled 8 times (8 texels per repeat).
    std::vector<RgbImage> images;
    for (const std::string& how : {"--map " + shellQuote(map), std::string("--scale 8")}) {
        const std::string file = out.file("surface" + std::to_string(images.size()) + ".png");
        result =
            runBtfviewer(xvfb.display(), "sample-pca.btfmat --surface-size 16 --no-hud " + how +
                                             " --window 0 0 320 240 --capture " + shellQuote(file));
        ASSERT_EQ(result.exitCode, 0) << result.output;
        if (images.empty()) {
            EXPECT_NE(result.output.find("sample-pca.btfmat through the coordinate map " + map +
                                         ": 64x64 texels per repeat from the 8x8 sample"),
                      std::string::npos)
                << result.output;
        }
        images.push_back(readCapture(file));
        keepScreenshot(images.back(),
                       images.size() == 1 ? "btfviewer-surface-map" : "btfviewer-surface-tiled");
        const ScreenStats stats = analyse(images.back());
        EXPECT_TRUE(notBlank(stats)) << describe(stats);
        EXPECT_TRUE(materialColoured(stats)) << describe(stats);
    }
    EXPECT_GT(differingPixels(images[0], images[1]), images[0].rgb.size() / 3 / 200)
        << "the map changed nothing";
}

}  // namespace

}  // namespace OSGBTF_TEST_FILE
