// A method owns all of itself: its name appears as a string literal only in its own
// folder materials/<name>/, its shaders live there too, and what the rest of the library needs of
// it (environment lighting, its roles) comes from its MethodInfo. The scanner is checked on a fake
// tree first, so that a clean result on the real one means something.
#include <algorithm>
#include <cctype>
#include <filesystem>
#include <fstream>
#include <regex>
#include <sstream>

#include <gtest/gtest.h>

#include "core/Error.h"
#include "core/ShaderSource.h"
#include "harness/sample/SampleBtf.h"
#include "materials/EnvironmentState.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using namespace osgBTF::test;
namespace fs = std::filesystem;

namespace {

struct Literal {
    int line;
    std::string text;  ///< the characters between the quotes, escapes as written
};

/** The string literals of C++ source text, comments skipped; raw strings and character literals
 *  are read as such, so that a quote inside them does not start a literal. */
std::vector<Literal> stringLiterals(const std::string& text) {
    std::vector<Literal> literals;
    int line = 1;
    const std::size_t n = text.size();
    auto isWord = [](char c) { return std::isalnum(static_cast<unsigned char>(c)) || c == '_'; };
    for (std::size_t i = 0; i < n; ++i) {
        const char c = text[i];
        if (c == '\n') {
            ++line;
        } else if (c == '/' && i + 1 < n && text[i + 1] == '/') {
            while (i < n && text[i] != '\n') ++i;
            --i;  // the newline counts the line
        } else if (c == '/' && i + 1 < n && text[i + 1] == '*') {
            const std::size_t end = text.find("*/", i + 2);
            const std::size_t stop = end == std::string::npos ? n : end + 2;
            line += int(std::count(text.begin() + long(i), text.begin() + long(stop), '\n'));
            i = stop - 1;
        } else if (c == '"' && i > 0 && text[i - 1] == 'R' &&
                   (i < 2 || !isWord(text[i - 2]) || text[i - 2] == '8' || text[i - 2] == 'u' ||
                    text[i - 2] == 'U' || text[i - 2] == 'L')) {
            const std::size_t open = text.find('(', i);
            if (open == std::string::npos) break;
            const std::string close = ")" + text.substr(i + 1, open - i - 1) + "\"";
            const std::size_t end = text.find(close, open);
            const std::size_t stop = end == std::string::npos ? n : end + close.size();
            const int startLine = line;
            line += int(std::count(text.begin() + long(i), text.begin() + long(stop), '\n'));
            if (end != std::string::npos)
                literals.push_back({startLine, text.substr(open + 1, end - open - 1)});
            i = stop - 1;
        } else if (c == '"') {
            std::size_t j = i + 1;
            while (j < n && text[j] != '"' && text[j] != '\n') j += text[j] == '\\' ? 2 : 1;
            literals.push_back({line, text.substr(i + 1, std::min(j, n) - i - 1)});
            i = std::min(j, n - 1);
        } else if (c == '\'' && (i == 0 || !isWord(text[i - 1]))) {
            // A character literal; after a digit or letter it is a digit separator (1'000).
            std::size_t j = i + 1;
            while (j < n && text[j] != '\'' && text[j] != '\n') j += text[j] == '\\' ? 2 : 1;
            i = std::min(j, n - 1);
        }
    }
    return literals;
}

/** Every "<method name>" literal in the .cpp and .h files under root/<folder> for each folder,
 *  except a method's own name in its folder materials/<name>/ and anything in a method's tests
 *  (materials/<name>/test/: the tests layer, which names methods freely as tests/ does):
 *  "path:line: "name"" (path relative to root), sorted. */
std::vector<std::string> misplacedMethodNames(const fs::path& root,
                                              const std::vector<std::string>& folders,
                                              const std::vector<std::string>& names) {
    std::vector<std::string> found;
    for (const std::string& folder : folders) {
        if (!fs::is_directory(root / folder)) continue;
        for (const auto& entry : fs::recursive_directory_iterator(root / folder)) {
            const std::string extension = entry.path().extension().string();
            if (!entry.is_regular_file() || (extension != ".cpp" && extension != ".h")) continue;
            const fs::path relative = entry.path().lexically_relative(root);
            std::string owner;  // the method whose folder holds the file, if any
            auto part = relative.begin();
            if (part != relative.end() && *part == "materials" && ++part != relative.end() &&
                std::next(part) != relative.end()) {
                owner = part->string();
                if (*std::next(part) == "test") continue;
            }
            for (const Literal& literal : stringLiterals(readTextFile(entry.path().string())))
                if (literal.text != owner &&
                    std::find(names.begin(), names.end(), literal.text) != names.end())
                    found.push_back(relative.generic_string() + ":" + std::to_string(literal.line) +
                                    ": \"" + literal.text + "\"");
        }
    }
    std::sort(found.begin(), found.end());
    return found;
}

/** The methods built into the library (not those a test binary defines, with their shader). */
std::vector<std::string> builtInMethods() {
    std::vector<std::string> names;
    for (const std::string& name : methodNames())
        if (findMethod(name).fragmentShader.empty()) names.push_back(name);
    return names;
}

const std::vector<std::string> kSourceFolders = {"core",      "loaders",   "materials", "scene",
                                                 "streaming", "synthesis", "harness",   "plugins",
                                                 "tools",     "examples"};

}  // namespace

