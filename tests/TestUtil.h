// Helpers shared by the unit tests: scratch folders and running the tools.
#pragma once

#include <filesystem>
#include <functional>
#include <string>

namespace osgBTF::test {

/** This build's source tree and build folder. Defined in a file CMake writes into the build folder
 *  (tests/TestPaths.cpp.in), not passed as compile definitions: an absolute path on a compile line
 *  makes every test object differ between two clones, and ccache could share none of them. */
const std::string& sourceDir();
const std::string& buildDir();
/** An executable of this build, e.g. builtTool("btf"): <build>/bin/NAME. */
std::string builtTool(const std::string& name);

/** A fresh folder under the system temp dir, removed with its contents on destruction. */
class TempDir {
public:
    TempDir();
    ~TempDir();
    const std::filesystem::path& path() const { return _path; }
    std::string file(const std::string& name) const { return (_path / name).string(); }

private:
    std::filesystem::path _path;
};

struct CommandResult {
    int exitCode = -1;
    std::string output;  ///< stdout and stderr together
};

/** Runs a shell command line and captures its output. */
CommandResult runCommand(const std::string& commandLine);

/** Quotes a path for the shell. */
std::string shellQuote(const std::string& text);

/** Runs f and returns the message of the osgBTF::Error it throws; "no error" if it throws none,
 *  "unexpected exception type: ..." for any other exception. */
std::string errorOf(const std::function<void()>& f);

void writeTextFile(const std::string& path, const std::string& content);
std::string readTextFile(const std::string& path);

/** Whether this program is built with AddressSanitizer or ThreadSanitizer (GCC defines the
 *  macros, clang answers __has_feature): stock programs cannot load its instrumented plugins,
 *  and memory figures include the sanitizer's. */
#if defined(__SANITIZE_ADDRESS__) || defined(__SANITIZE_THREAD__)
inline constexpr bool kSanitized = true;
#elif defined(__has_feature)
#if __has_feature(address_sanitizer) || __has_feature(thread_sanitizer)
inline constexpr bool kSanitized = true;
#else
inline constexpr bool kSanitized = false;
#endif
#else
inline constexpr bool kSanitized = false;
#endif

}  // namespace osgBTF::test
