// Several threads reading the same .btfmat, .zip (fitted, through the fit cache) and UBO2014
// .btf at once through osgDB: from std::threads calling osgDB::readRefNodeFile, and through an
// osgDB::DatabasePager whose threads load ProxyNodes naming the same files.
// These run in the ThreadSanitizer build too (ctest label "concurrency", README "Reliability").
#include <algorithm>
#include <atomic>
#include <chrono>
#include <filesystem>
#include <map>
#include <memory>
#include <mutex>
#include <set>
#include <string>
#include <thread>
#include <vector>

#include <dlfcn.h>

#include <gtest/gtest.h>
#include <tbb/global_control.h>
#include <tbb/parallel_for.h>

#include <osg/FrameStamp>
#include <osg/ProxyNode>
#include <osgDB/DatabasePager>
#include <osgDB/ReadFile>

#include "harness/sample/SampleBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "loaders/Ubo2014.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/fmf/Fmf.h"
#include "scene/MaterialNode.h"
#include "scene/OpenMaterial.h"
#include "streaming/TileFetcher.h"
#include "tests/PluginTestUtil.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;
namespace fs = std::filesystem;

namespace {

#if defined(__SANITIZE_THREAD__)
// TBB (Debian's, uninstrumented) hands work between its threads with atomics ThreadSanitizer does
// not see, so every task would look like a race with the thread that started it. With one TBB
// thread each std::thread and pager thread runs its own loops: the races looked for here are
// between those threads, in osgBTF and osgDB.
const tbb::global_control oneTbbThread(tbb::global_control::max_allowed_parallelism, 1);
#endif

/** A sample zip, its lambert fit (.btfmat) and its fmf fit written as a UBO2014 .btf, made once
 *  for all tests of this process. */
struct Files {
    TempDir dir;
    std::string zip, btfmat, btf, cache;
    Files() {
        zip = dir.file("sample.zip");
        btfmat = dir.file("sample.btfmat");
        btf = dir.file("sample.btf");
        cache = dir.file("cache");
        // In this process, not with the btf tool: the ThreadSanitizer build builds no tool.
        const MeasuredBtf sample = smallSampleBtf();
        writeUbo2003Zip(sample, zip, Ubo2003ImageFormat::Png);
        saveMaterial(*findMethod("lambert").fit(sample, {}), btfmat);
        const osg::ref_ptr<Material> fmf = findMethod("fmf").fit(sample, {});
        writeFactorsAsUbo2014(dynamic_cast<const FmfMaterial&>(*fmf).completeFactors(), btf, 2);
    }
    std::vector<std::string> all() const { return {btfmat, zip, btf}; }
    /** The option string each file is read with: the zip fitted (lambert) into a fresh cache. */
    osg::ref_ptr<osgDB::Options> options() const {
        return new osgDB::Options("method=lambert cache=" + cache);
    }
};

const Files& files() {
    static const Files f;
    return f;
}

/** The cache holds one complete entry per measured file (the zip and the .btf, both fitted with
 *  lambert) and no temporaries. */
void expectCompleteCacheEntries(const std::string& cache) {
    std::vector<std::string> names;
    for (const auto& e : fs::directory_iterator(cache)) names.push_back(e.path().string());
    ASSERT_EQ(names.size(), 2u);
    for (const std::string& name : names) {
        EXPECT_EQ(fs::path(name).extension(), ".btfmat");
        EXPECT_EQ(errorOf([&] { loadMaterial(name); }), "no error");
    }
}

/** Files "f/<n>" whose first two fetches fail transiently (a server restarting), counted. */
class FlakySource : public TileSource {
public:
    FetchResult fetch(const std::string& path) override {
        std::lock_guard<std::mutex> lock(_mutex);
        FetchResult result;
        if (++_fetches[path] <= 2) {
            result.error = path + ": connection refused";
            result.transient = true;
        } else {
            result.ok = true;
            result.data.assign(path.begin(), path.end());
        }
        return result;
    }
    std::string describe(const std::string& path) const override { return path; }
    std::map<std::string, int> fetches() const {
        std::lock_guard<std::mutex> lock(_mutex);
        return _fetches;
    }

private:
    mutable std::mutex _mutex;
    std::map<std::string, int> _fetches;
};

}  // namespace

