// Storage kinds reach the shader as the CPU sees them.
#include <cmath>

#include <gtest/gtest.h>

#include "harness/MaterialImage.h"
#include "harness/sample/SampleBtf.h"
#include "materials/lambert/Lambert.h"
#include "tests/gl/GlTestEnv.h"

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
