// osgBTF BSVTF: an fmf material streamed tile by tile (Schwartz et al. 2013 sections 5-6). It
// renders at once, from what has arrived (missing Eigen-Textures and U packets count as zero), and
// sharpens as the TileStreamer that opened it brings tiles into the shared cache. Put it on a
// MaterialNode like any material; the scene needs a StreamingGroup above it for the feedback pass
// and the updates (streaming/StreamingGroup.h).
#pragma once

#include <osg/observer_ptr>

#include "materials/DirectionLookup.h"
#include "materials/MethodMaterial.h"

namespace osgBTF {

class FmfMaterial;
class TileStreamer;

/** A streamed material's members: which stream of which streamer it shows. Copies share the
 *  stream (a shallow copy). */
struct StreamedFmfData {
protected:
    osg::observer_ptr<TileStreamer> _streamer;
    int _index = -1;
    std::string _location;
    DirectionLookup _viewLookup, _lightLookup;
};

/** Not a registered method (its streamer makes it, nothing loads it by name): the base gives it
 *  copying, assignFrom and methodName(), no registration. */
class StreamedFmfMaterial : public MethodMaterial<StreamedFmfMaterial, StreamedFmfData> {
public:
    static constexpr const char* kMethod = "bsvtf";
    StreamedFmfMaterial() = default;
    StreamedFmfMaterial(const StreamedFmfMaterial& other,
                        const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
        : MethodMaterial(other, copyop) {}
    META_Object(osgBTF, StreamedFmfMaterial)
        /** The fmf material of what has arrived (snapshot()): the CPU reference of the shader. */
        glm::vec3
        evaluate(int x, int y, const glm::vec3& view, const glm::vec3& light) const override;
    void evaluateMeasured(std::size_t texel, float* abrdf) const override;
    /** This material's own GPU bytes: U and its lookup table (the tile cache is the streamer's,
     *  shared by every streamed material: TileStreamer::gpuBytes). */
    MemoryFootprint memory() const override;
    /** The snapshot's file: an fmf material of what has arrived. */
    FittedMaterial toFittedMaterial() const override;
    osg::ref_ptr<osg::StateSet> createStateSet() const override;

    /** The fmf material the shader renders now: every texel's Eigen-Texture values from the
     *  deepest resident tile over it (zeros where its data have not arrived), U with zeros for
     *  the packets still missing. Rebuilt when the stream changed. Throws Error when the
     *  streamer is gone. */
    osg::ref_ptr<FmfMaterial> snapshot() const;
    /** The CPU reference of the render at texture coordinate (u, v) and level of detail `lod`
     *  (log2 of finest texels per pixel, as GL computes it), from the tiles resident now. With
     *  padding: per group the GL_LINEAR blend at the fragment's tile's deepest resident level
     *  d, mixed with the one at d's parent level by lod - (L - d) clamped to [0, 1] (0 at level
     *  0): trilinear where d is the finer of the two levels the lod falls between
     *  (streaming/bsvtf.frag); evaluated as the snapshot's fmf material. Without padding:
     *  evaluateFiltered, the four texels' values at their deepest levels. Equals
     *  evaluateFiltered where lod <= 0 and every finest tile under the footprint is resident.
     *  Material::evaluateFiltered is not virtual: call this one on the streamed material. */
    glm::vec3 evaluateResidentFiltered(float u, float v, float lod, const glm::vec3& view,
                                       const glm::vec3& light) const;

    TileStreamer* streamer() const { return _streamer.get(); }
    int streamIndex() const { return _index; }
    /** Where the tile set comes from (a folder or a URL). */
    const std::string& location() const { return _location; }

protected:
    ~StreamedFmfMaterial() override = default;
    /** bsvtf.frag filters the Eigen-Textures in the cache from the tiles' padding, as fmf.frag
     *  filters its SxV (TexelFilter::Parameters). Tiles without padding (P = 0) leave nothing to
     *  filter from: false, so btf_main.glsl blends the four texels' values instead. */
    bool linearInParameters() const override;
    /** The snapshot's: the CPU reference of the filtered render once every finest tile is
     *  resident and magnified (elsewhere, and minified: evaluateResidentFiltered). */
    glm::vec3 evaluateLinear(int x, int y, const glm::vec3& view,
                             const glm::vec3& light) const override;
    glm::vec3 finishLinear(const glm::vec3& linear, const glm::vec3& view,
                           const glm::vec3& light) const override;

private:
    friend class TileStreamer;
};

}  // namespace osgBTF