#if defined(__SANITIZE_THREAD__)
// tests/CMakeLists.txt runs these with a libtbb that has no libtbbmalloc beside it: TBB's own
// allocator recycles memory between threads where ThreadSanitizer cannot see it.
TEST(Concurrency, OneTbbAllocatesThroughMallocUnderThreadSanitizer) {
    std::atomic<int> sum{0};
    tbb::parallel_for(0, 64, [&](int i) { sum += i; });  // TBB picks its allocator on first use
    EXPECT_EQ(sum.load(), 64 * 63 / 2);
    EXPECT_EQ(dlopen("libtbbmalloc.so.2", RTLD_LAZY | RTLD_NOLOAD), nullptr)
        << "libtbbmalloc is loaded: run this binary through ctest, which puts "
           "<build>/tbb-without-tbbmalloc first in LD_LIBRARY_PATH";
}
#endif

TEST(Concurrency, ThreadsReadTheSameFilesThroughOsgDB) {
    const Files& f = files();
    usePluginsFromBuild();
    fs::remove_all(f.cache);
    constexpr int kThreads = 6, kRounds = 2;
    const osg::ref_ptr<osgDB::Options> options = f.options();
    std::atomic<int> nodes{0};
    std::vector<std::string> problems(kThreads);
    const std::vector<std::string> all = f.all();
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back([&, t] {
            for (int round = 0; round < kRounds; ++round)
                for (std::size_t i = 0; i < all.size(); ++i) {
                    // Each thread starts at another file, so every pair of files overlaps.
                    const std::string& file = all[(i + std::size_t(t)) % all.size()];
                    osg::ref_ptr<osg::Node> node = osgDB::readRefNodeFile(file, options.get());
                    auto* material = dynamic_cast<MaterialNode*>(node.get());
                    if (material && material->getMaterial())
                        ++nodes;
                    else
                        problems[std::size_t(t)] += " " + file;
                }
        });
    for (std::thread& t : threads) t.join();
    EXPECT_EQ(nodes.load(), kThreads * kRounds * 3);
    for (const std::string& p : problems) EXPECT_EQ(p, "") << "not read as a MaterialNode";
    expectCompleteCacheEntries(f.cache);
}

// the last holder of a shared material drops it on one thread while another thread
// replaces the material's cache entry (the file changed, so it is read again). The two threads
// are ordered only by a relaxed atomic, which gives ThreadSanitizer no happens-before edge, so
// every access the cache makes to the old material must be one it can order by itself. With an
// osg::observer_ptr in the cache it was not: dropping the entry decremented the material's
// ObserverSet here (inline, instrumented) while ~Referenced, inside uninstrumented libosg,
// decremented and freed it there: a report in every run of this test under TSan.
TEST(Concurrency, LastHolderDropsASharedMaterialWhileAnotherThreadReplacesItsEntry) {
    TempDir dir;
    const std::string file = dir.file("changing.btfmat");
    fs::copy_file(files().btfmat, file);
    osg::ref_ptr<Material> first = loadSharedMaterial(file);
    const Material* const firstAddress = first.get();
    fs::last_write_time(file, fs::last_write_time(file) + std::chrono::seconds(2));
    std::atomic<bool> replaced{false};
    osg::ref_ptr<Material> second;
    std::thread replacer([&] {
        second = loadSharedMaterial(file);
        replaced.store(true, std::memory_order_relaxed);
    });
    std::thread dropper([&] {
        while (!replaced.load(std::memory_order_relaxed)) std::this_thread::yield();
        first = nullptr;
    });
    replacer.join();
    dropper.join();
    ASSERT_NE(second, nullptr);
    EXPECT_NE(second.get(), firstAddress) << "the changed file was not read again";
}

// Threads opening one file at once (DatabasePager threads loading tiles that name the same
// material) get one Material: one copy of its textures, not one per thread.
TEST(Concurrency, ThreadsOpeningOneFileAtOnceShareOneMaterial) {
    TempDir dir;
    const std::string file = dir.file("once.btfmat");
    fs::copy_file(files().btfmat, file);
    constexpr int kThreads = 6;
    std::vector<osg::ref_ptr<Material>> opened(kThreads);
    std::atomic<int> ready{0};
    std::vector<std::thread> threads;
    for (int t = 0; t < kThreads; ++t)
        threads.emplace_back([&, t] {
            ++ready;
            while (ready.load() < kThreads) std::this_thread::yield();
            opened[std::size_t(t)] = loadSharedMaterial(file);
        });
    for (std::thread& t : threads) t.join();
    for (const auto& material : opened) {
        ASSERT_NE(material, nullptr);
        EXPECT_EQ(material.get(), opened[0].get());
    }
}

