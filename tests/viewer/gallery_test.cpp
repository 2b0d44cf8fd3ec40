// btf-examples --gallery: the page opens in a real browser (Debian's headless Chromium) without
// console messages, and the browser shows every picture the page names. The pictures' pixels are
// not judged here (the GL tests compare renders with the CPU reference); that each one decodes
// and is shown is.
//
// The page's own script writes into the body how many of its pictures the browser could decode
// (data-pictures-shown) out of how many it has (data-pictures); tests/viewer/Browser.h reads
// them and the console. Both checks are checked: a gallery with one picture deleted shows one
// fewer, and a page with a script error logs it.
#include <gtest/gtest.h>

#include <filesystem>
#include <regex>
#include <set>
#include <string>

#include "tests/TestUtil.h"
#include "tests/viewer/Browser.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using osgBTF::test::BrowserView;
using osgBTF::test::builtTool;
using osgBTF::test::CommandResult;
using osgBTF::test::haveChromium;
using osgBTF::test::openInChromium;
using osgBTF::test::readTextFile;
using osgBTF::test::runCommand;
using osgBTF::test::shellQuote;
using osgBTF::test::TempDir;
using osgBTF::test::writeTextFile;

namespace {

const std::vector<std::string> kMethods = {"lambert", "pca"};
// examples/btf-examples/Gallery.cpp: galleryViews(), in column order.
const std::vector<std::string> kViews = {"close-up", "grazing", "distance", "environment",
                                         "shadows"};

std::string joined(const std::vector<std::string>& items) {
    std::string out;
    for (const std::string& item : items) out += (out.empty() ? "" : ",") + item;
    return out;
}

}  // namespace

TEST(Gallery, AFolderThatIsNotAGalleryIsNotReplaced) {
    TempDir dir;
    writeTextFile(dir.file("keep.txt"), "mine");
    const CommandResult result =
        runCommand(builtTool("btf-examples") + " --gallery " + shellQuote(dir.path().string()) +
                   " --size 8 --methods lambert --no-progress 2>&1");
    EXPECT_EQ(result.exitCode, 1) << result.output;
    EXPECT_NE(result.output.find("btf-examples: " + dir.path().string() +
                                 ": exists and is not a gallery (no index.html): choose another "
                                 "folder"),
              std::string::npos)
        << result.output;
    EXPECT_EQ(readTextFile(dir.file("keep.txt")), "mine");
}

TEST(Gallery, EveryPictureIsShownInAHeadlessBrowserWithoutConsoleMessages) {
    TempDir dir;
    const fs::path gallery = dir.path() / "gallery";
    const CommandResult result =
        runCommand(builtTool("btf-examples") + " --gallery " + shellQuote(gallery.string()) +
                   " --size 8 --methods " + joined(kMethods) + " --no-progress 2>&1");
    ASSERT_EQ(result.exitCode, 0) << result.output;
    const std::string page = (gallery / "index.html").string();
    ASSERT_TRUE(fs::exists(page)) << result.output;
    EXPECT_TRUE(fs::exists(gallery / "compare" / "report.md"));

    // The page names one picture per method and view, and each file is there.
    const std::string html = readTextFile(page);
    const std::regex image("<img src=\"([^\"]+)\"");
    std::set<std::string> named;
    for (auto it = std::sregex_iterator(html.begin(), html.end(), image);
         it != std::sregex_iterator(); ++it)
        named.insert((*it)[1]);
    std::set<std::string> expected;
    for (const std::string& method : kMethods)
        for (const std::string& view : kViews)
            expected.insert("pictures/" + method + "-" + view + ".png");
    EXPECT_EQ(named, expected);
    for (const std::string& file : expected) EXPECT_TRUE(fs::exists(gallery / file)) << file;

    if (!haveChromium())
        GTEST_SKIP() << "chromium is not installed (Debian package chromium; tools/setup.sh "
                        "installs it): the page was not opened in a browser";
    const BrowserView view = openInChromium(page, dir.path());
    ASSERT_EQ(view.exitCode, 0) << view.log;
    EXPECT_EQ(view.attribute("pictures"), int(expected.size())) << view.dom;
    EXPECT_EQ(view.attribute("pictures-shown"), int(expected.size())) << view.dom;
    EXPECT_FALSE(view.consoleMessages()) << view.log;

    // The checks see a broken gallery: one picture missing, then a script error.
    fs::remove(gallery / *expected.begin());
    const BrowserView missing = openInChromium(page, dir.path());
    EXPECT_EQ(missing.attribute("pictures"), int(expected.size()));
    EXPECT_EQ(missing.attribute("pictures-shown"), int(expected.size()) - 1) << missing.dom;
    writeTextFile(page, readTextFile(page) + "<script>notAFunction();</script>\n");
    const BrowserView broken = openInChromium(page, dir.path());
    EXPECT_TRUE(broken.consoleMessages()) << broken.log;
}

}  // namespace OSGBTF_TEST_FILE
