// What the soak benchmarks (soak.cpp, paged.cpp) start from: this build's osgDB plugins, and
// three fitted materials of the built-in sample written into a folder.
#pragma once

#include <filesystem>
#include <string>
#include <vector>

#include <osgDB/Registry>

#include "harness/sample/SampleBtf.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"

namespace osgBTF::bench {

/** Puts the plugins of this build (bin/../lib) before any installed ones on osgDB's path. */
inline void useBuildPlugins() {
    const std::filesystem::path lib =
        std::filesystem::canonical("/proc/self/exe").parent_path().parent_path() / "lib";
    osgDB::Registry::instance()->getLibraryFilePathList().push_front(lib.string());
}

/** lambert, pca and laf (their quick fit options) fitted to the built-in sample of `texels` x
 *  `texels` texels, saved as <method>.btfmat into `folder` (created); the files, in that order. */
inline std::vector<std::string> writeSampleMaterials(const std::filesystem::path& folder,
                                                     int texels) {
    std::filesystem::create_directories(folder);
    SampleOptions sample;
    sample.width = sample.height = texels;
    const MeasuredBtf btf = makeSampleBtf(sample);
    std::vector<std::string> files;
    for (const char* method : {"lambert", "pca", "laf"}) {
        const MethodInfo& info = findMethod(method);
        const std::string file = (folder / (std::string(method) + ".btfmat")).string();
        saveMaterial(*info.fit(btf, FitOptions::parse(info.quickFitOptions)), file);
        files.push_back(file);
    }
    return files;
}

}  // namespace osgBTF::bench
