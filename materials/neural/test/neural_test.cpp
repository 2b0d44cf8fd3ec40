// Method "neural" (materials/neural): option errors first, then the decoder against a network
// written by hand, the file round trip and its refusals, and the fit (libtorch): below the lambert
// baseline, deterministic for a seed, latents stored as halves, bounded blocks of measured data.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <iostream>

#include <Imath/half.h>

#include "core/Error.h"
#include "core/ErrorMetrics.h"
#include "harness/sample/SampleBtf.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/lambert/Lambert.h"
#include "materials/neural/Neural.h"
#include "tests/SmallSample.h"
#include "tests/TestUtil.h"

namespace OSGBTF_TEST_FILE {

using namespace osgBTF;
using osgBTF::test::errorOf;

namespace {

osg::ref_ptr<NeuralMaterial> fit(const BtfSource& btf, const std::string& options) {
    return NeuralMaterial::fit(btf, FitOptions::parse(options));
}

ErrorSummary errorOfMaterial(const MeasuredBtf& btf, const Material& m) {
    return computeError(btf,
                        [&](std::size_t texel, float* out) { m.evaluateMeasured(texel, out); });
}

// An eighth of this limit holds 16 texels' ABRDFs (81 x 81 pairs, RGB floats): an 8 x 8 sample
// is fitted in 4 blocks.
constexpr std::uint64_t kFourBlocksOf8x8 = 8ull * 16 * 81 * 81 * 3 * 4;

struct MemoryLimitGuard {
    std::uint64_t saved = memoryLimit();
    ~MemoryLimitGuard() { setMemoryLimit(saved); }
};

/** Sets neuron j of layer k: its bias and its weights (the rest stay 0). */
void setNeuron(NeuralMaterial& m, int k, int j, float bias, const std::vector<float>& weights) {
    float* row = &m.decoder.data[std::size_t(m.decoderRow(k, j)) * m.decoder.width * 4];
    row[0] = bias;
    std::copy(weights.begin(), weights.end(), row + 4);
}

/** 1 x 1 texels (or `width` x 1), 4 latents, one hidden layer of 4 units, written by hand. */
osg::ref_ptr<NeuralMaterial> handMadeNetwork(int width = 1) {
    osg::ref_ptr<NeuralMaterial> m = new NeuralMaterial;
    m->setShape(width, 1, DirectionSet::bonn81(), DirectionSet::bonn81(), 4, 1, 4);
    const float latent[4] = {1.0f, -2.0f, 3.0f, 0.5f};
    for (int i = 0; i < 4; ++i) m->latent.set(m->latentIndex(0, 0, i), latent[i]);
    // Inputs: z0..z3, then v.x, v.y, l.x, l.y, h.x, h.y, h.z, l.z.
    setNeuron(*m, 0, 0, 0.0f, {1, 0, 0, 0});                          // z0 = 1
    setNeuron(*m, 0, 1, 0.0f, {0, 1, 0, 0});                          // relu(z1 = -2) = 0
    setNeuron(*m, 0, 2, -1.0f, {0, 0, 1, 0});                         // z2 - 1 = 2
    setNeuron(*m, 0, 3, 0.0f, {0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 2, 0});  // 2 h.z
    setNeuron(*m, 1, 0, 0.5f, {1, 0, 0, 0});                          // 0.5 + n0
    setNeuron(*m, 1, 1, 0.0f, {0, 1, -1, 0});                         // n1 - n2
    setNeuron(*m, 1, 2, 0.0f, {0, 0, 0, 1});                          // n3
    return m;
}

}  // namespace

TEST(Neural, OptionErrorsHaveTheRegistryFormat) {
    const MeasuredBtf btf = test::sampleBtf(2, 2);
    EXPECT_EQ(errorOf([&] { fit(btf, "latent=6"); }),
              "neural: option latent must be a multiple of 4 in 4..32, got 6");
    EXPECT_EQ(errorOf([&] { fit(btf, "units=30"); }),
              "neural: option units must be a multiple of 4 in 4..64, got 30");
    EXPECT_EQ(errorOf([&] { fit(btf, "latent=36"); }),
              "neural: option latent must be a multiple of 4 in 4..32, got 36");
    EXPECT_EQ(errorOf([&] { fit(btf, "layers=0"); }),
              "neural: option layers must be an integer in 1..4, got 0");
    EXPECT_EQ(errorOf([&] { fit(btf, "width=8"); }),
              "neural: option width is unknown (known: latent, layers, units, steps, batch, seed, "
              "filtered, threads)");
    EXPECT_EQ(errorOf([&] { fit(MeasuredBtf(), ""); }), "neural: the BTF is empty");
}

TEST(Neural, DecoderComputesTheNetworkWrittenByHand) {
    const osg::ref_ptr<NeuralMaterial> m = handMadeNetwork();
    // Straight down, view and light at the normal: h = (0, 0, 1), l_z = 1.
    const glm::vec3 up(0, 0, 1);
    glm::vec3 v = m->evaluate(0, 0, up, up);
    EXPECT_FLOAT_EQ(v.r, 1.5f);   // 0.5 + 1
    EXPECT_FLOAT_EQ(v.g, -2.0f);  // 0 - 2: the output layer is linear
    EXPECT_FLOAT_EQ(v.b, 2.0f);   // 2 h.z
    // Light at 60 degrees in x, view at the normal: h = normalize(sin 60, 0, 1 + cos 60), l_z =
    // 0.5.
    const glm::vec3 light(std::sqrt(3.0f) / 2, 0, 0.5f);
    const double hz = 1.5 / std::sqrt(0.75 + 2.25);
    v = m->evaluate(0, 0, up, light);
    EXPECT_NEAR(v.r, 1.5 * 0.5, 1e-6);
    EXPECT_NEAR(v.g, -2.0 * 0.5, 1e-6);
    EXPECT_NEAR(v.b, 2 * hz * 0.5, 1e-6);
}

TEST(Neural, AFilteredLookupDecodesTheBlendedLatentsOnce) {
    // Texel 0 as above, texel 1 with latents (-1, 2, 1, 0.5): half-way between their centres
    // the latents blend to (0, 0, 2, 0.5), which decode (view and light at the normal) to
    // (0.5 + 0, 0 - 1, 2 h.z): not the mean of the two texels' values ((1.5, -2, 2) and
    // (0.5, 2, 2)), which a blend of decodes would give.
    const osg::ref_ptr<NeuralMaterial> m = handMadeNetwork(2);
    const float second[4] = {-1.0f, 2.0f, 1.0f, 0.5f};
    for (int i = 0; i < 4; ++i) m->latent.set(m->latentIndex(1, 0, i), second[i]);
    ASSERT_EQ(m->texelFilter(), Material::TexelFilter::Inputs);
    const glm::vec3 up(0, 0, 1);
    EXPECT_EQ(m->evaluate(1, 0, up, up), glm::vec3(0.5f, 2.0f, 2.0f));
    // u = 0.5 lies half-way between the centres 0.25 and 0.75.
    EXPECT_EQ(m->evaluateFiltered(0.5f, 0.5f, 0.0f, up, up), glm::vec3(0.5f, -1.0f, 2.0f));
    // At a texel's centre the texel itself.
    EXPECT_EQ(m->evaluateFiltered(0.75f, 0.5f, 0.0f, up, up), m->evaluate(1, 0, up, up));
}

TEST(Neural, ShapesOutsideTheLimitsAreRefused) {
    osg::ref_ptr<NeuralMaterial> m = new NeuralMaterial;
    m->setShape(1, 1, DirectionSet::bonn81(), DirectionSet::bonn81(), 4, 1, 4);
    EXPECT_EQ(errorOf([&] { m->setNetworkShape(40, 2, 32); }),
              "neural: the latent size must be a multiple of 4 in 4..32, got 40");
    EXPECT_EQ(errorOf([&] { m->setNetworkShape(8, 5, 32); }),
              "neural: the hidden layers must be 1..4, got 5");
    EXPECT_EQ(errorOf([&] { m->setNetworkShape(8, 2, 66); }),
              "neural: the units per layer must be a multiple of 4 in 4..64, got 66");
}

TEST(Neural, FileRoundTripIsExactAndBadFilesAreRefused) {
    const osg::ref_ptr<NeuralMaterial> m = handMadeNetwork();
    const test::TempDir dir;
    const std::string path = dir.file("hand.btfmat");
    saveMaterial(*m, path);
    const osg::ref_ptr<Material> loaded = loadMaterial(path);
    ASSERT_EQ(loaded->methodName(), "neural");
    const DirectionSet& d = m->views();
    for (std::size_t i = 0; i < d.size(); i += 7)
        for (std::size_t j = 0; j < d.size(); j += 5) {
            const glm::vec3 a = m->evaluate(0, 0, d.vector(i), d.vector(j));
            const glm::vec3 b = loaded->evaluate(0, 0, d.vector(i), d.vector(j));
            ASSERT_EQ(a, b);
        }
    FittedMaterial file = m->toFittedMaterial();
    file.source = "hand.btfmat";
    FittedMaterial wrongUnits = file;
    wrongUnits.parameters["units"] = "8";
    EXPECT_EQ(errorOf([&] { materialFromFile(wrongUnits); }),
              "hand.btfmat: texture 'decoder' must be 4x11x1 RGBA float for latent 4, layers 1, "
              "units 8");
    FittedMaterial notNumber = file;
    notNumber.parameters["layers"] = "2x";
    EXPECT_EQ(errorOf([&] { materialFromFile(notNumber); }),
              "hand.btfmat: parameter 'layers' is not an integer");
    FittedMaterial badShape = file;
    badShape.parameters["latent"] = "6";
    EXPECT_EQ(errorOf([&] { materialFromFile(badShape); }),
              "hand.btfmat: neural: the latent size must be a multiple of 4 in 4..32, got 6");
    FittedMaterial notFinite = file;
    notFinite.textures[1].data[0] = std::nanf("");
    EXPECT_EQ(errorOf([&] { materialFromFile(notFinite); }),
              "hand.btfmat: texture 'decoder' holds a value that is not finite");
}

TEST(Neural, MemoryCountsHalfLatentsPerTexelAndTheSharedDecoder) {
    osg::ref_ptr<NeuralMaterial> m = new NeuralMaterial;
    m->setShape(16, 8, DirectionSet::bonn81(), DirectionSet::bonn81(), 8, 2, 32);
    // Decoder: 1 + max(8 + 8, 32) / 4 = 9 RGBA texels per row, 2 x 32 + 3 rows, float.
    const std::uint64_t shared = 9 * 67 * 4 * 4;
    const MemoryFootprint f = m->memory();
    EXPECT_EQ(f.sharedBytes, shared);
    EXPECT_EQ(f.totalBytes, 16u * 8 * 8 * 2 + shared);
    EXPECT_DOUBLE_EQ(f.bytesPerTexel, 16.0 + double(shared) / 128);
}

// The network can represent lambert's albedo x l_z exactly (a constant decoder output per texel),
// so a working fit ends below the baseline; 2000 steps on 8 x 8 texels give 0.0169 against 0.0190.
TEST(Neural, FitLearnsTheSampleBelowTheLambertBaseline) {
    const MeasuredBtf btf = test::sampleBtf(8, 8);
    const osg::ref_ptr<NeuralMaterial> m = fit(btf, "latent=4 units=16 steps=2000 batch=1024");
    const ErrorSummary neural = errorOfMaterial(btf, *m);
    const ErrorSummary lambert = errorOfMaterial(btf, *LambertMaterial::fit(btf, FitOptions()));
    std::cout << "neural average error " << neural.average << ", RMSE " << neural.rmse
              << "; lambert " << lambert.average << ", " << lambert.rmse << "\n";
    EXPECT_EQ(neural.nonFiniteValues, 0u);
    EXPECT_LT(neural.rmse, 0.95 * lambert.rmse);
    // What the file and the GPU hold: the latents are halves.
    EXPECT_EQ(m->latent.kind(), MaterialTexture::Half);
    EXPECT_TRUE(m->latent.allFinite());
    EXPECT_EQ(m->fitInfo.at("blocks"), "1");
}

TEST(Neural, TheSameSeedFitsTheSameMaterialAndAnotherSeedAnother) {
    const MeasuredBtf btf = test::sampleBtf(4, 4);
    const std::string options = "latent=4 units=8 layers=1 steps=50 batch=256";
    const osg::ref_ptr<NeuralMaterial> a = fit(btf, options), b = fit(btf, options),
                                       c = fit(btf, options + " seed=2");
    EXPECT_EQ(a->latent, b->latent);
    EXPECT_EQ(a->decoder.data, b->decoder.data);
    EXPECT_NE(a->decoder.data, c->decoder.data);
    // Two threads: a batch and network large enough for torch to split its products.
    const std::string twoThreads = "latent=8 units=32 layers=2 steps=20 batch=8192 threads=2";
    const osg::ref_ptr<NeuralMaterial> d = fit(btf, twoThreads), e = fit(btf, twoThreads);
    EXPECT_EQ(d->latent, e->latent);
    EXPECT_EQ(d->decoder.data, e->decoder.data);
}

TEST(Neural, AMemoryLimitSplitsTheMeasuredDataIntoBlocks) {
    const MeasuredBtf btf = test::sampleBtf(8, 8);
    MemoryLimitGuard guard;
    setMemoryLimit(kFourBlocksOf8x8);
    const std::string options = "latent=4 units=8 layers=1 batch=64";
    const osg::ref_ptr<NeuralMaterial> m = fit(btf, options + " steps=8");
    EXPECT_EQ(m->fitInfo.at("blocks"), "4");
    EXPECT_EQ(m->fitInfo.at("blocksRead"), "4");
    EXPECT_TRUE(m->latent.allFinite());
    // Three steps reach three blocks, one step each; the fourth's texels keep their start.
    EXPECT_EQ(fit(btf, options + " steps=3")->fitInfo.at("blocksRead"), "3");
}

// What the blocks are for: a fit that reads the data a block at a time still learns it (the long
// fit: .ci/run runs it in the normal build, not under the sanitizers).
TEST(Neural, AFitInBlocksLearnsTheSampleBelowTheLambertBaseline) {
    const MeasuredBtf btf = test::sampleBtf(8, 8);
    MemoryLimitGuard guard;
    setMemoryLimit(kFourBlocksOf8x8);
    const osg::ref_ptr<NeuralMaterial> m = fit(btf, "latent=4 units=16 steps=2000 batch=1024");
    EXPECT_EQ(m->fitInfo.at("blocks"), "4");
    EXPECT_EQ(m->fitInfo.at("blocksRead"), "4");
    setMemoryLimit(guard.saved);
    const ErrorSummary neural = errorOfMaterial(btf, *m);
    const ErrorSummary lambert = errorOfMaterial(btf, *LambertMaterial::fit(btf, FitOptions()));
    EXPECT_LT(neural.rmse, 0.95 * lambert.rmse);
}

}  // namespace OSGBTF_TEST_FILE
