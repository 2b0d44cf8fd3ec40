// core/Progress.h: the observer that hears every Progress and may stop the work (what the
// Python module reports fits and Ctrl-C through).
#include <atomic>
#include <cstddef>
#include <mutex>
#include <string>
#include <vector>

#include <gtest/gtest.h>
#include <tbb/parallel_for.h>

#include "core/Progress.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

/** Removes the observer and any stop, whatever a test left. */
struct ObserverGuard {
    ~ObserverGuard() {
        Progress::setObserver(nullptr);
        Progress::clearStop();
    }
};

TEST(ProgressObserver, HearsTheLabelAndTheFinalTotal) {
    ObserverGuard guard;
    std::mutex mutex;
    std::vector<std::size_t> done;
    std::string label;
    Progress::setObserver([&](const std::string& l, std::size_t d, std::size_t total) {
        std::lock_guard<std::mutex> lock(mutex);
        label = l;
        EXPECT_EQ(total, 1000u);
        EXPECT_LE(d, total);
        done.push_back(d);
        return true;
    });
    {
        Progress progress("work", 1000);
        for (int i = 0; i < 1000; ++i) progress.advance();
    }
    // The first advance reports (nothing drawn before), finish() reports the total.
    ASSERT_GE(done.size(), 2u);
    EXPECT_EQ(done.front(), 1u);
    EXPECT_EQ(done.back(), 1000u);
    EXPECT_EQ(label, "work");
}

TEST(ProgressObserver, ReturningFalseStopsTheWorkInEveryThread) {
    ObserverGuard guard;
    Progress::setObserver([](const std::string&, std::size_t, std::size_t) { return false; });
    std::atomic<int> reached{0};
    EXPECT_THROW(
        {
            Progress progress("parallel", 100000);
            tbb::parallel_for(0, 100000, [&](int) {
                progress.advance();
                ++reached;
            });
        },
        Progress::Cancelled);
    EXPECT_LT(reached.load(), 100000);
    EXPECT_TRUE(Progress::stopRequested());
    // Until cleared, every Progress stops at its first step.
    Progress::setObserver(nullptr);
    Progress other("other", 10);
    EXPECT_THROW(other.advance(), Progress::Cancelled);
    Progress::clearStop();
    EXPECT_NO_THROW(other.advance());
}

TEST(ProgressObserver, RequestStopWithoutAnObserver) {
    ObserverGuard guard;
    Progress progress("plain", 10);
    EXPECT_NO_THROW(progress.advance());
    Progress::requestStop();
    try {
        progress.advance();
        FAIL() << "no Cancelled";
    } catch (const Error& e) {  // a Cancelled is an osgBTF Error like any other
        EXPECT_STREQ(e.what(), "cancelled");
    }
}

}  // namespace OSGBTF_TEST_FILE
