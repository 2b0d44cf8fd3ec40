#include "tests/viewer/Browser.h"

#include <regex>

#include "tests/TestUtil.h"

namespace osgBTF::test {

namespace fs = std::filesystem;

int BrowserView::attribute(const std::string& name) const {
    const std::string value = text(name);
    return value.empty() || value.find_first_not_of("0123456789") != std::string::npos
               ? -1
               : std::stoi(value);
}

std::string BrowserView::text(const std::string& name) const {
    std::smatch match;
    if (!std::regex_search(dom, match, std::regex("data-" + name + "=\"([^\"]*)\""))) return "";
    return match[1];
}

bool haveChromium() {
    return runCommand("command -v chromium >/dev/null").exitCode == 0;
}

BrowserView openInChromium(const std::string& page, const fs::path& scratch,
                           const std::string& flags) {
    // --no-sandbox: CI runs as root, where Chromium's sandbox refuses to start. The virtual time
    // budget lets the page load (pictures decoded, load event run) before the DOM is dumped. A
    // fresh profile per run: nothing cached from the previous one. In braces: runCommand adds
    // 2>&1 to the whole line, which would otherwise send the log into the DOM file. The
    // background-networking flags keep Chromium from calling out of this closed network.
    static int run = 0;
    const std::string profile = (scratch / ("profile-" + std::to_string(++run))).string();
    const std::string log = (scratch / "chromium.log").string();
    const std::string dom = (scratch / "dom.html").string();
    const std::string command =
        "{ timeout 120 chromium --headless --no-sandbox --disable-gpu --user-data-dir=" +
        shellQuote(profile) +
        " --no-first-run --disable-background-networking --disable-component-update "
        "--disable-sync --enable-logging=stderr --v=0 --virtual-time-budget=10000 --dump-dom " +
        flags + " " + shellQuote("file://" + fs::absolute(page).string()) + " >" + shellQuote(dom) +
        " 2>" + shellQuote(log) + "; }";
    BrowserView view;
    view.exitCode = runCommand(command).exitCode;
    view.dom = readTextFile(dom);
    view.log = readTextFile(log);
    return view;
}

}  // namespace osgBTF::test