TEST(Concurrency, DatabasePagerThreadsLoadProxyNodesNamingTheSameFiles) {
    const Files& f = files();
    usePluginsFromBuild();
    fs::remove_all(f.cache);
    osg::ref_ptr<osgDB::DatabasePager> pager = new osgDB::DatabasePager;
    pager->setUpThreads(5, 1);      // four threads read local files
    pager->setDoPreCompile(false);  // no GL context here
    pager->setAcceptNewDatabaseRequests(true);
    pager->setDatabasePagerThreadPause(false);

    constexpr int kCopies = 4;  // proxies per file
    osg::ref_ptr<osg::Group> root = new osg::Group;
    std::vector<osg::ref_ptr<osg::ProxyNode>> proxies;
    for (int copy = 0; copy < kCopies; ++copy)
        for (const std::string& file : f.all()) {
            osg::ref_ptr<osg::ProxyNode> proxy = new osg::ProxyNode;
            proxy->setFileName(0, file);
            proxy->setDatabaseOptions(f.options());
            root->addChild(proxy.get());
            proxies.push_back(proxy);
        }

    // What a viewer's cull and update traversals do each frame: request what is missing (the
    // requests stay current only while asked for every frame), then merge what was loaded.
    osg::ref_ptr<osg::FrameStamp> stamp = new osg::FrameStamp;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(60);
    std::size_t loaded = 0;
    for (unsigned frame = 0; loaded < proxies.size(); ++frame) {
        ASSERT_LT(std::chrono::steady_clock::now(), deadline) << loaded << " proxies loaded";
        stamp->setFrameNumber(frame);
        pager->signalBeginFrame(stamp.get());
        for (osg::ref_ptr<osg::ProxyNode>& proxy : proxies) {
            if (proxy->getNumChildren() > 0) continue;
            osg::NodePath path{root.get(), proxy.get()};
            pager->requestNodeFile(proxy->getFileName(0), path, 1.0f, stamp.get(),
                                   proxy->getDatabaseRequest(0), proxy->getDatabaseOptions());
        }
        pager->signalEndFrame();
        pager->updateSceneGraph(*stamp);
        loaded = 0;
        for (const auto& proxy : proxies) loaded += proxy->getNumChildren() > 0 ? 1 : 0;
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    // One thread at a time. DatabaseThread::cancel() joins its thread only if it still runs when
    // it looks, and DatabasePager::cancel() first tells every thread to stop: a thread that ends
    // before its turn is never joined (a leak to ThreadSanitizer), and joining the threads again
    // afterwards joins the others twice (a crash under clang's ASan). A thread not yet told to
    // stop is still running, so this way each is joined exactly once.
    for (unsigned i = 0; i < pager->getNumDatabaseThreads(); ++i)
        pager->getDatabaseThread(i)->cancel();
    pager->cancel();
    for (const auto& proxy : proxies) {
        const auto* node = dynamic_cast<const MaterialNode*>(proxy->getChild(0));
        ASSERT_NE(node, nullptr) << proxy->getFileName(0);
        EXPECT_NE(node->getMaterial(), nullptr) << proxy->getFileName(0);
    }
    expectCompleteCacheEntries(f.cache);
}

// Three workers fetch and retry while two threads request the same keys with changing
// priorities: every file is delivered once, after exactly its two transient failures.
TEST(Concurrency, FetcherRetriesWhileThreadsRequestTheSameKeys) {
    constexpr int kKeys = 200;
    const auto source = std::make_shared<FlakySource>();
    TileFetcherOptions options;
    options.threads = 3;
    options.retryDelay = std::chrono::milliseconds(1);
    TileFetcher fetcher(source, options);
    std::vector<std::thread> requesters;
    for (int t = 0; t < 2; ++t)
        requesters.emplace_back([&fetcher, t] {
            for (int round = 0; round < 3; ++round)
                for (int i = 0; i < kKeys; ++i)
                    fetcher.request(std::uint64_t(i), "f/" + std::to_string(i),
                                    double((i * (t + 1) + round) % 17));
        });
    for (std::thread& thread : requesters) thread.join();
    ASSERT_TRUE(fetcher.waitIdle(std::chrono::seconds(60)));
    std::vector<bool> seen(kKeys, false);
    for (const FetchedItem& item : fetcher.takeCompleted()) {
        ASSERT_LT(item.key, std::uint64_t(kKeys));
        EXPECT_FALSE(seen[item.key]) << item.key;
        seen[item.key] = true;
        EXPECT_TRUE(item.result.ok) << item.result.error;
        EXPECT_EQ(std::string(item.result.data.begin(), item.result.data.end()), item.path);
    }
    EXPECT_EQ(std::count(seen.begin(), seen.end(), true), kKeys);
    const std::map<std::string, int> fetches = source->fetches();
    EXPECT_EQ(fetches.size(), std::size_t(kKeys));
    for (const auto& [path, count] : fetches) EXPECT_EQ(count, 3) << path;
    EXPECT_EQ(fetcher.retries(), std::uint64_t(2 * kKeys));
}

}  // namespace OSGBTF_TEST_FILE
