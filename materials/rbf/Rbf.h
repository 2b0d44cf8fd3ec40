// osgBTF method "rbf": the RTI field's default model, relight's type "rbf" (cnr-isti-vclab/relight,
// relight-cli's default; Ponchio, Corsini, Scopigno 2018, "A compact representation of relightable
// images for the web"), as a BTF method on the front view.
//
//   f_c(x, l) = sum_i w_i(l) * ( E_{0,c}(i) + sum_{p=1..N} a_p(x) E_{p,c}(i) )
//
// The capture's light profiles (one 3L vector per texel: the RGB values under the L measured
// lights) are reduced by one PCA shared by all texels: the mean profile E_0 and the N principal
// profiles E_p (unit vectors, largest variance first); each texel keeps its N coefficients a_p(x)
// = E_p . (profile(x) - E_0). A light l that was not measured is interpolated between the
// measured lights L_i ("nodes") with normalised Gaussian weights, as relight's lightWeightsRbf
// computes them:
//
//   g_i = exp(-|l' - L_i|^2 / sigma^2),  w_i = g_i / sum_j g_j,
//   drop every w_i <= 0.001 and renormalise the rest to sum 1,
//
// with l' = (l_x, l_y, sqrt(1 - l_x^2 - l_y^2)) (relight's light from its projection). The
// exponent is taken relative to the nearest node, exp(-(d_i - d_min) / sigma^2), which leaves every
// w_i unchanged and keeps the sum from underflowing to 0 far from every node (where relight's
// float sum gives 0 / 0).
//
// A material read from relight's type "bilinear" keeps the same equation with another
// interpolation: the nodes are an R x R grid over the octahedral map of the hemisphere, and
// w are the 4 bilinear weights of the grid cell holding l (relight's lightWeightsBilinear):
// s = |l_x| + |l_y| + |l_z|, u = ((l_x + l_y) / s + 1) / 2 (R - 1), v = ((l_y - l_x) / s + 1) / 2
// (R - 1), the cell's corner clamped to 0..R-2 (`resolution` R; 0 for rbf).
//
// Storage: the coefficients per texel as half (default) or float, three planes per RGB layer of
// a 2D array texture (plane p in layer p / 3, channel p % 3; the unused channels of the last
// layer 0); the basis table E (float RGB, (N + 1) x nodes: texel (p, i)) and the nodes (float RGB,
// nodes x 1) shared by all texels. Units: display values 0..1 (relight's 0..255 / 255).
#pragma once

#include <cstdint>
#include <utility>
#include <vector>

#include "materials/MethodMaterial.h"
#include "materials/MethodOptions.h"
#include "materials/RelightLayoutWriter.h"
#include "materials/StoredValues.h"

namespace osgBTF {

struct RelightPlanes;

/** RbfMaterial's members (materials/MethodMaterial.h). */
struct RbfData {
    /** Per-texel coefficients: [layer][y][x][3], plane p = layer p / 3, channel p % 3, rows
     *  bottom-up; half or float as stored. */
    StoredValues coefficients;
    /** Float RGB, width planes + 1, height nodes: texel (p, i) = E_p of node i (p = 0: mean). */
    MaterialTexture basis;
    /** Float RGB, width nodes, height 1: the node directions (rbf: the measured lights as given;
     *  bilinear: unused, zeros). */
    MaterialTexture nodes;

protected:
    int _planes = 0;
    float _sigma = 0.125f;
    int _resolution = 0;  ///< 0: Gaussian weights over the nodes; R: R x R octahedral grid
};

class RbfMaterial : public MethodMaterial<RbfMaterial, RbfData> {
public:
    static constexpr const char* kMethod = "rbf";
    /** fromFile takes the file's half coefficients as they are stored. */
    static constexpr bool kLoadsHalves = true;
    /** The most planes the shader holds (16 RGB layers). */
    static constexpr int kMaxPlanes = 48;
    /** The most nodes (basis rows): a texture height every GL 3.3 implementation allows. */
    static constexpr int kMaxNodes = 4096;
    /** relight's weight threshold: a normalised weight at or below it is dropped. */
    static constexpr float kThreshold = 0.001f;

    RbfMaterial() : _weightsSerial(newSerial()) {}
    RbfMaterial(const RbfMaterial& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop), _weightsSerial(newSerial()) {}
    /** MethodMaterial's, then a new weights serial (the nodes may have changed). */
    void assignFrom(const Material& other) override {
        MethodMaterial::assignFrom(other);
        _weightsSerial = newSerial();
    }
    META_Object(osgBTF, RbfMaterial)

