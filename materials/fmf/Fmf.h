// osgBTF method "fmf": the full-matrix factorisation B = U * SxV^T (Schwartz et al. 2013 section 3;
// the UBO2014 ".btf" files store exactly this, see core/FactoredBtf.h and formats.md section 2).
//
//   BTF(x, v, l) ~ decode( sum_{v' in N(v), l' in N(l)} w_v' w_l' U[(v', l'), c] . SxV[x] ) / cos
//
// U holds the Eigen-ABRDFs (one row per measured (view, light[, channel])), SxV the
// Eigen-Textures with the singular values folded in (one row per texel). N(v), N(l) are the (up
// to) 3 measured directions of the Delaunay interpolation and w their barycentric weights, so 9
// (view, light) combinations of U rows are blended (Schwartz et al. 2013 blends U, not decoded
// values), dotted with the texel's SxV row, THEN the colour model (DFMF) or exp (FMF with
// dynamic-range reduction) is applied once, THEN the division by the query light's cos(theta) when
// the data include it. The material holds a FactoredBtf and renders every variant it supports (DFMF
// with per-channel ranks and colour models 0/1/3/4/11, FMF with or without DRR, the cosine flag) as
// stored.
//
// GPU layout (both RGBA, half or float as the storage option says; components in groups of 4):
//   U:   2D array texture, layer = measured view, texel (group g, light * 3 + channel): components
//        4g..4g+3 of that row (DFMF: channel c's own factor; zero beyond its rank).
//   SxV: 2D array texture of width x height texels (y from the bottom), one layer per group of 4
//        components; DFMF channels follow each other (channel c starts at layer layerOffset(c)).
#pragma once

#include <array>
#include <memory>
#include <vector>

#include "core/FactoredBtf.h"
#include "materials/DirectionLookup.h"
#include "materials/MethodMaterial.h"
#include "materials/MethodOptions.h"

namespace osgBTF {

/** The method's registry name: what a BSVTF tile set (streaming/) is a material of. */
inline constexpr char kFmfMethodName[] = "fmf";
/** Parameter "model" of a file whose factors are FactorModel::Fmf ("dfmf": Dfmf). */
inline constexpr char kFmfPlainModel[] = "fmf";

/** FmfMaterial's members (materials/MethodMaterial.h). */
struct FmfData {
protected:
    /** Shared, never changed once set: the GPU textures upload from U and SxV below
     *  (createStoredTextureArray), so the factors are held once, by the material and its
     *  textures together, and copies of the material share them. */
    std::shared_ptr<const FactoredBtf> _factors = std::make_shared<const FactoredBtf>();
    /** SxV, the bulk (a row per texel), as the GPU gets it: the "sxv" texture (sxvShape()), in
     *  `halves` under half storage (a full-size UBO2014 file's 183 MiB of floats are 92), in
     *  `data` under float storage; the factors' SxV matrices stay empty (0 rows). A file's
     *  texture is taken as it is: loading holds it once. Shared like _factors. */
    std::shared_ptr<const MaterialTexture> _sxv = std::make_shared<const MaterialTexture>();
    /** U the same way: the "u" texture (uShape(): a layer per view, a row per (light, channel),
     *  the components in groups of 4, zero beyond a factor's rank), halves or floats as stored;
     *  the factors' U matrices stay empty (0 rows). A full-size UBO2014 file's 27 MiB of floats
     *  are 14 as halves. Shared like _factors. */
    std::shared_ptr<const MaterialTexture> _u = std::make_shared<const MaterialTexture>();
    MaterialTexture::PixelKind _storage = MaterialTexture::Half;
    DirectionLookup _viewLookup, _lightLookup;
};

class FmfMaterial : public MethodMaterial<FmfMaterial, FmfData> {
public:
    static constexpr const char* kMethod = kFmfMethodName;

    FmfMaterial() = default;
    FmfMaterial(const FmfMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop) {}
    META_Object(osgBTF, FmfMaterial)

        /** Renders `factors` as they are (no refit, no decode of the measured data). Half storage
         *  rounds U and SxV to half here, so that the CPU evaluator uses exactly what the GPU gets.
         *  Throws Error "<source>: ..." for factors that fail FactoredBtf::validate(), a layout
         *  beyond the GPU's texture limits, or (half) a factor value beyond half's range.
         *  sourceFile stays empty: a caller that read the factors from a file sets it. */
        static osg::ref_ptr<FmfMaterial> fromFactors(
            FactoredBtf factors, MaterialTexture::PixelKind storage = MaterialTexture::Half);

    /** Options: components (default 32), storage (half | float, default half). Truncated SVD
     *  of the (view, light, channel) x texel matrix, blockwise against the BTF's own storage.
     *  Throws Error for an empty BTF, invalid options, or components above min(rows, texels). */
    static osg::ref_ptr<FmfMaterial> fit(const BtfSource& btf, const FitOptions& options);
    /** Takes the file's "sxv" texture as it is (half textures as halves: kLoadsHalves). */
    static osg::ref_ptr<FmfMaterial> fromFile(FittedMaterial file);
    /** Sets factors read with their SxV into `sxv` (FactorHooks::receiver: SxV matrices of 0
     *  rows, `sxv` in sxvShape's layout), checked as fromFactors checks them. */
    void setFactorsAndSxv(FactoredBtf factors, MaterialTexture sxv);
    static constexpr bool kLoadsHalves = true;

