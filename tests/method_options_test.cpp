// Declarative fit options (materials/MethodOptions.h): one validation, one message format for
// every method, typed values with the table's defaults, and documentation generated from (or
// checked against) the tables: btf fit --help and each method README's option table.
#include <filesystem>
#include <fstream>
#include <sstream>

#include <gtest/gtest.h>

#include "core/Error.h"
#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;

namespace {

std::string validationError(const std::string& method, const std::string& options) {
    return errorOf([&] { validateOptions(method, FitOptions::parse(options)); });
}

}  // namespace

TEST(MethodOptions, EveryKindOfMistakeHasTheOneFormat) {
    // Integer out of range, not an integer, unknown name, enum, bool, real number, no options.
    EXPECT_EQ(validationError("laf", "lobes=9"),
              "laf: option lobes must be an integer in 1..8, got 9");
    EXPECT_EQ(validationError("laf", "lobes=2.5"),
              "laf: option lobes must be an integer in 1..8, got 2.5");
    EXPECT_EQ(validationError("laf", "lobes="),
              "laf: option lobes must be an integer in 1..8, got ");
    EXPECT_EQ(validationError("laf", "clusters=4"),
              "laf: option clusters is unknown (known: lobes, iterations, cosine)");
    EXPECT_EQ(validationError("laf", "cosine=yes"), "laf: option cosine must be 0 or 1, got yes");
    EXPECT_EQ(validationError("pca", "storage=int"),
              "pca: option storage must be one of unorm8, half, float, got int");
    EXPECT_EQ(validationError("rf", "max-exponent=300"),
              "rf: option max-exponent must be a number in 1..256, got 300");
    EXPECT_EQ(validationError("rf", "max-exponent=1e400"),
              "rf: option max-exponent must be a number in 1..256, got 1e400");
    EXPECT_EQ(validationError("lpca", "training=-5"),
              "lpca: option training must be an integer >= 0, got -5");
    EXPECT_EQ(validationError("lambert", "lobes=2"),
              "lambert: option lobes is unknown (known: none)");
    EXPECT_EQ(validationError("nope", ""), errorOf([] { findMethod("nope"); }));
}

TEST(MethodOptions, LambertRejectsWhatItCannotUse) {
    SampleOptions sample;
    sample.width = sample.height = 2;
    EXPECT_EQ(errorOf([&] {
                  findMethod("lambert").fit(makeSampleBtf(sample), FitOptions::parse("lobes=2"));
              }),
              "lambert: option lobes is unknown (known: none)");
}

TEST(MethodOptions, ValuesAreTypedWithTheTablesDefaults) {
    const OptionValues laf = validateOptions("laf", FitOptions::parse("lobes=3"));
    EXPECT_EQ(laf.integer("lobes"), 3);
    EXPECT_TRUE(laf.given("lobes"));
    EXPECT_EQ(laf.integer("iterations"), 50);
    EXPECT_FALSE(laf.given("iterations"));
    EXPECT_TRUE(laf.flag("cosine"));
    EXPECT_FALSE(validateOptions("laf", FitOptions::parse("cosine=0")).flag("cosine"));
    const OptionValues rf = validateOptions("rf", {});
    EXPECT_EQ(rf.integer("lobes"), 2);
    EXPECT_EQ(rf.integer("iterations"), 20);
    EXPECT_EQ(rf.integer("starts"), 2);
    EXPECT_EQ(rf.number("max-exponent"), 64.0);
    const OptionValues pca = validateOptions("pca", {});
    EXPECT_EQ(pca.integer("components"), 16);
    EXPECT_EQ(pca.choice("storage"), "unorm8");
    const OptionValues lpca = validateOptions("lpca", {});
    EXPECT_EQ(lpca.integer("clusters"), 32);
    EXPECT_EQ(lpca.integer("components"), 8);
    EXPECT_EQ(lpca.integer("iterations"), 20);
    EXPECT_EQ(lpca.integer("training"), 4096);
    EXPECT_EQ(lpca.integer("seed"), 1);
    const OptionValues revised = validateOptions("lpca-revised", {});
    EXPECT_EQ(revised.integer("resolution"), 16);
    EXPECT_EQ(revised.choice("storage"), "half");
    const OptionValues slaf = validateOptions("slaf", {});
    EXPECT_EQ(slaf.integer("rounds"), 2);
    // Reading an option the table does not declare, or with another type, is a program bug.
    EXPECT_THROW(laf.integer("clusters"), std::logic_error);
    EXPECT_THROW(laf.number("lobes"), std::logic_error);
}

TEST(MethodOptions, FitHelpListsEveryMethodAndOptionFromTheTables) {
    const std::string help = methodsHelp();
    for (const std::string& name : methodNames()) {
        const MethodInfo& info = findMethod(name);
        EXPECT_NE(help.find("\n  " + name + ": " + info.description), std::string::npos) << name;
        for (const OptionSpec& option : info.options)
            EXPECT_NE(help.find("\n      " + option.name + "=  " + optionHelp(option)),
                      std::string::npos)
                << name << " " << option.name;
    }
    EXPECT_NE(help.find("lobes=  number of Lafortune lobes (integer in 1..8, default 2)"),
              std::string::npos)
        << help;
    EXPECT_NE(help.find("\n  lambert: plain lit texture: rho(x) * cos(theta_l), the baseline\n"
                        "      (no options)"),
              std::string::npos)
        << help;
}

// Every method folder's README holds the option table generated from the method's schema, under
// "## Options": changing an option without its README (or the other way round) fails here.
TEST(MethodOptions, EachReadmeOptionTableMatchesTheSchema) {
    const std::filesystem::path materials = std::filesystem::path(sourceDir()) / "materials";
    int checked = 0;
    const std::vector<std::string> names = methodNames();
    for (const auto& entry : std::filesystem::directory_iterator(materials)) {
        if (!entry.is_directory()) continue;
        const std::string method = entry.path().filename().string();
        SCOPED_TRACE(method);
        ASSERT_NE(std::find(names.begin(), names.end(), method), names.end())
            << "materials/" << method << "/ is not a registered method";
        const std::string readme = readTextFile((entry.path() / "README.md").string());
        const auto section = readme.find("\n## Options\n");
        ASSERT_NE(section, std::string::npos) << "no '## Options' section";
        const std::string table = optionTableMarkdown(findMethod(method));
        const auto at = readme.find(table, section);
        EXPECT_NE(at, std::string::npos) << "expected this table under ## Options:\n" << table;
        ++checked;
    }
    EXPECT_GE(checked, 7);
}

}  // namespace OSGBTF_TEST_FILE
