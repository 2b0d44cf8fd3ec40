// osgBTF method "lpca": clustered local PCA of the texels' apparent BRDFs (Müller et al. 2003;
// Schneider 2004 sections 3-5, Meseth et al. 2003 section 3.5 equation 7).
//
//   BTF(x, v, l) ~ sum_{v' in N(v), l' in N(l)} w_v(v') w_l(l') sum_{i<c} alpha_i(x) E_{i,k(x)}(v',
//   l')
//
// Each texel's ABRDF (all measured view x light x RGB values, one vector of V*L*3) belongs to one
// of k clusters; a cluster is a c-dimensional subspace spanned by its Eigen-BRDFs E_{i,k}
// (orthonormal vectors over all measured (view, light, rgb)); a texel stores its cluster index
// k(x) and its c weights alpha_i(x) (the projections onto the Eigen-BRDFs). The cluster mean is
// folded into the subspace (see README.md: Meseth et al. 2003 Table 2's 85.9 values per texel count
// exactly c Eigen-BRDFs per cluster, no separate mean), so each cluster is the best rank-c *linear*
// subspace of its members, which also contains the best mean + (c-1) components fit.
// N(v), N(l): the 3 measured directions of the baked Delaunay table and their weights.
//
// Storage (Meseth et al. 2003 Table 2 at Bonn 81x81, 256x256, k = 32, c = 8: 85.9 values, 170.8
// bytes): cluster index 8-bit, weights half, Eigen-BRDFs half.
#pragma once

#include <cstdint>
#include <vector>

#include "materials/DirectionLookup.h"
#include "materials/MethodMaterial.h"
#include "materials/MethodOptions.h"
#include "materials/StoredValues.h"

namespace osgBTF {

/** Settings of an LPCA fit (FitOptions keys in brackets). */
struct LpcaSettings {
    int clusters = 32;          ///< [clusters] k, 1..256 (the index is stored in 8 bits)
    int components = 8;         ///< [components] c Eigen-BRDFs per cluster, >= 1
    int iterations = 20;        ///< [iterations] at most this many Lloyd iterations, >= 1
    int trainingTexels = 4096;  ///< [training] texels the clusters are trained on (0 = all)
    unsigned seed = 1;          ///< [seed] random seed of the training sample and refit subsampling

    /** The options above as an option table (lpca-revised extends it). */
    static std::vector<OptionSpec> optionTable();
    /** The settings from values validated against a table that includes optionTable(). */
    static LpcaSettings fromValues(const OptionValues& values);
    /** validateOptions("lpca", options), then fromValues. */
    static LpcaSettings fromOptions(const FitOptions& options);
};

/** LpcaMaterial's members (materials/MethodMaterial.h). */
struct LpcaData {
    /** Per texel (rows bottom-up): cluster index, 0 .. clusters-1. */
    std::vector<std::uint8_t> clusterOf;
    // Held as the file and the GPU store them (materials/StoredValues.h), in their layouts, so
    // that a loaded material takes its file's size in memory.
    /** Per texel c weights, half: [component / 4][texel][component % 4] (lpcaWeightIndex). */
    StoredValues weights;
    /** Per cluster c Eigen-BRDFs, half: [cluster][view][component][light][rgb] (eigenBrdfRun). */
    StoredValues eigenBrdfs;

protected:
    int _clusters = 0, _components = 0;
    DirectionLookup _viewLookup, _lightLookup;
};

class LpcaMaterial : public MethodMaterial<LpcaMaterial, LpcaData> {
public:
    static constexpr const char* kMethod = "lpca";
    /** fromFile takes the file's 8-bit and half textures as they are stored. */
    static constexpr bool kLoadsBytes = true;
    static constexpr bool kLoadsHalves = true;

    LpcaMaterial() = default;
    LpcaMaterial(const LpcaMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop) {}
    META_Object(osgBTF, LpcaMaterial)

        /** Fits the model (LpcaFit.cpp). Options: see LpcaSettings. Fills fitInfo with "seconds",
         *  "iterations", "training_texels", "training_rms". Throws Error for invalid options. */
        static osg::ref_ptr<LpcaMaterial> fit(const BtfSource& btf, const FitOptions& options);
    /** The same with settings already read (lpca-revised's fit). */
    static osg::ref_ptr<LpcaMaterial> fit(const BtfSource& btf, const LpcaSettings& settings);
    static osg::ref_ptr<LpcaMaterial> fromFile(FittedMaterial file);