    /** The factors as rendered (half storage: the rounded values): their description and S.
     *  Each factor's U and SxV matrices are empty, 0 rows by its components (the material keeps
     *  them as the GPU textures): uRow() and sxvRow() read them, completeFactors() gives
     *  everything. */
    const FactoredBtf& factors() const { return *_factors; }
    /** SxV as kept: the GPU's texture (sxvTexture()'s layout), halves or floats as stored. */
    const MaterialTexture& sxv() const { return *_sxv; }
    /** U as kept: the GPU's texture (uShape()'s layout), halves or floats as stored; the row of
     *  (image, channel c) starts at value (image * 3 + c) * uRowValues(). */
    const MaterialTexture& u() const { return *_u; }
    std::size_t uRowValues() const { return std::size_t(_u->width) * 4; }
    /** U's row for measured image `image` (view * lights + light) and colour channel c as floats:
     *  components(c) values (Fmf: row image * 3 + c of the factor; Dfmf: row image of factor c). */
    void uRow(std::size_t image, int channel, float* out) const;
    /** A copy of the factors with SxV (as floats), e.g. to write them or fit from them. */
    FactoredBtf completeFactors() const;
    /** Factor f's SxV row `row` (FactoredBtf::factorRow) as floats: components(f) values. */
    void sxvRow(std::size_t factor, std::size_t row, float* out) const;
    MaterialTexture::PixelKind storage() const { return _storage; }

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    void evaluateMeasured(std::size_t texel, float* abrdf) const override;
    MemoryFootprint memory() const override;
    FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

    /** Meseth et al. 2003 Table 2 counts per-texel storage: SxV fully, U (shared by all texels)
     * divided by the texel count; uBytes is U's whole size on the GPU. */
    struct MemoryBreakdown {
        double perTexelValues = 0, perTexelBytes = 0;  ///< SxV
        double sharedValues = 0, sharedBytes = 0;      ///< U / texel count
        std::uint64_t uBytes = 0, sxvBytes = 0;
    };
    MemoryBreakdown memoryBreakdown() const;

    const DirectionLookup& viewLookup() const { return _viewLookup; }
    const DirectionLookup& lightLookup() const { return _lightLookup; }

    /** Groups of 4 components of channel c's factor (Fmf: the one factor's for every c). */
    int groups(int channel) const;
    /** First SxV layer of channel c (Fmf: 0 for every c). */
    int layerOffset(int channel) const;
    /** The textures as the GPU and the file get them (built on demand: the material keeps only
     *  the factors; the GPU gets them layer by layer, createStateSet). */
    MaterialTexture uTexture() const;
    MaterialTexture sxvTexture() const;

protected:
    // Its filtered evaluation is its snapshot's (evaluateLinear, finishLinear).
    friend class StreamedFmfMaterial;
    ~FmfMaterial() override = default;
    /** The three factor sums, before colour decoding (and exp) and the cosine division. */
    /** One row: the interpolated U rows blended once for the row, then a dot product with each
     *  texel's SxV (evaluate's operations in its order). */
    void evaluateRow(int x0, int y, int count, const glm::vec3& view, const glm::vec3& light,
                     glm::vec3* out) const override;
    glm::vec3 evaluateLinear(int x, int y, const glm::vec3& view,
                             const glm::vec3& light) const override;
    glm::vec3 finishLinear(const glm::vec3& linear, const glm::vec3& view,
                           const glm::vec3& light) const override;

private:
    /** The textures' sizes and storage (no data). */
    MaterialTexture uShape() const;
    MaterialTexture sxvShape() const;
    /** Sets the factors after checks and rounding, SxV moved into the texture. */
    void setFactors(FactoredBtf factors, MaterialTexture::PixelKind storage);
    /** Sets factors whose U and SxV matrices are empty and the textures that hold them (checked
     *  by the caller); prepares the direction lookups. */
    void adopt(FactoredBtf factors, MaterialTexture u, MaterialTexture sxv);
    /** Index of texel (x, y) (y from the bottom) in the SxV texture's layers. */
    std::size_t sxvTexel(int x, int y) const {
        return std::size_t(y) * std::size_t(_width) + std::size_t(x);
    }
    /** The up to 9 (image, weight) combinations for a query view and light. The one place that
     *  knows how directions are interpolated (DirectionLookup: exact, as the shader). */
    int directionCombinations(const glm::vec3& view, const glm::vec3& light,
                              std::array<std::size_t, 9>& images,
                              std::array<float, 9>& weights) const;
    /** The three factor sums of texel row `row` for U rows blended over the combinations. */
    void factorSums(std::size_t row, const std::size_t* images, const float* weights, int count,
                    float sums[3]) const;
};

/** Whether fmf's factors render linearly in the light weights (model Fmf without dynamic-range
 *  reduction; the cosine flag is a per-light factor and folds into g): whether the material's
 *  environment lighting folds (materials/EnvironmentState.h). */
bool fmfFoldable(const FmfMaterial& material);

/** FMF environment folding for one vertex (U folded per view, channel by channel; g: the
 *  environment projected onto the measured light directions, materials/EnvironmentLighting.h):
 *  per measured view j and component q, u*_jq[c] = sum_i g_i[c] s_i U[(j, i, c), q] with s_i the
 *  cosine division at l_i (1 without the cosine flag). Layout: ((j * K) + q) * 3, K the
 *  components. Throws Error for factors that fmfFoldable rejects (the message says why). */
std::vector<float> foldFmf(const FmfMaterial& material, const std::vector<glm::vec3>& g);

/** Renders folded FMF data: sum over the view's neighbours j of w_j sum_q u*_jq SxV_q(x). */
glm::vec3 evaluateFoldedFmf(const FmfMaterial& material, const std::vector<float>& folded, int x,
                            int y, const glm::vec3& view);

}  // namespace osgBTF
