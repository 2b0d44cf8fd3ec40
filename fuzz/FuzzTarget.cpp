// One libFuzzer target (fuzz_<name>), compiled once per target with OSGBTF_FUZZ_TARGET=<name>:
// the body is fuzz/FuzzEntries.cpp's, shared with the regression test.
#include <cstdio>
#include <cstdlib>
#include <memory>

#include <tbb/global_control.h>

#include "core/Error.h"
#include "fuzz/FuzzEntries.h"

#define OSGBTF_FUZZ_STRINGIFY2(x) #x
#define OSGBTF_FUZZ_STRINGIFY(x) OSGBTF_FUZZ_STRINGIFY2(x)

namespace {
const osgBTF::fuzz::Target* g_target = nullptr;
}

extern "C" int LLVMFuzzerInitialize(int*, char***) {
    // One thread per fuzzer: the loaders decode with TBB, and parallel fuzzers (-jobs=N) each
    // take one core.
    static const auto oneThread =
        std::make_unique<tbb::global_control>(tbb::global_control::max_allowed_parallelism, 1);
    const char* fixtures = std::getenv("OSGBTF_FUZZ_FIXTURES");
    osgBTF::fuzz::setUp(fixtures && *fixtures ? fixtures : OSGBTF_FUZZ_FIXTURES_DIR);
    g_target = osgBTF::fuzz::findTarget(OSGBTF_FUZZ_STRINGIFY(OSGBTF_FUZZ_TARGET));
    if (!g_target) {
        std::fprintf(stderr, "no fuzz entry '%s'\n", OSGBTF_FUZZ_STRINGIFY(OSGBTF_FUZZ_TARGET));
        std::abort();
    }
    return 0;
}

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
    try {
        g_target->run(data, size);
    } catch (const osgBTF::Error&) {
        // Refusing bad input with a message is the parsers' job; any other exception escapes
        // and libFuzzer reports it (deadly signal from std::terminate).
    }
    return 0;
}
