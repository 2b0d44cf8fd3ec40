// btfviewer's window (WindowSetup.h says why osgViewer's default is not used).
#include "examples/btfviewer/WindowSetup.h"

#include <algorithm>
#include <chrono>
#include <cstdlib>
#include <iostream>
#include <mutex>
#include <thread>
#include <vector>

#include <osg/GraphicsContext>
#include <osg/Notify>
#include <osgViewer/config/SingleWindow>

#include "core/Error.h"

namespace btfviewer {
namespace {

/** Keeps what OSG reports (notice and worse) while installed: X errors reach the application
 *  only as OSG notices ("BadValue (integer parameter out of range for operation)", "Unable to
 *  open display ..."). Raises the notify level to NOTICE meanwhile and passes on to the previous
 *  handler only what the user's own level shows, and only while `forward` is set. */
class NotifyRecorder : public osg::NotifyHandler {
public:
    void notify(osg::NotifySeverity severity, const char* message) override {
        std::string line(message ? message : "");
        while (!line.empty() && (line.back() == '\n' || line.back() == ' ')) line.pop_back();
        line.erase(0, line.find_first_not_of(' '));
        {
            std::lock_guard<std::mutex> lock(_mutex);
            if (!line.empty() && severity <= osg::NOTICE) _lines.push_back(line);
        }
        if (forward && previous && severity <= userLevel) previous->notify(severity, message);
    }
    /** The lines since `from` that say what went wrong: OSG's per-error preamble ("Got an
     *  X11ErrorHandling call ...", "Error code: N") and its progress notes left out, each line
     *  once. */
    std::vector<std::string> problems(std::size_t from = 0) const {
        std::lock_guard<std::mutex> lock(_mutex);
        std::vector<std::string> out;
        for (std::size_t i = from; i < _lines.size(); ++i) {
            const std::string& line = _lines[i];
            if (line.rfind("Got an X11ErrorHandling call", 0) == 0 ||
                line.rfind("Error code:", 0) == 0 ||
                line.find("has been created") != std::string::npos ||
                line.rfind("SingleWindow::configure", 0) == 0)
                continue;
            if (std::find(out.begin(), out.end(), line) == out.end()) out.push_back(line);
        }
        return out;
    }
    std::size_t size() const {
        std::lock_guard<std::mutex> lock(_mutex);
        return _lines.size();
    }

