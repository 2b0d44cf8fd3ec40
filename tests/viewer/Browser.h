// Pages opened in Debian's headless Chromium, for the tests of the pages the tools write (the
// gallery, the batch leaderboard).
//
// How the browser's view is read: `chromium --headless --dump-dom` prints the page's DOM after
// its load event, where the page's own script has written what a test checks into attributes of
// the body; with --enable-logging=stderr every console message (a script error, a console.error)
// appears on stderr as "CONSOLE".
#pragma once

#include <filesystem>
#include <string>

namespace osgBTF::test {

struct BrowserView {
    int exitCode = -1;
    std::string dom;
    std::string log;
    /** The number in the first data-NAME="N" of the DOM, -1 when absent. */
    int attribute(const std::string& name) const;
    /** The text of the first data-NAME="..." of the DOM, empty when absent. */
    std::string text(const std::string& name) const;
    bool consoleMessages() const { return log.find("CONSOLE") != std::string::npos; }
};

bool haveChromium();

/** Opens `page` (a file) in a fresh profile under `scratch` and waits for its load event;
 *  `flags` are added to Chromium's command line. */
BrowserView openInChromium(const std::string& page, const std::filesystem::path& scratch,
                           const std::string& flags = "");

}  // namespace osgBTF::test
