// The shared shader stages build the surface frame and the eye direction the CPU evaluator
// assumes, on surfaces and projections the flat orthographic patch does not exercise: a patch
// under a non-uniform scale (tangents transform by the modelview, normals by its inverse
// transpose) and projections whose matrix is orthographic without [3][3] being exactly 1, or
// perspective.
#include <gtest/gtest.h>

#include <cmath>

#include <glm/geometric.hpp>

#include "harness/sample/SampleBtf.h"
#include "materials/MethodOptions.h"
#include "materials/laf/Laf.h"
#include "materials/pca/Pca.h"
#include "tests/gl/MaterialGpuCheck.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

namespace {

const MeasuredBtf& sample() {
    static const MeasuredBtf btf = [] {
        SampleOptions options;
        options.width = 8;
        options.height = 6;
        return makeSampleBtf(options);
    }();
    return btf;
}

const Material& laf() {
    static osg::ref_ptr<LafMaterial> m =
        LafMaterial::fit(sample(), FitOptions::parse("iterations=20"));
    return *m;
}

const Material& pca() {
    static osg::ref_ptr<PcaMaterial> m =
        PcaMaterial::fit(sample(), FitOptions::parse("components=4"));
    return *m;
}

// Rotated 40 degrees about Z, then stretched 4x along world Y, then tilted 20 degrees about X:
// the texture's s axis is no longer perpendicular to its t axis in the world, and the normal
// matrix (inverse transpose) turns the tangent the other way than the model matrix does.
osg::Matrixd stretchedModel() {
    return osg::Matrixd::rotate(osg::DegreesToRadians(40.0), osg::Vec3d(0, 0, 1)) *
           osg::Matrixd::scale(1, 4, 1) *
           osg::Matrixd::rotate(osg::DegreesToRadians(20.0), osg::Vec3d(1, 0, 0));
}

void expectMatch(const Material& m, const test::PatchRender& render, const std::string& what) {
    const test::GpuCpuComparison r = test::compareGpuWithCpu(m, render);
    EXPECT_GT(r.pixelsCompared, 48) << what;
    EXPECT_LE(r.maxAbsDifference, 1e-3) << what << ": " << r.worst;
}

}  // namespace

TEST(SurfaceFrame, TangentFollowsTheModelMatrixUnderNonUniformScale) {
    const osg::Matrixd model = stretchedModel();
    // The set-up must tell the two transforms apart: the tangent the normal matrix gives, made
    // orthogonal to the normal, is far from the true one.
    const glm::dmat3 frame = test::patchFrame(model);
    const osg::Vec3d wrong =
        osg::Matrixd::transform3x3(osg::Matrixd::inverse(model), osg::Vec3d(1, 0, 0));
    glm::dvec3 w(wrong.x(), wrong.y(), wrong.z());
    w = glm::normalize(w - frame[2] * glm::dot(frame[2], w));
    EXPECT_GT(std::acos(glm::dot(w, frame[0])), osg::DegreesToRadians(30.0));

    const std::pair<Direction, Direction> pairs[] = {
        {{40, 30}, {50, 200}}, {{25, 120}, {60, 10}}, {{55, 260}, {30, 75}}};
    for (const auto& [v, l] : pairs) {
        const std::string what = "view " + std::to_string(v.theta) + "/" + std::to_string(v.phi) +
                                 " light " + std::to_string(l.theta) + "/" + std::to_string(l.phi);
        expectMatch(laf(), test::orthoPatchRender(laf(), v.toVector(), l.toVector(), model),
                    "laf " + what);
        expectMatch(pca(), test::orthoPatchRender(pca(), v.toVector(), l.toVector(), model),
                    "pca " + what);
    }
}

TEST(SurfaceFrame, OrthographicProjectionWithoutAUnitCorner) {
    // A projection matrix is defined up to a positive factor (clip coordinates are homogeneous):
    // the same picture, but [3][3] is not 1. 1 - 2^-20 is what rounding in a product of
    // matrices gives; float keeps it apart from 1.
    for (double factor : {0.5, 1.0 - std::ldexp(1.0, -20), 3.0}) {
        test::PatchRender render = test::orthoPatchRender(laf(), Direction{50, 70}.toVector(),
                                                          Direction{35, 250}.toVector());
        for (int row = 0; row < 4; ++row)
            for (int column = 0; column < 4; ++column)
                render.camera.projection(row, column) *= factor;
        ASSERT_NE(float(render.camera.projection(3, 3)), 1.0f);
        expectMatch(laf(), render, "ortho x " + std::to_string(factor));
    }
}

TEST(SurfaceFrame, PerspectiveProjection) {
    // Seen from close by at a slant: the view direction changes across the patch. LAF only: its
    // value is continuous in the view, while the per-view methods' baked table is piecewise
    // constant, so a pixel whose direction lies within float rounding of a cell border could
    // pick a different cell on the GPU than on the CPU.
    for (const osg::Matrixd& model : {osg::Matrixd(), stretchedModel()}) {
        test::PatchRender render = test::orthoPatchRender(laf(), Direction{45, 60}.toVector(),
                                                          Direction{40, 200}.toVector(), model);
        const osg::Vec3d centre = osg::Vec3d(0.5, 0.5, 0) * model;
        const glm::dmat3 frame = test::patchFrame(model);
        const glm::dvec3 toEye = frame * glm::dvec3(Direction{45, 60}.toVector());
        const double distance = model.isIdentity() ? 1.2 : 3.0;
        render.camera.view = osg::Matrixd::lookAt(
            centre + osg::Vec3d(toEye.x, toEye.y, toEye.z) * distance, centre, osg::Vec3d(0, 0, 1));
        render.camera.projection = osg::Matrixd::perspective(50.0, 1.0, 0.05, 20.0);
        render.camera.width = render.camera.height = 192;
        expectMatch(laf(), render, model.isIdentity() ? "flat" : "stretched");
    }
}

}  // namespace OSGBTF_TEST_FILE
