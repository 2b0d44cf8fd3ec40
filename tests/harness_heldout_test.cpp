// Held-out scores (harness/HeldOut.h): SSIM against values worked out by hand and against
// scikit-image's implementation, and the scores of models that predict the left-out directions
// exactly and of one that does not.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "core/MeasuredBtf.h"
#include "harness/HeldOut.h"
#include "materials/MethodRegistry.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;

TEST(Ssim, EmptyImagesAreRefused) {
    const float pixel[3] = {0, 0, 0};
    EXPECT_EQ(test::errorOf([&] { structuralSimilarity(pixel, pixel, 0, 4, 3); }),
              "SSIM: empty image 0x4");
}

TEST(Ssim, IdenticalImagesScoreOne) {
    std::vector<float> a(20 * 14 * 3);
    for (std::size_t i = 0; i < a.size(); ++i) a[i] = float((i * 37) % 101) / 100;
    EXPECT_NEAR(structuralSimilarity(a.data(), a.data(), 20, 14, 3), 1.0, 1e-12);
}

// Two constant images (8 x 6: the window shrinks to 5 x 5, and no variance anywhere): the
// contrast-structure factor is C2 / C2 = 1, the luminance factor (2 a b + C1) / (a^2 + b^2 + C1)
// with C1 = 0.01^2: a = 0.3, b = 0.5 gives 0.3001 / 0.3401.
TEST(Ssim, ConstantImagesScoreTheirLuminanceTerm) {
    const std::vector<float> a(8 * 6, 0.3f), b(8 * 6, 0.5f);
    const double expected = (2 * 0.3 * 0.5 + 1e-4) / (0.3 * 0.3 + 0.5 * 0.5 + 1e-4);
    // The images hold float(0.3) and float(0.5): a relative change of ~1e-8.
    EXPECT_NEAR(structuralSimilarity(a.data(), b.data(), 8, 6, 1), expected, 1e-7);
}

// Reference: scikit-image 0.19.3, skimage.metrics.structural_similarity(a, b,
// gaussian_weights=True, sigma=1.5, use_sample_covariance=False, data_range=1.0, channel_axis=-1)
// (Wang et al. 2004's settings) on these float images, 16 x 13 RGB, gave 0.8864316032253269.
TEST(Ssim, MatchesScikitImageOnAPattern) {
    const int w = 16, h = 13;
    std::vector<float> a(std::size_t(w * h * 3)), b(a.size());
    for (int y = 0; y < h; ++y)
        for (int x = 0; x < w; ++x)
            for (int c = 0; c < 3; ++c) {
                const double av = 0.5 + 0.4 * std::sin(0.7 * x + 0.3 * y + c);
                const double bv = 0.8 * av + 0.1 * std::cos(0.05 * x * y + c) +
                                  0.02 * double((x * 7 + y * 3 + c) % 5);
                const std::size_t i = std::size_t((y * w + x) * 3 + c);
                a[i] = float(av);
                b[i] = float(bv);
            }
    EXPECT_NEAR(structuralSimilarity(a.data(), b.data(), w, h, 3), 0.8864316032253269, 1e-9);
}

// Data that are exactly Lambertian (albedo x l_z, albedos exact in half): lambert fitted without
// the held-out directions predicts them exactly, so SSIM is 1 and the error is float rounding; a
// model of other data (the albedos halved) scores far lower.
TEST(HeldOutScores, AModelThatPredictsTheLeftOutPairsScoresPerfectly) {
    const DirectionSet bonn = DirectionSet::bonn81();
    const auto lambertian = [&](double scale) {
        MeasuredBtf btf(12, 12, bonn, bonn);
        for (std::size_t v = 0; v < bonn.size(); ++v)
            for (std::size_t l = 0; l < bonn.size(); ++l)
                for (std::size_t t = 0; t < btf.texelCount(); ++t)
                    for (int c = 0; c < 3; ++c)
                        btf.setValue(v, l, t, c,
                                     float(scale * double(8 + (t * 5 + std::size_t(c)) % 48) / 64 *
                                           bonn.vector(l).z));
        return btf;
    };
    const MeasuredBtf btf = lambertian(1.0);
    const batch::HoldoutSplit split = batch::holdoutSplit(btf.viewCount(), btf.lightCount(), 0.1);
    const batch::DirectionSubsetSource kept(btf, split);
    const osg::ref_ptr<Material> model = findMethod("lambert").fit(kept, FitOptions());
    const HeldOutScores scores = scoreHeldOut(btf, *model, split);
    EXPECT_EQ(scores.pairs, split.leftOutPairs.size());
    EXPECT_EQ(scores.imagesScored, 8u);
    EXPECT_NEAR(scores.ssim, 1.0, 1e-6);
    EXPECT_LT(scores.error.average, 1e-6);
    EXPECT_GT(scores.error.psnr, 100.0);

    const MeasuredBtf darker = lambertian(0.5);
    const batch::DirectionSubsetSource keptDarker(darker, split);
    const osg::ref_ptr<Material> wrong = findMethod("lambert").fit(keptDarker, FitOptions());
    const HeldOutScores bad = scoreHeldOut(btf, *wrong, split);
    EXPECT_LT(bad.ssim, 0.95);
    EXPECT_LT(bad.error.psnr, 30.0);
    EXPECT_EQ(test::errorOf([&] { scoreHeldOut(btf, *model, batch::HoldoutSplit()); }),
              "held-out scores: no direction is left out");
}

}  // namespace OSGBTF_TEST_FILE