    /** A model of the given shape with zero weights and Eigen-BRDFs, e.g. for memory accounting
     *  of a configuration without fitting one. */
    static osg::ref_ptr<LpcaMaterial> ofShape(int width, int height, const DirectionSet& views,
                                              const DirectionSet& lights, int clusters,
                                              int components);

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    void evaluateMeasured(std::size_t texel, float* abrdf) const override;
    MemoryFootprint memory() const override;
    FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

    int clusters() const { return _clusters; }
    int components() const { return _components; }
    const DirectionLookup& viewLookup() const { return _viewLookup; }
    const DirectionLookup& lightLookup() const { return _lightLookup; }
    /** Values of one Eigen-BRDF: views * lights * 3. */
    std::size_t eigenBrdfSize() const { return _views.size() * _lights.size() * 3; }
    /** Where Eigen-BRDF i of cluster k holds measured view `view`: lights * 3 values from there
     *  in eigenBrdfs, [light][rgb]. */
    std::size_t eigenBrdfRun(int k, int i, std::size_t view) const {
        return ((std::size_t(k) * _views.size() + view) * std::size_t(_components) +
                std::size_t(i)) *
               _lights.size() * 3;
    }
    /** Weight i of a texel. */
    float weight(std::size_t texel, int i) const;

    /** Call after changing the arrays' shape by hand: checks sizes, rebuilds the direction
     *  lookups. */
    void finishSetup(int clusters, int components);

protected:
    ~LpcaMaterial() override = default;

private:
    friend struct LpcaFitter;
};

/** A Texture2DArray for `texture` even when its depth is 1 (createFloatTexture makes a Texture2D
 *  then, but the LPCA shaders sample arrays whatever the number of clusters or weight groups). */
osg::ref_ptr<osg::Texture> createTextureArray(const MaterialTexture& texture);

/** The per-texel textures shared by "lpca" and "lpca-revised": the cluster index (8-bit, index /
 *  255) and the weights in groups of 4 (RGBA layers, zero-padded). */
MaterialTexture lpcaClusterTexture(int width, int height,
                                   const std::vector<std::uint8_t>& clusterOf);
MaterialTexture lpcaWeightTexture(int width, int height, int components,
                                  const StoredValues& weights);
/** Reads them back; throws Error naming the file for wrong shapes or out-of-range indices. */
std::vector<std::uint8_t> lpcaClusterFromTexture(FittedMaterial& file, int clusters);
StoredValues lpcaWeightsFromTexture(FittedMaterial& file, int components);
/** Where weight i of a texel is in the weight texture's layout, [i / 4][texel][i % 4]. */
inline std::size_t lpcaWeightIndex(std::size_t texels, std::size_t texel, int i) {
    return (std::size_t(i / 4) * texels + texel) * 4 + std::size_t(i % 4);
}
/** Values of the weight texture of `components` weights per texel (zero-padded to groups of 4). */
inline std::size_t lpcaWeightCount(std::size_t texels, int components) {
    return texels * 4 * std::size_t((components + 3) / 4);
}

/** LPCA's per-vertex environment data are g itself (lights x RGB; g: the environment projected
 *  onto the measured light directions, materials/EnvironmentLighting.h): folding into every
 *  cluster's Eigen-BRDFs would store clusters x components x views RGB values per vertex (20 736
 *  for 32 x 8 x 81, 256 times g's 81), and a triangle spans texels of many clusters, so the
 *  fragment folds g into its own cluster's Eigen-BRDFs (evaluateFoldedLpca; g blended across the
 *  triangle first, which equals blending folded data because folding is linear). */
std::vector<float> foldLpca(const LpcaMaterial& material, const std::vector<glm::vec3>& g);

/** sum over the view's neighbours j of w_j sum_q alpha_q(x) sum_i g_i E_{q,k(x)}(j, i): the
 *  lpca_environment.frag loops. */
glm::vec3 evaluateFoldedLpca(const LpcaMaterial& material, const std::vector<float>& folded, int x,
                             int y, const glm::vec3& view);

}  // namespace osgBTF
