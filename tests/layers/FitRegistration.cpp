// Built twice (tests/layers/CMakeLists.txt): linked to the render library libosgBTF alone, every
// registered method's fit must refuse with the error that names libosgBTFFit; linked to
// libosgBTFFit as well, without calling any of its functions by name, every method must reach its
// own fitter (the library's static initialisers ran, so its link interface kept it loaded).
// An unknown option tells the two apart without fitting anything: every fitter validates its
// options first (MethodInfo::fit), the stand-in of a missing fitter does not look at them.
#include <cstdio>
#include <exception>
#include <string>

#include "core/MeasuredBtf.h"
#include "materials/Material.h"
#include "materials/MethodRegistry.h"

#ifndef OSGBTF_EXPECT_FITTERS
#define OSGBTF_EXPECT_FITTERS 0
#endif

int main() {
    using namespace osgBTF;
    const MeasuredBtf empty;
    const FitOptions bogus = FitOptions::parse("osgbtf-no-such-option=1");
    if (methodNames().empty()) {
        std::puts("no method is registered");
        return 1;
    }
    int failures = 0;
    for (const std::string& name : methodNames()) {
        std::string message = "(no error)";
        try {
            findMethod(name).fit(empty, bogus);
        } catch (const std::exception& e) {
            message = e.what();
        }
        const std::string missing = "method '" + name + "': fitting needs libosgBTFFit";
        const bool saysMissing = message.rfind(missing, 0) == 0;
        if (saysMissing != !OSGBTF_EXPECT_FITTERS) {
            std::printf("%s: %s\n", name.c_str(), message.c_str());
            ++failures;
        }
    }
    std::printf("%zu methods, %d unexpected\n", methodNames().size(), failures);
    return failures == 0 ? 0 : 1;
}