        /** PCA of the front view's light profiles (see the file comment). Options: planes,
         *  sigma, storage. Throws Error for bad options, an empty BTF, more planes than 3 x
         *  lights or texels. Fills fitInfo: seconds, planes, sigma, storage, front-view,
         *  variance kept. */
        static osg::ref_ptr<RbfMaterial> fit(const BtfSource& btf, const FitOptions& options);
    static osg::ref_ptr<RbfMaterial> fromFile(FittedMaterial file);
    /** A zero model: `planes` coefficients per texel, `nodes` basis rows (rbf: the lights' count,
     *  node directions set by the caller through setNode; bilinear: resolution^2), the
     *  coefficients stored as `storage`. Throws Error for planes outside 1..48, nodes outside
     *  1..4096, a resolution that is neither 0 nor 2..64 or a sigma outside 1e-6..1e6 (1 /
     *  sigma^2 a finite float). */
    static osg::ref_ptr<RbfMaterial> create(int width, int height, DirectionSet views,
                                            DirectionSet lights, int planes, int nodes, float sigma,
                                            int resolution, MaterialTexture::PixelKind storage);

    glm::vec3 evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    void evaluateMeasured(std::size_t texel, float* abrdf) const override;
    MemoryFootprint memory() const override;
    FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

    int planes() const { return _planes; }
    int layers() const { return (_planes + 2) / 3; }
    int nodeCount() const { return basis.height; }
    float sigma() const { return _sigma; }
    int resolution() const { return _resolution; }
    MaterialTexture::PixelKind storage() const {
        return coefficients.kind() == StoredValues::Kind(MaterialTexture::Float)
                   ? MaterialTexture::Float
                   : MaterialTexture::Half;
    }

    /** Coefficient a_p of a texel, as stored. */
    float coefficient(std::size_t texel, int p) const {
        return coefficients[((std::size_t(p / 3) * texelCount()) + texel) * 3 + std::size_t(p % 3)];
    }
    void setCoefficient(std::size_t texel, int p, float value) {
        coefficients.set(((std::size_t(p / 3) * texelCount()) + texel) * 3 + std::size_t(p % 3),
                         value);
    }
    /** E_p of node i (p = 0: the mean), RGB. */
    glm::vec3 basisValue(int p, int node) const {
        const std::size_t at = (std::size_t(node) * std::size_t(_planes + 1) + std::size_t(p)) * 3;
        return glm::vec3(basis.data[at], basis.data[at + 1], basis.data[at + 2]);
    }
    void setBasisValue(int p, int node, const glm::vec3& value) {
        const std::size_t at = (std::size_t(node) * std::size_t(_planes + 1) + std::size_t(p)) * 3;
        for (int c = 0; c < 3; ++c) basis.data[at + std::size_t(c)] = value[c];
    }
    glm::vec3 node(int i) const {
        const std::size_t at = std::size_t(i) * 3;
        return glm::vec3(nodes.data[at], nodes.data[at + 1], nodes.data[at + 2]);
    }
    void setNode(int i, const glm::vec3& direction) {
        for (int c = 0; c < 3; ++c) nodes.data[std::size_t(i) * 3 + std::size_t(c)] = direction[c];
        _weightsSerial = newSerial();
    }

    /** The interpolation weights of a light direction: (node, weight) pairs, the weights summing
     *  to 1, in node order; the float operations of rbf.frag. */
    std::vector<std::pair<int, float>> lightWeights(const glm::vec3& light) const;
    /** The model at a texel for given weights (unclamped). */
    glm::vec3 combine(std::size_t texel, const std::vector<std::pair<int, float>>& weights) const;

protected:
    ~RbfMaterial() override = default;

private:
    /** A number no material had before: evaluate() keeps the last light's weights per thread
     *  under it, so a material freed and another made at the same address cannot reuse them.
     *  Renewed whenever the weights' inputs (nodes, sigma, resolution) change. */
    static std::uint64_t newSerial();
    std::uint64_t _weightsSerial;

    void setShape(int width, int height, DirectionSet views, DirectionSet lights, int planes,
                  int nodes, float sigma, int resolution, MaterialTexture::PixelKind storage,
                  bool allocate);
};

/** A relight folder of type rbf or bilinear (colorspace mrgb; materials/RelightFolder.h) as an rbf
 *  material: the basis dequantised as relight's Rti::load does ((b - 127) / range for the planes,
 *  the mean / 255), the planes' coefficients as RelightFolder dequantises them. */
osg::ref_ptr<RbfMaterial> rbfMaterialFromRelight(const std::string& infoPath,
                                                 const RelightPlanes& planes);

/** An rbf material as relight's layout holds it (materials/RelightLayoutWriter.h): type rbf
 *  (the nodes written as info.json's lights, sigma) or bilinear (resolution), colorspace mrgb,
 *  the coefficients as planes, the basis unquantised (the writer quantises it as relight does). */
RelightModel relightModelOfRbf(const RbfMaterial& material, const std::string& infoPath);

}  // namespace osgBTF