TEST(MethodNames, ScannerFindsPlantedLiteralsInAFakeTree) {
    TempDir dir;
    const std::vector<std::string> names = {"pca", "fmf", "lpca", "lpca-revised", "rf"};
    fs::create_directories(dir.path() / "materials" / "pca");
    fs::create_directories(dir.path() / "materials" / "lpca");
    fs::create_directories(dir.path() / "core" / "deep");
    fs::create_directories(dir.path() / "unscanned");
    // A method's own name in its folder is fine, another's is not.
    writeTextFile(dir.file("materials/pca/Pca.cpp"),
                  "std::string name() { return \"pca\"; }\nauto other = \"fmf\";\n");
    // Comments, longer strings and raw strings do not count; a quote in a character literal
    // starts no string.
    writeTextFile(dir.file("core/a.cpp"),
                  "// \"pca\" in a comment\n"
                  "/* \"lpca\"\n   \"fmf\" */ int x = 1'000;\n"
                  "const char q = '\"'; auto s = \"fmf\";\n"
                  "auto raw = R\"x(\"rf\" )\" \"pca\")x\";\n"
                  "auto longer = \"pca fmf\", escaped = \"\\\"pca\";\n"
                  "auto planted = \"lpca-revised\";\n");
    writeTextFile(dir.file("core/deep/b.h"), "#pragma once\nconstexpr auto m = \"rf\";\n");
    // The registry (materials/Material.cpp) is not a method folder.
    writeTextFile(dir.file("materials/Material.cpp"), "auto baseline = \"lpca\";\n");
    writeTextFile(dir.file("materials/lpca/notes.txt"), "\"pca\"\n");
    // A method's tests are the tests layer's.
    fs::create_directories(dir.path() / "materials" / "pca" / "test");
    writeTextFile(dir.file("materials/pca/test/pca_test.cpp"), "auto baseline = \"lpca\";\n");
    writeTextFile(dir.file("unscanned/c.cpp"), "auto m = \"pca\";\n");
    EXPECT_EQ(
        misplacedMethodNames(dir.path(), kSourceFolders, names),
        (std::vector<std::string>{"core/a.cpp:4: \"fmf\"", "core/a.cpp:7: \"lpca-revised\"",
                                  "core/deep/b.h:2: \"rf\"", "materials/Material.cpp:1: \"lpca\"",
                                  "materials/pca/Pca.cpp:2: \"fmf\""}));
}

