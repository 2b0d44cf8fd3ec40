// Storage kinds reach the shader as the CPU sees them; a rectified image leaves no fixed view
// behind in the method's shared program.
#include <cmath>

#include <gtest/gtest.h>

#include "harness/MaterialImage.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/laf/Laf.h"
#include "materials/lambert/Lambert.h"
#include "tests/gl/GlTestEnv.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

TEST(MaterialImage, GpuImageEqualsCpuImageAndKeepsTheInputOrientation) {
    SampleOptions options;
    options.width = 8;
    options.height = 5;
    const MeasuredBtf btf = makeSampleBtf(options);
    osg::ref_ptr<LambertMaterial> m = LambertMaterial::fit(btf, {});
    const glm::vec3 view = Direction{30, 60}.toVector(), light = Direction{45, 200}.toVector();
    const FloatImage gpu = renderMaterialImage(test::sharedRenderer(), *m, view, light);
    const FloatImage cpu = evaluateMaterialImage(*m, view, light);
    EXPECT_LE(maxAbsDifference(gpu, cpu), 1e-6);
    // Row 0 of an image file is the top (+Y) edge, texel row height-1.
    EXPECT_NEAR(gpu.at(3, 0, 1), m->evaluate(3, 4, view, light).g, 1e-6);
}

TEST(MaterialState, ARectifiedImageLeavesTheNextDrawItsRealEyeDirection) {
    // osgBTF_fixedView belongs to the method's one shared program, and GL keeps a program's
    // uniform values until they are set again: after a rectified image (the view fixed straight
    // above) the material's own StateSet must shade each pixel as seen along its eye ray again.
    SampleOptions options;
    options.width = 5;
    options.height = 3;
    osg::ref_ptr<LafMaterial> m =
        LafMaterial::fit(makeSampleBtf(options), FitOptions::parse("lobes=1 iterations=10"));
    const glm::vec3 light = Direction{45, 200}.toVector();
    renderMaterialImage(test::sharedRenderer(), *m, glm::vec3(0, 0, 1), light);
    const test::GpuCpuComparison r =
        test::compareGpuWithCpu(*m, Direction{60, 30}.toVector(), light);
    EXPECT_GT(r.pixelsCompared, 8);
    EXPECT_LE(r.maxAbsDifference, 1e-3) << r.worst;
}

}  // namespace OSGBTF_TEST_FILE
