// The fit cache as an application uses it (fit/FitCache.h, libosgBTFFit), without osgDB: the
// plugins' tests (scene_plugin_test.cpp) cover the same cache through the readers.
#include <chrono>
#include <cstdlib>
#include <filesystem>
#include <optional>
#include <string>
#include <vector>

#include <gtest/gtest.h>

#include "fit/FitCache.h"
#include "harness/sample/SampleBtf.h"
#include "harness/sample/Ubo2003Writer.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

namespace fs = std::filesystem;
using namespace osgBTF;
using osgBTF::test::TempDir;

namespace {

std::string writeSample(const TempDir& dir) {
    SampleOptions options;
    options.width = options.height = 4;
    const std::string zip = dir.file("s.zip");
    writeUbo2003Zip(makeSampleBtf(options), zip);
    return zip;
}

std::vector<std::string> filesIn(const std::string& folder) {
    std::vector<std::string> names;
    std::error_code error;
    for (const auto& entry : fs::directory_iterator(folder, error))
        names.push_back(entry.path().filename().string());
    return names;
}

/** Sets (or with nullopt unsets) an environment variable for one scope. */
class ScopedEnv {
public:
    ScopedEnv(const char* name, std::optional<std::string> value) : _name(name) {
        if (const char* old = std::getenv(name)) _old = old;
        if (value)
            setenv(name, value->c_str(), 1);
        else
            unsetenv(name);
    }
    ~ScopedEnv() {
        if (_old)
            setenv(_name, _old->c_str(), 1);
        else
            unsetenv(_name);
    }

private:
    const char* _name;
    std::optional<std::string> _old;
};

}  // namespace

TEST(FitCache, FitsOnceThenReadsTheCachedFile) {
    TempDir dir;
    const std::string zip = writeSample(dir), cache = dir.file("cache");
    const MethodInfo& lambert = baselineMethod();

    const osg::ref_ptr<Material> fitted = fitCached(zip, lambert, FitOptions(), cache);
    const std::vector<std::string> files = filesIn(cache);
    ASSERT_EQ(files.size(), 1u);
    // <input name>-<method>-<16 hex digits>.btfmat
    const std::string prefix = "s.zip-" + lambert.name + "-";
    ASSERT_EQ(files[0].size(), prefix.size() + 16 + 7) << files[0];
    EXPECT_EQ(files[0].rfind(prefix, 0), 0u) << files[0];
    EXPECT_EQ(files[0].find_first_not_of("0123456789abcdef", prefix.size()), prefix.size() + 16);
    EXPECT_EQ(files[0].substr(prefix.size() + 16), ".btfmat");
    const std::string entry = (fs::path(cache) / files[0]).string();
    EXPECT_EQ(fitted->sourceFile, entry);
    EXPECT_EQ(fitted->fitInfo.at("cacheKey"), fitCacheKey(zip, lambert.name, FitOptions()));
    const auto writtenAt = fs::last_write_time(entry);

    const osg::ref_ptr<Material> cached = fitCached(zip, lambert, FitOptions(), cache);
    EXPECT_EQ(cached->sourceFile, entry);
    EXPECT_EQ(fs::last_write_time(entry), writtenAt);  // read, not written again
    EXPECT_EQ(filesIn(cache).size(), 1u);
    const glm::vec3 view(0, 0, 1), light(0.3f, 0.2f, 0.93f);
    EXPECT_EQ(cached->evaluate(1, 2, view, light), fitted->evaluate(1, 2, view, light));

    // Another method or other options are another entry.
    const MethodInfo& other = pluginDefaultMethod();
    fitCached(zip, other, FitOptions::parse(other.quickFitOptions), cache);
    EXPECT_EQ(filesIn(cache).size(), 2u);
}

TEST(FitCache, KeyNamesWhatTheFitDependsOn) {
    TempDir dir;
    const std::string zip = writeSample(dir);
    const std::string key = fitCacheKey(zip, "m", FitOptions::parse("a=1 b=two"), true);
    EXPECT_NE(key.find(fs::absolute(zip).lexically_normal().string()), std::string::npos) << key;
    EXPECT_NE(key.find("|" + std::to_string(fs::file_size(zip)) + "|"), std::string::npos) << key;
    EXPECT_NE(key.find("|m|mipmap|a=1|b=two"), std::string::npos) << key;
    EXPECT_NE(key, fitCacheKey(zip, "m", FitOptions::parse("a=1 b=two"), false));
    EXPECT_NE(key, fitCacheKey(zip, "m", FitOptions::parse("a=2 b=two"), true));
    fs::last_write_time(zip, fs::last_write_time(zip) + std::chrono::seconds(5));
    EXPECT_NE(key, fitCacheKey(zip, "m", FitOptions::parse("a=1 b=two"), true));
}

TEST(FitCache, DamagedEntryIsFittedAgainAndNoFolderFitsEveryTime) {
    TempDir dir;
    const std::string zip = writeSample(dir), cache = dir.file("cache");
    const MethodInfo& lambert = baselineMethod();
    fitCached(zip, lambert, FitOptions(), cache);
    const std::string entry = (fs::path(cache) / filesIn(cache).at(0)).string();
    test::writeTextFile(entry, "not a fitted material");
    const osg::ref_ptr<Material> refitted = fitCached(zip, lambert, FitOptions(), cache);
    EXPECT_EQ(refitted->sourceFile, entry);
    EXPECT_NE(test::readTextFile(entry), "not a fitted material");
    EXPECT_EQ(loadMaterial(entry)->fitInfo.at("cacheKey"), refitted->fitInfo.at("cacheKey"));

    const osg::ref_ptr<Material> uncached = fitCached(zip, lambert, FitOptions(), "");
    EXPECT_TRUE(uncached->sourceFile.empty());
    EXPECT_EQ(filesIn(cache).size(), 1u);
}

TEST(FitCache, DefaultFolderFollowsTheEnvironment) {
    const ScopedEnv cacheDir("OSGBTF_CACHE_DIR", "/tmp/a");
    const ScopedEnv xdg("XDG_CACHE_HOME", "/tmp/x");
    const ScopedEnv home("HOME", "/tmp/h");
    EXPECT_EQ(defaultFitCacheFolder(), "/tmp/a");
    {
        const ScopedEnv none("OSGBTF_CACHE_DIR", std::nullopt);
        EXPECT_EQ(defaultFitCacheFolder(), "/tmp/x/osgbtf");
        const ScopedEnv noXdg("XDG_CACHE_HOME", std::nullopt);
        EXPECT_EQ(defaultFitCacheFolder(), "/tmp/h/.cache/osgbtf");
        const ScopedEnv noHome("HOME", std::nullopt);
        EXPECT_EQ(defaultFitCacheFolder(), "");
    }
}

}  // namespace OSGBTF_TEST_FILE
