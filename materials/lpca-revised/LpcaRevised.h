// osgBTF method "lpca-revised": LPCA rendered as in Schneider 2004 section 6 (Schneider). The LPCA
// model's Eigen-BRDFs are resampled over the elevated concentric map (ConcentricMap.h) onto a
// regular grid of n samples per parameter (s_v, t_v, s_l, t_l), texel centres at (j + 0.5) / n,
// each sample interpolated in the measured data with the exact Delaunay weights of its view and
// light. The grids of all Eigen-BRDFs live in one linearly filtered 3D texture:
//
//   x = cluster * n + s_v,  y = component * n + t_v,  z = t_l * n + s_l   (texel units)
//
// so the hardware interpolates (s_v, t_v, s_l) and the shader interpolates t_l by hand: per
// component two 3D fetches and one lerp (Schneider 2004's z1, z2, w). Coordinates are clamped to
// half a texel inside their n x n x n block, so filtering never mixes clusters, components or t_l
// slabs.
//
//   BTF(x, v, l) ~ sum_{i<c} alpha_i(x) [(1 - w) S(s_v, t_v, z1) + w S(s_v, t_v, z2)]
//
// Schneider 2004's two cube maps (direction -> (s_v, t_v) and -> (z1, z2, w)) are computed in the
// shader instead: Omega^-1 is a handful of ALU operations and an atan, it is exact (a cube map
// quantises the direction to its resolution), and the CPU evaluator then computes the same
// numbers, so GPU == CPU holds to float rounding.
//
// Storage "half" (default): grid values half. Storage "unorm8" (Schneider 2004's GeForce FX 3D
// textures): every Eigen-BRDF grid is quantised to 8 bits as q = (E / s + 1) / 2 with its own
// scale s = max |E|; E = 2 s q - s is folded into the texel's weights: alpha'_i = 2 s_i alpha_i
// and one extra per-texel offset b = -sum_i s_i alpha_i, so the shader sums alpha'_i q_i + b.
#pragma once

#include <cstdint>
#include <vector>

#include <glm/vec2.hpp>

#include "materials/MethodMaterial.h"
#include "materials/MethodOptions.h"
#include "materials/lpca/Lpca.h"

namespace osgBTF {

/** LpcaRevisedMaterial's members (materials/MethodMaterial.h). */
struct LpcaRevisedData {
    std::vector<std::uint8_t> clusterOf;  ///< per texel
    // Held as the file and the GPU store them (materials/StoredValues.h).
    /** Per texel weightsPerTexel() values, half, in lpca's weight layout (lpcaWeightIndex). */
    StoredValues weights;
    /** The 3D texture, [z][y][x][rgb]; half, or 8-bit for storage=unorm8. */
    StoredValues grid;

protected:
    int _clusters = 0, _components = 0, _resolution = 0;
    bool _eightBit = false;
    std::vector<glm::vec2> _viewParams, _lightParams;  ///< Omega^-1 of the measured directions
};

class LpcaRevisedMaterial : public MethodMaterial<LpcaRevisedMaterial, LpcaRevisedData> {
public:
    static constexpr const char* kMethod = "lpca-revised";
    /** fromFile takes the file's 8-bit and half textures as they are stored. */
    static constexpr bool kLoadsBytes = true;
    static constexpr bool kLoadsHalves = true;

    LpcaRevisedMaterial() = default;
    LpcaRevisedMaterial(const LpcaRevisedMaterial& other,
                        const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop) {}
    META_Object(osgBTF, LpcaRevisedMaterial)

        /** Fits LPCA (options clusters, components, iterations, training, seed as "lpca") and
         *  resamples it; extra options: resolution (grid samples per parameter, default 16) and
         *  storage (half or unorm8). Throws Error "lpca-revised: ..." for invalid options. */
        static osg::ref_ptr<LpcaRevisedMaterial> fit(const BtfSource& btf,
                                                     const FitOptions& options);
    /** Resamples a fitted LPCA model. */
    static osg::ref_ptr<LpcaRevisedMaterial> fromLpca(const LpcaMaterial& lpca, int resolution,
                                                      bool eightBit);
    static osg::ref_ptr<LpcaRevisedMaterial> fromFile(FittedMaterial file);

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    void evaluateMeasured(std::size_t texel, float* abrdf) const override;
    MemoryFootprint memory() const override;
    FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

    int clusters() const { return _clusters; }
    int components() const { return _components; }
    int resolution() const { return _resolution; }
    bool eightBit() const { return _eightBit; }
    /** Weights per texel: c, plus the offset b with unorm8 storage. */
    int weightsPerTexel() const { return _components + (_eightBit ? 1 : 0); }
    /** Weight i (0 .. weightsPerTexel() - 1) of a texel. */
    float weight(std::size_t texel, int i) const {
        return weights[lpcaWeightIndex(texelCount(), texel, i)];
    }
    /** Size of the grid texture: (K n) x (c n) x (n n). */
    int gridWidth() const { return _clusters * _resolution; }
    int gridHeight() const { return _components * _resolution; }
    int gridDepth() const { return _resolution * _resolution; }

protected:
    ~LpcaRevisedMaterial() override = default;

private:
    void finishSetup();
    /** Hardware-style trilinear filtering of the grid at texel-unit coordinates. */
    glm::vec3 trilinear(float x, float y, float z) const;
    glm::vec3 evaluateAt(std::size_t texel, const glm::vec2& sv, const glm::vec2& sl) const;
};

}  // namespace osgBTF