TEST(MethodNames, NoMethodNameLiteralOutsideItsFolder) {
    // A name needed elsewhere is a constant in the method's header (kFmfMethodName) or a
    // MethodInfo field (baseline, pluginDefault, factors, environment).
    const std::vector<std::string> found =
        misplacedMethodNames(fs::path(sourceDir()), kSourceFolders, builtInMethods());
    std::string list;
    for (const std::string& f : found) list += "\n  " + f;
    EXPECT_TRUE(found.empty()) << "method names outside their folders:" << list;
}

namespace {

/** `text` with comments and the contents of string and character literals blanked (lines kept). */
std::string codeOnly(const std::string& text) {
    std::string code = text;
    const std::size_t n = text.size();
    auto blank = [&](std::size_t from, std::size_t to) {
        for (std::size_t k = from; k < std::min(to, n); ++k)
            if (code[k] != '\n') code[k] = ' ';
    };
    for (std::size_t i = 0; i < n; ++i) {
        if (text.compare(i, 2, "//") == 0) {
            const std::size_t end = text.find('\n', i);
            blank(i, end == std::string::npos ? n : end);
            i = end == std::string::npos ? n : end;
        } else if (text.compare(i, 2, "/*") == 0) {
            const std::size_t end = text.find("*/", i + 2);
            const std::size_t stop = end == std::string::npos ? n : end + 2;
            blank(i, stop);
            i = stop - 1;
        } else if (text[i] == '"') {
            std::size_t j = i + 1;
            while (j < n && text[j] != '"' && text[j] != '\n') j += text[j] == '\\' ? 2 : 1;
            blank(i + 1, j);
            i = std::min(j, n - 1);
        }
    }
    return code;
}

/** "path:line: Class" for every use of a built-in method's class (its osg::Object className)
 *  in the .cpp and .h files under `folders`, outside the method folders. */
std::vector<std::string> misplacedMethodClasses(const fs::path& root,
                                                const std::vector<std::string>& folders) {
    std::vector<std::string> classes;
    for (const std::string& name : builtInMethods()) {
        osg::ref_ptr<osg::Object> instance = findMethod(name).createInstance();
        classes.push_back(instance->className());
    }
    std::vector<std::string> found;
    for (const std::string& folder : folders) {
        for (const auto& entry : fs::recursive_directory_iterator(root / folder)) {
            const std::string extension = entry.path().extension().string();
            if (!entry.is_regular_file() || (extension != ".cpp" && extension != ".h")) continue;
            const std::string relative = entry.path().lexically_relative(root).generic_string();
            // A method may build on another's (lpca-revised resamples an lpca model).
            if (relative.rfind("materials/", 0) == 0 &&
                std::count(relative.begin(), relative.end(), '/') > 1)
                continue;
            const std::string code = codeOnly(readTextFile(entry.path().string()));
            for (const std::string& name : classes) {
                const std::regex word("\\b" + name + "\\b");
                for (auto it = std::sregex_iterator(code.begin(), code.end(), word);
                     it != std::sregex_iterator(); ++it) {
                    const auto line =
                        1 + std::count(code.begin(), code.begin() + it->position(), '\n');
                    found.push_back(relative + ":" + std::to_string(line) + ": " + name);
                }
            }
        }
    }
    std::sort(found.begin(), found.end());
    return found;
}

}  // namespace

// What the tools, the plugins, the scene graph and the harness need of a method comes from its
// MethodInfo, not from its class. streaming/ is the one exception, by design: BSVTF (Schwartz et
// al. 2013) streams the Eigen-Textures of the fmf material and is built on its class.
TEST(MethodNames, NoMethodClassOutsideItsFolder) {
    std::vector<std::string> folders;
    for (const std::string& folder : kSourceFolders)
        if (folder != "streaming") folders.push_back(folder);
    const std::vector<std::string> found = misplacedMethodClasses(fs::path(sourceDir()), folders);
    std::string list;
    for (const std::string& f : found) list += "\n  " + f;
    EXPECT_TRUE(found.empty()) << "method classes outside their folders:" << list;
}

