// Method "pca" on the GPU, its cases of EveryMethod/MethodGpu (tests/gl/method_gpu_test.cpp): the
// shader's 3 view x 3 light interpolation of Eigen-Textures equals the CPU reference at measured
// and unmeasured directions, for 8-bit (the default) and float Eigen-Textures.
#include "materials/pca/Pca.h"
#include "tests/gl/MethodGpuCases.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

// 20 measured (view, light) pairs over every theta ring (view theta < 75, so that the
// orthographic patch covers enough pixels) and 5 unmeasured ones: interpolation inside triangles
// and beyond the outermost ring. 16 float components exercise the float array texture path.
const bool kCases = test::registerGpuCases(
    PcaMaterial::kMethod, {{"components=6", test::GpuCase::sampleOfSize(8, 6),
                            test::bonnPairs(20, 37, 0, 57, 23, 5,
                                            {{{31.7f, 77}, {52, 200}},
                                             {{8, 11}, {68, 301}},
                                             {{52, 160}, {82, 45}},
                                             {{20, 250}, {5, 190}},
                                             {{44, 333}, {37.5f, 95}}}),
                            test::fixedBound(1e-3)},
                           {"components=16 storage=float", test::GpuCase::sampleOfSize(8, 6),
                            test::vectorPairs({{{30, 90}, {45, 20}}, {{31.7f, 77}, {52, 200}}}),
                            test::fixedBound(1e-3)}});

}  // namespace OSGBTF_TEST_FILE
