// `btf batch report`'s index.html in a real browser (Debian's headless Chromium): it loads from
// disk without console messages, its table has one row per job and a plot per material and per
// class, and a click on a column header sorts the rows (nulls last), a second click reverses them.
// The results are written by hand (tests/HandMadeBatch.h), not by running jobs.
#include <gtest/gtest.h>

#include <filesystem>
#include <map>
#include <sstream>

#include "tests/HandMadeBatch.h"
#include "tests/TestUtil.h"
#include "tests/viewer/Browser.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF::test;

namespace {

std::vector<std::string> split(const std::string& text) {
    std::vector<std::string> items;
    std::string item;
    std::istringstream in(text);
    while (std::getline(in, item, ','))
        if (!item.empty()) items.push_back(item);
    return items;
}

// HandMadeBatch.h's bytes per texel; -1: the job has none (failed, pending).
const std::map<std::string, double> kBytes = {
    {"wool01--lambert", 6},  {"wool01--pca", 40},  {"wool01--ptm", 36},
    {"wool02--lambert", 6},  {"wool02--pca", -1},  {"wool02--ptm", 36},
    {"stone01--lambert", 6}, {"stone01--pca", 40}, {"stone01--ptm", -1}};

/** Sorted by bytes in `direction` (+1 ascending, -1 descending), the jobs without any last. */
void expectSortedByBytes(const std::vector<std::string>& order, int direction) {
    ASSERT_EQ(order.size(), kBytes.size());
    bool nulls = false;
    double last = direction > 0 ? -1e300 : 1e300;
    for (const std::string& job : order) {
        ASSERT_TRUE(kBytes.count(job)) << job;
        const double bytes = kBytes.at(job);
        if (bytes < 0) {
            nulls = true;
            continue;
        }
        EXPECT_FALSE(nulls) << job << " after a job without a value";
        EXPECT_GE(bytes * direction, last * direction) << job;
        last = bytes;
    }
}

}  // namespace

TEST(Leaderboard, PageLoadsWithEveryRowAndPlotAndSortsOnAClick) {
    TempDir dir;
    const fs::path results = dir.path() / "results";
    writeHandMadeBatch(results);
    const CommandResult r = runCommand(builtTool("btf") + " --no-progress batch report " +
                                       shellQuote(results.string()));
    ASSERT_EQ(r.exitCode, 0) << r.output;
    const fs::path page = results / "index.html";
    ASSERT_TRUE(fs::exists(page));
    if (!haveChromium())
        GTEST_SKIP() << "chromium is not installed (Debian package chromium; tools/setup.sh "
                        "installs it): the page was not opened in a browser";

    const BrowserView view = openInChromium(page.string(), dir.path());
    ASSERT_EQ(view.exitCode, 0) << view.log;
    EXPECT_EQ(view.attribute("ready"), 1) << view.dom;
    EXPECT_EQ(view.attribute("rows"), 9);
    EXPECT_EQ(view.attribute("plots"), 3 + 2);  // per material, per class
    EXPECT_FALSE(view.consoleMessages()) << view.log;

    // A copy that clicks the bytes-per-texel header twice once the page has loaded, and writes
    // the row order after each click into the body.
    std::string html = readTextFile(page.string());
    const std::string clicks = R"(<script>
window.addEventListener('load', () => {
  const order = () => [...document.querySelectorAll('tbody tr[data-job]')]
      .filter((row) => row.closest('table').id === 'board').map((row) => row.dataset.job).join(',');
  const header = document.querySelector('#board th[data-key="bytes_per_texel"]');
  header.click();
  document.body.dataset.testAscending = order();
  document.body.dataset.testKey = document.body.dataset.sortKey + '/' + document.body.dataset.sortDir;
  header.click();
  document.body.dataset.testDescending = order();
});
</script>
)";
    const auto end = html.rfind("</body>");
    ASSERT_NE(end, std::string::npos);
    html.insert(end, clicks);
    const fs::path clicked = results / "clicked.html";
    writeTextFile(clicked.string(), html);
    const BrowserView sorted = openInChromium(clicked.string(), dir.path());
    ASSERT_EQ(sorted.exitCode, 0) << sorted.log;
    EXPECT_FALSE(sorted.consoleMessages()) << sorted.log;
    EXPECT_EQ(sorted.text("test-key"), "bytes_per_texel/asc") << sorted.dom;
    expectSortedByBytes(split(sorted.text("test-ascending")), +1);
    expectSortedByBytes(split(sorted.text("test-descending")), -1);

    // The check sees a broken page: a script error is logged.
    writeTextFile(clicked.string(), html + "<script>notAFunction();</script>\n");
    EXPECT_TRUE(openInChromium(clicked.string(), dir.path()).consoleMessages());
}

}  // namespace OSGBTF_TEST_FILE