TEST(MethodNames, RolesComeFromTheMethods) {
    EXPECT_EQ(baselineMethod().name, "lambert");
    EXPECT_EQ(pluginDefaultMethod().name, "lpca");
    std::vector<std::string> ubo2014, folding;
    for (const std::string& name : methodNames()) {
        if (findMethod(name).factors) ubo2014.push_back(name);
        if (hasFoldedEnvironment(name)) folding.push_back(name);
    }
    EXPECT_EQ(ubo2014, std::vector<std::string>{"fmf"});
    EXPECT_EQ(factorMethod().name, "fmf");
    // "dummy": the test-only method of tests/DummyMethod.cpp, registered in this program, folds
    // its environment lighting through its own hooks like the built-in three.
    EXPECT_EQ(folding, (std::vector<std::string>{"dummy", "fmf", "lpca", "pca"}));
    EXPECT_EQ(findMethodIfRegistered("martian"), nullptr);
}

TEST(EnvironmentHooks, MethodsWithoutThemHaveNoFoldedLighting) {
    EXPECT_FALSE(hasFoldedEnvironment("martian"));
    SampleOptions options;
    options.width = options.height = 2;
    const osg::ref_ptr<Material> lambert =
        findMethod("lambert").fit(makeSampleBtf(options), FitOptions());
    const std::string message = "environment: method 'lambert' has no folded environment lighting";
    EXPECT_FALSE(foldsEnvironment(*lambert));
    EXPECT_EQ(errorOf([&] { foldEnvironment(*lambert, std::vector<glm::vec3>(81)); }), message);
    EXPECT_EQ(errorOf([&] { evaluateFolded(*lambert, {}, 0, 0, glm::vec3(0, 0, 1)); }), message);
    EXPECT_EQ(errorOf([&] { foldedStride(*lambert); }), message);
    EXPECT_EQ(errorOf([&] { environmentProgram("lambert"); }), message);
    EXPECT_EQ(errorOf([&] { environmentStateSet(*lambert, {}); }), message);
}

TEST(MethodShaders, EmbeddedFromTheMethodFolders) {
    // Each built-in method's shaders are materials/<m>/<m>.frag and <m>_environment.frag, embedded
    // under the names the programs ask for; shaders/ keeps only what no one method owns.
    const std::vector<std::string> embedded = embeddedShaderNames();
    const fs::path source(sourceDir());
    auto has = [&](const std::string& name) {
        return std::find(embedded.begin(), embedded.end(), name) != embedded.end();
    };
    for (const std::string& name : builtInMethods()) {
        SCOPED_TRACE(name);
        EXPECT_TRUE(fs::exists(source / "materials" / name / (name + ".frag")));
        EXPECT_TRUE(has(name + ".frag"));
        EXPECT_FALSE(fs::exists(source / "shaders" / (name + ".frag")));
        const bool environment = hasFoldedEnvironment(name);
        EXPECT_EQ(fs::exists(source / "materials" / name / (name + "_environment.frag")),
                  environment);
        EXPECT_EQ(has("environment/" + name + ".frag"), environment);
        if (environment) {
            EXPECT_EQ(shaderOrigin("environment/" + name + ".frag"),
                      "embedded:environment/" + name + ".frag");
        }
    }
    EXPECT_FALSE(fs::exists(source / "shaders" / "environment"));
    // Any other shader file of a method folder is embedded as "<m>/<file>" (what its shaders
    // include, e.g. the evaluation that the streamed materials share).
    int others = 0;
    for (const std::string& name : builtInMethods())
        for (const auto& entry : fs::directory_iterator(source / "materials" / name)) {
            const std::string file = entry.path().filename().string(),
                              ext = entry.path().extension();
            if ((ext != ".glsl" && ext != ".frag" && ext != ".vert") || file == name + ".frag" ||
                file == name + "_environment.frag")
                continue;
            EXPECT_TRUE(has(name + "/" + file)) << name << "/" << file;
            EXPECT_NO_THROW(shaderSource(name + "/" + file));
            ++others;
        }
    EXPECT_GE(others, 1);
}

}  // namespace OSGBTF_TEST_FILE
