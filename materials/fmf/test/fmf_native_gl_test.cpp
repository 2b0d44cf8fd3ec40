// UBO2014 files opened as stored (scene/OpenMaterial.h): the fmf shader equals the CPU evaluator
// on the hand-written DFMF (colour model 11, ranks 2/3/1) and FMF (dynamic-range reduction, cosine
// flag) files of tests/HandWrittenUbo2014.h, at measured and unmeasured directions. The fmf
// method's own GPU test (fmf_gl_test.cpp) uses fitted materials; these inputs are files
// another implementation of the format could have written.
#include <unistd.h>

#include <algorithm>
#include <filesystem>
#include <fstream>
#include <iostream>

#include <gtest/gtest.h>

#include "scene/OpenMaterial.h"
#include "tests/HandWrittenUbo2014.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

double worstDifference = 0;  // over the whole test binary, printed for the record

/** Values reach ~10 (exp, division by cos 75 degrees); GPU and CPU do the same float math on the
 *  same half/float factors, so 1e-3 is float rounding with a wide margin. */
void expectGpuEqualsCpu(const Material& m, const Direction& v, const Direction& l) {
    const test::GpuCpuComparison r = test::compareGpuWithCpu(m, v.toVector(), l.toVector());
    worstDifference = std::max(worstDifference, r.maxAbsDifference);
    EXPECT_GT(r.pixelsCompared, 4 * m.width() * m.height() / 3) << "view " << v.theta;
    EXPECT_LE(r.maxAbsDifference, 1e-3) << "view " << v.theta << "/" << v.phi << " light "
                                        << l.theta << "/" << l.phi << ": " << r.worst;
}

void checkFile(const test::HandWrittenBtf& f, MaterialTexture::PixelKind storage) {
    // The GL tests do not link tests/TestUtil: a file of their own, removed once read.
    const std::string path = (std::filesystem::temp_directory_path() /
                              ("osgbtf-native-" + std::to_string(::getpid()) + ".btf"))
                                 .string();
    std::ofstream(path, std::ios::binary).write(f.bytes.data(), std::streamsize(f.bytes.size()));
    osg::ref_ptr<Material> m = openUbo2014Material(path, storage);
    std::filesystem::remove(path);
    ASSERT_EQ(m->methodName(), "fmf");
    // Every measured (view, light) pair with view theta below 75 (the orthographic patch needs
    // enough pixels) and a spread of lights.
    for (std::size_t v = 0; v < m->views().size(); ++v) {
        if (m->views()[v].theta >= 70) continue;
        for (std::size_t l = v % 3; l < m->lights().size(); l += 3)
            expectGpuEqualsCpu(*m, m->views()[v], m->lights()[l]);
    }
    // Unmeasured: inside triangles, near the zenith, beyond the outermost ring.
    const std::vector<std::pair<Direction, Direction>> unmeasured = {{{31.7f, 77}, {52, 200}},
                                                                     {{8, 11}, {68, 301}},
                                                                     {{52, 160}, {82, 45}},
                                                                     {{20, 250}, {5, 190}},
                                                                     {{44, 333}, {37.5f, 95}}};
    for (const auto& [v, l] : unmeasured) expectGpuEqualsCpu(*m, v, l);
}

}  // namespace

TEST(FmfNativeGpu, HandWrittenDfmfColourModel11MatchesCpu) {
    checkFile(test::handWrittenDfmf11(), MaterialTexture::Half);
    checkFile(test::handWrittenDfmf11(), MaterialTexture::Float);  // float file, float textures
    std::cout << "fmf native (DFMF) GPU vs CPU: largest difference " << worstDifference << "\n";
}

TEST(FmfNativeGpu, HandWrittenFmfWithDrrAndCosineMatchesCpu) {
    checkFile(test::handWrittenFmfDrrCosine(), MaterialTexture::Half);
    std::cout << "fmf native (FMF) GPU vs CPU: largest difference " << worstDifference << "\n";
}

}  // namespace OSGBTF_TEST_FILE
