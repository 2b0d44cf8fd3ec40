// osgBTF method "pca": per-view Eigen-Textures (Sattler, Sarlette, Klein 2003; Sattler et al. 2003
// section 4, Meseth et al. 2003 section 3.4, equation 6).
//
//   BTF(x, v, l) ~ sum_{v' in N(v), l' in N(l)} w_v' w_l' * sum_{k<c} alpha_k(v', l') E_{k,v'}(x)
//
// For each measured view v the images of all lights form a (3 * texels) x lights matrix M_v (one
// RGB image per column). Its best rank-c approximation (truncated SVD, Eckart-Young) gives c
// Eigen-Textures E_{k,v} (RGB images, the left singular vectors) and weights alpha_k(v, l). Seed
// 004 eq. 1 writes the reconstruction without a mean image (the text mentions an "affine
// subspace", but eq. 1 and Meseth et al. 2003 eq. 6 have none, and the 3888 values of Meseth et al.
// 2003 Table 2 = 81 x 16 x 3 leave no room for one): we follow the equations, a linear rank-c
// subspace. N(v), N(l) are the (up to) 3 measured directions of the Delaunay interpolation and w
// their exact barycentric weights (materials/DirectionLookup.h, the same on CPU and GPU).
//
// Storage (option storage): Eigen-Textures as unorm8 (the default, as Meseth et al. 2003 Table 2
// counts: 1 byte per value), half or float. For unorm8 every Eigen-Texture channel is mapped to [0,
// 1] by its own offset and range, E = offset + range * q, and both are folded into the weights
// table: the stored RGB weight of component k is alpha_k * range_k, and one extra RGB "bias" entry
// per (view, light) holds sum_k alpha_k * offset_k. After quantisation the weights alpha are
// refitted by least squares against the quantised Eigen-Textures, so they are the best for what is
// stored. The weights table is float (it is tiny and shared by all texels).
//
// GPU layout: Eigen-Textures in one 2D array texture, one layer per view, the c components tiled
// in a grid of tileColumns x tileRows (width * tileColumns <= 16384) inside the layer; weights in
// a float 2D array texture of (c + 1) x lights texels, one layer per view.
#pragma once

#include <vector>

#include "materials/DirectionLookup.h"
#include "materials/MethodMaterial.h"
#include "materials/MethodOptions.h"

namespace osgBTF {

/** The method's registry name, for code outside this folder that singles pca out. */
inline constexpr char kPcaMethodName[] = "pca";

/** PcaMaterial's members (materials/MethodMaterial.h). */
struct PcaData {
    /** Stored Eigen-Textures: q in [0, 1] for unorm8 (held as bytes, 0..255), E itself for half
     *  and float. RGB. */
    MaterialTexture eigenTextures;
    /** Float RGB weights: (components + 1) x lights per view layer; slot `components` = bias. */
    MaterialTexture weights;

protected:
    int _components = 0;
    int _tileColumns = 1;
    DirectionLookup _viewLookup, _lightLookup;
};

class PcaMaterial : public MethodMaterial<PcaMaterial, PcaData> {
public:
    static constexpr const char* kMethod = kPcaMethodName;

    PcaMaterial() = default;
    PcaMaterial(const PcaMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop) {}
    META_Object(osgBTF, PcaMaterial)

        /** Options: components (default 16), storage (unorm8 | half | float, default unorm8).
         * Throws Error for an empty BTF, unknown options, components outside 1..min(lights, 3 *
         * texels), an unknown storage, or a texel size whose tiled Eigen-Textures exceed 16384
         * texels. */
        static osg::ref_ptr<PcaMaterial> fit(const BtfSource& btf, const FitOptions& options);
    /** Takes the file's textures (8-bit Eigen-Textures as bytes, kLoadsBytes): loading holds
     *  them once. */
    static osg::ref_ptr<PcaMaterial> fromFile(FittedMaterial file);
    static constexpr bool kLoadsBytes = true;

    /** Sets size, directions, component count and storage and sizes the two textures' dimensions
     *  WITHOUT allocating their data (memory() only needs the shape; fit() allocates). */
    void setShape(int width, int height, const DirectionSet& views, const DirectionSet& lights,
                  int components, MaterialTexture::PixelKind storage);

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    void evaluateMeasured(std::size_t texel, float* abrdf) const override;
    MemoryFootprint memory() const override;
    FittedMaterial toFittedMaterial() const override;
    FittedMaterial releaseFittedMaterial() override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

    /** Meseth et al. 2003 Table 2 counts per-texel storage; the weights table is shared by all
     * texels. */
    struct MemoryBreakdown {
        double perTexelValues = 0, perTexelBytes = 0;  ///< Eigen-Textures
        double sharedValues = 0, sharedBytes = 0;      ///< weights table / texel count
    };
    MemoryBreakdown memoryBreakdown() const;

    /** The model at measured view v and light l for one texel, no interpolation. */
    glm::vec3 combination(int x, int y, std::size_t view, std::size_t light) const;

    int components() const { return _components; }
    const DirectionLookup& viewLookup() const { return _viewLookup; }
    const DirectionLookup& lightLookup() const { return _lightLookup; }
    int tileColumns() const { return _tileColumns; }

    /** Index of texel (x, y) of component k of view v in eigenTextures.data (RGB follows). */
    std::size_t eigenIndex(std::size_t view, int k, int x, int y) const {
        const std::size_t row = std::size_t(k / _tileColumns) * _height + y;
        const std::size_t col = std::size_t(k % _tileColumns) * _width + x;
        return ((view * eigenTextures.height + row) * eigenTextures.width + col) * 3;
    }
    /** Stored RGB of texel (x, y) of component k of view v, from eigenTextures' data or bytes. */
    glm::vec3 eigenTexel(std::size_t view, int k, int x, int y) const {
        const std::size_t i = eigenIndex(view, k, x, y);
        if (!eigenTextures.bytes.empty())
            return glm::vec3(eigenTextures.bytes[i], eigenTextures.bytes[i + 1],
                             eigenTextures.bytes[i + 2]) /
                   255.0f;
        return glm::vec3(eigenTextures.data[i], eigenTextures.data[i + 1],
                         eigenTextures.data[i + 2]);
    }
    /** Index of weight slot k (k == components: the bias) of (view, light) in weights.data. */
    std::size_t weightIndex(std::size_t view, std::size_t light, int k) const {
        return ((view * _lights.size() + light) * std::size_t(_components + 1) + k) * 3;
    }

protected:
    ~PcaMaterial() override = default;

private:
    void prepareLookups();
};

/** PCA environment folding for one vertex (g: the environment projected onto the measured light
 *  directions, materials/EnvironmentLighting.h): per measured view j and slot k (0..c-1 the
 *  components, c the bias of unorm8 storage), gamma*_kj = sum_i g_i alpha_k(j, i) (RGB, channel by
 *  channel). Layout: ((j * (c + 1)) + k) * 3. */
std::vector<float> foldPca(const PcaMaterial& material, const std::vector<glm::vec3>& g);

/** Renders folded PCA data: sum over the view's interpolation neighbours j of
 *  w_j (gamma*_cj + sum_k gamma*_kj E_kj(x)). What pca_environment.frag computes per vertex. */
glm::vec3 evaluateFoldedPca(const PcaMaterial& material, const std::vector<float>& folded, int x,
                            int y, const glm::vec3& view);

}  // namespace osgBTF