    osg::ref_ptr<osg::NotifyHandler> previous;
    osg::NotifySeverity userLevel = osg::NOTICE;
    bool forward = true;

protected:
    ~NotifyRecorder() override = default;

private:
    mutable std::mutex _mutex;
    std::vector<std::string> _lines;
};

/** Installs a NotifyRecorder for its lifetime. */
class RecordNotices {
public:
    RecordNotices() : _recorder(new NotifyRecorder) {
        _recorder->previous = osg::getNotifyHandler();
        _recorder->userLevel = osg::getNotifyLevel();
        if (_recorder->userLevel < osg::NOTICE) osg::setNotifyLevel(osg::NOTICE);
        osg::setNotifyHandler(_recorder.get());
    }
    ~RecordNotices() {
        osg::setNotifyHandler(_recorder->previous.get());
        osg::setNotifyLevel(_recorder->userLevel);
    }
    RecordNotices(const RecordNotices&) = delete;
    RecordNotices& operator=(const RecordNotices&) = delete;
    NotifyRecorder& operator*() const { return *_recorder; }
    NotifyRecorder* operator->() const { return _recorder.get(); }

private:
    osg::ref_ptr<NotifyRecorder> _recorder;
};

std::string joined(const std::vector<std::string>& lines, const char* separator = "; ") {
    std::string out;
    for (const std::string& line : lines) out += (out.empty() ? "" : separator) + line;
    return out;
}

std::string sizeText(unsigned width, unsigned height) {
    return std::to_string(width) + "x" + std::to_string(height);
}

bool envSet(const char* name) {
    const char* value = std::getenv(name);
    return value && *value;
}

/** Throws "cannot open a window on DISPLAY=D: WHAT; the X server and OSG said: ...". */
[[noreturn]] void fail(const std::string& what, const NotifyRecorder& recorder) {
    const std::vector<std::string> problems = recorder.problems();
    std::string message = "cannot open a window";
    if (envSet("DISPLAY")) message += std::string(" on DISPLAY=") + std::getenv("DISPLAY");
    message += ": " + what;
    if (!problems.empty()) message += "; the X server and OSG said: " + joined(problems);
    throw osgBTF::Error(message);
}

struct WindowChoice {
    unsigned width, height;
    bool wholeScreen;
};

}  // namespace

void openWindow(osgViewer::Viewer& viewer) {
    RecordNotices recorder;
    osgViewer::Viewer::Contexts contexts;
    viewer.getContexts(contexts);
    if (!contexts.empty() || envSet("OSG_WINDOW") || envSet("OSG_SCREEN") ||
        envSet("OSG_CONFIG_FILE")) {
        // The user's own choice: osgViewer opens it, nothing else is tried.
        viewer.realize();
        if (!viewer.isRealized())
            fail(contexts.empty() ? "the window OSG_WINDOW, OSG_SCREEN or OSG_CONFIG_FILE names"
                                  : "the window of --window or --screen",
                 *recorder);
        return;
    }
    // OSG would take an unset DISPLAY for ":0.0"; X clients refuse it.
    if (!envSet("DISPLAY"))
        fail(
            "DISPLAY is not set (run it on an X server, e.g. xvfb-run -a -s '-screen 0 "
            "1024x768x24' btfviewer ...)",
            *recorder);

    osg::GraphicsContext::WindowingSystemInterface* wsi =
        osg::GraphicsContext::getWindowingSystemInterface();
    if (!wsi) fail("osgViewer has no windowing system", *recorder);
    osg::GraphicsContext::ScreenIdentifier screen;
    screen.readDISPLAY();
    if (screen.displayNum < 0) screen.displayNum = 0;
    if (screen.screenNum < 0) screen.screenNum = 0;

    // Each query opens and closes a connection; a server that resets after its last client
    // left refuses the next one for a moment, so ask again, waiting longer each time (1.55 s in
    // all). The failed queries' "Unable to open display" stays out of the terminal.
    unsigned screenWidth = 0, screenHeight = 0;
    recorder->forward = false;
    for (int attempt = 0; attempt < 6 && (screenWidth == 0 || screenHeight == 0); ++attempt) {
        if (attempt > 0)
            std::this_thread::sleep_for(std::chrono::milliseconds(50 << (attempt - 1)));
        wsi->getScreenResolution(screen, screenWidth, screenHeight);
    }
    recorder->forward = true;
    // No answer in all that time: no server there (a wrong display number, a server that
    // exited), which no window size changes.
    if (screenWidth == 0 || screenHeight == 0)
        fail("no X server answered (asked for the screen's size 6 times in 1.6 s)", *recorder);

    std::vector<WindowChoice> choices = {{screenWidth, screenHeight, true}};
    for (const WindowChoice smaller :
         {WindowChoice{640, 480, false}, WindowChoice{320, 240, false}})
        if (smaller.width < choices.back().width && smaller.height < choices.back().height)
            choices.push_back(smaller);

    std::vector<std::string> tried;
    for (const WindowChoice& choice : choices) {
        // A window whose connection is refused (the same reset) is tried again before a smaller
        // one: only a window the server turns down for what it is makes the next one smaller.
        for (int attempt = 0; attempt < 4; ++attempt) {
            if (attempt > 0) std::this_thread::sleep_for(std::chrono::milliseconds(100 << attempt));
            const std::size_t before = recorder->size();
            osg::ref_ptr<osgViewer::SingleWindow> config = new osgViewer::SingleWindow(
                0, 0, int(choice.width), int(choice.height), unsigned(screen.screenNum));
            config->setWindowDecoration(!choice.wholeScreen);
            viewer.apply(config.get());
            if (viewer.getCamera()->getGraphicsContext()) {
                viewer.realize();
                if (viewer.isRealized()) {
                    std::cout << "btfviewer: window " << sizeText(choice.width, choice.height)
                              << (choice.wholeScreen
                                      ? " (the whole screen)"
                                      : " (the screen is " + sizeText(screenWidth, screenHeight) +
                                            ")")
                              << (tried.empty() ? "" : "; did not open: " + joined(tried, ", "))
                              << std::endl;
                    return;
                }
                viewer.getCamera()->setGraphicsContext(nullptr);
            }
            const std::vector<std::string> problems = recorder->problems(before);
            const bool refused =
                std::any_of(problems.begin(), problems.end(), [](const std::string& line) {
                    return line.find("Unable to open display") != std::string::npos;
                });
            if (!refused) break;
        }
        tried.push_back(choice.wholeScreen
                            ? "the whole screen (" + sizeText(choice.width, choice.height) + ")"
                            : sizeText(choice.width, choice.height));
    }
    fail("tried " + joined(tried, ", "), *recorder);
}

}  // namespace btfviewer
