// osgBTF: what every compression method provides (the Material interface). The registry that
// lists the methods is materials/MethodRegistry.h, loading and saving any method's file
// materials/MaterialFiles.h, the per-method programs materials/MethodPrograms.h.
//
// A method (materials/<name>/) fits a Material from measured data (a BtfSource: a MeasuredBtf in
// memory or a FactoredBtf decoded block by block). The Material evaluates itself on the CPU with
// the same math as its shader (the reference for tests and error metrics), saves itself as a
// FittedMaterial file, accounts for its memory, and builds the OSG state that renders it: float
// textures and uniforms in a StateSet, with one osg::Program shared per method.
#pragma once

#include <functional>
#include <map>
#include <memory>
#include <optional>
#include <string>
#include <vector>

#include <glm/vec3.hpp>
#include <osg/Object>
#include <osg/Program>
#include <osg/StateSet>

#include "core/FittedMaterialFile.h"
#include "core/MeasuredBtf.h"
#include "core/MipPyramid.h"
#include "materials/ShaderCost.h"

namespace osgBTF {

struct FilterTaps;  // materials/BilinearTaps.h

/** Storage per texel as Meseth et al. 2003 Table 2 counts it: values and bytes, derived from the
 * model's actual arrays (per-texel arrays count fully; shared tables are divided by the texel
 * count). */
struct MemoryFootprint {
    double valuesPerTexel = 0;
    double bytesPerTexel = 0;
    std::uint64_t totalBytes = 0;
    /** Of totalBytes, the tables shared by all texels (e.g. fmf's U), when a method reports them
     *  (btf compare prints them under Table 2); 0: none or not reported. */
    std::uint64_t sharedBytes = 0;
};

class Material : public osg::Object {
public:
    Material() = default;
    Material(const Material& other, const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY);

    /** Registry name of the method, e.g. "laf". */
    virtual std::string methodName() const = 0;

    int width() const { return _width; }
    int height() const { return _height; }
    std::size_t texelCount() const { return std::size_t(_width) * std::size_t(_height); }
    const DirectionSet& views() const { return _views; }
    const DirectionSet& lights() const { return _lights; }

    /** CPU reference, the same math as the fragment shader: the BTF value of texel (x, y) (y
     *  counted from the bottom) for local view and light directions (unit vectors pointing away
     *  from the surface; the cosine term is part of the value). */
    virtual glm::vec3 evaluate(int x, int y, const glm::vec3& view,
                               const glm::vec3& light) const = 0;

    /** evaluate() for texels (x0 .. x0 + count - 1, y) at one view and light, into out[0 ..
     *  count - 1]: what an image needs. The default calls evaluate(); a method whose per-query
     *  work does not depend on the texel (fmf's interpolated U rows) does it once a row. Equal to
     *  evaluate(), bit for bit. */
    virtual void evaluateRow(int x0, int y, int count, const glm::vec3& view,
                             const glm::vec3& light, glm::vec3* out) const {
        for (int i = 0; i < count; ++i) out[i] = evaluate(x0 + i, y, view, light);
    }

    /** The model at every measured (view, light) pair, in MeasuredBtf::abrdf's layout. The default
     *  calls evaluate() with the measured directions; methods that store per-measured-direction
     *  data override it to skip interpolation. */
    virtual void evaluateMeasured(std::size_t texel, float* abrdf) const;

    /** A material fitted on a mip-map atlas (core/MipPyramid.h; `btf fit --mipmap`): its texels
     *  are the atlas's, every level's averaged data. Empty (not mip-mapped) otherwise. */
    const MipLayout& mipLayout() const { return _mipLayout; }
    /** Marks this material as fitted on `layout`'s atlas; throws Error when the atlas is not
     *  this material's texel size. */
    void setMipLayout(const MipLayout& layout);
    /** CPU reference of the shader's texture lookup at texture coordinate uv and level of detail
     *  `lod` (log2 of base texels per pixel, as GL computes it), what GL_LINEAR (magnified) and
     *  GL_LINEAR_MIPMAP_LINEAR (minified) give a texture: the bilinear blend, with wrap-around,
     *  of the values of the four texels around uv (centres at (i + 0.5) / size, weights
     *  frac(uv size - 0.5)). A mip-mapped material blends levels floor(lod) and floor(lod) + 1
     *  (clamped to its levels; NaN or negative lod: level 0) by lod - floor(lod), each level
     *  filtered bilinearly and wrapped inside its own rectangle of the atlas. texelFilter() says
     *  how the four texels are blended; both ways give the same filtered BTF. */
    glm::vec3 evaluateFiltered(float u, float v, float lod, const glm::vec3& view,
                               const glm::vec3& light) const;
    /** How the shader and evaluateFiltered blend the four texels around a texture coordinate. */
    enum class TexelFilter {
        /** The per-texel parameters are filtered (GL_LINEAR and GL_REPEAT on their textures, or
         *  the method's own blend of them) and the method evaluates the blend once: the value is
         *  linear in them up to finishLinear. One evaluation per light. */
        Parameters,
        /** btf_main.glsl evaluates the four texels (eight between two mip levels) and blends the
         *  values (uniform osgBTF_blendTexels): works for any method, four evaluations per light
         *  where the texel weights are not 0 or 1. */
        Values,
        /** The method blends its per-texel inputs over the same four (eight) texels and weights
         *  itself and evaluates the blend once (uniform osgBTF_blendInputs; evaluateTaps): for a
         *  method whose value is not linear in its inputs but which is fitted so that blended
         *  inputs decode well (neural's latents, MethodInfo::blendsInputs). One evaluation per
         *  light, also between mip levels and through a coordinate map. */
        Inputs,
    };
    /** Inputs when the method sets MethodInfo::blendsInputs; Parameters when it sets
     *  MethodInfo::filtersParameters, the material has no mip levels (they sit in an atlas, where
     *  the hardware filter cannot wrap inside a level) and linearInParameters(); Values
     *  otherwise. */
    TexelFilter texelFilter() const;
    bool filtersParameters() const { return texelFilter() == TexelFilter::Parameters; }
    /** The value a filtered lookup over `taps` shows (their texels' values blended by their
     *  weights, in the taps' order): evaluateFiltered's and evaluateThroughMap's last step. A
     *  method of TexelFilter::Inputs overrides it to blend its inputs and evaluate once, as its
     *  shader does. */
    virtual glm::vec3 evaluateTaps(const FilterTaps& taps, const glm::vec3& view,
                                   const glm::vec3& light) const;

    virtual MemoryFootprint memory() const = 0;
    virtual FittedMaterial toFittedMaterial() const = 0;
    /** toFittedMaterial for a material's last use (saving a fit): a method whose arrays can be
     *  gigabytes (PCA of a full-size UBO2014 file) moves them out instead of copying them, and
     *  the material is empty afterwards. The default copies. */
    virtual FittedMaterial releaseFittedMaterial() { return toFittedMaterial(); }

    /** Textures and uniforms of this material plus the method's shared program. */
    virtual osg::ref_ptr<osg::StateSet> createStateSet() const = 0;
    /** The `#define`s (a name, or "NAME VALUE") the method's program is compiled with for this
     *  material: a shape the material keeps for its life (ptm's colour and view models, hsh's
     *  order) as a compile-time choice instead of a uniform branch. A software rasterizer
     *  (llvmpipe) runs both sides of a branch and the whole of a loop whatever a uniform says, so
     *  code a material never takes still costs its pass (materials/ptm/README.md, "Pass cost").
     *  Every distinct list is a program of its own (MethodPrograms.h); the default: none. */
    virtual std::vector<std::string> shaderDefines() const { return {}; }

    /** createStateSet(), built once per material and shared by everything that renders it (every
     *  osgBTF::MaterialNode using this material): textures are uploaded once per context. Safe to
     *  call from several cull threads. */
    osg::StateSet* sharedStateSet() const;

    /** Makes this material a copy of `other`, which must be of the same method (else throws
     *  Error "cannot assign a X material to a Y material"). What the osgDB serializers need to
     *  fill an object in place: osg::Object forbids operator=. */
    virtual void assignFrom(const Material& other) = 0;

    /** Free-form facts from fitting (time, iterations, error), saved as parameters "fit.*". */
    std::map<std::string, std::string> fitInfo;

    /** The file this material was loaded from (set by loadMaterial), empty for a material fitted
     *  in memory. Lets a scene that holds the material refer to it by file name. */
    std::string sourceFile;

protected:
    ~Material() override = default;  // reference counted, like every osg::Object
    /** False for a material of a method that sets MethodInfo::filtersParameters whose value is
     *  nevertheless not linear in its per-texel parameters (e.g. ptm's luminance times colour, a
     *  product of two of them): filtering the parameters would then not blend the texels'
     *  values, so it takes TexelFilter::Values. */
    virtual bool linearInParameters() const { return true; }
    /** evaluate() = finishLinear(evaluateLinear()), split where the value stops being linear in
     *  the texel's parameters (ptm's clamp at 0, fmf's colour decoding and exp): the hardware
     *  filter blends the parameters, which blends evaluateLinear's values, and the shader then
     *  applies the rest to the blend. The defaults: evaluate() is linear all the way. */
    virtual glm::vec3 evaluateLinear(int x, int y, const glm::vec3& view,
                                     const glm::vec3& light) const {
        return evaluate(x, y, view, light);
    }
    virtual glm::vec3 finishLinear(const glm::vec3& linear, const glm::vec3& /*view*/,
                                   const glm::vec3& /*light*/) const {
        return linear;
    }
    void setGeometry(int width, int height, DirectionSet views, DirectionSet lights);
    /** Copies width/height/directions/fit info from a file, checking the method name. */
    void readCommon(const FittedMaterial& file);
    /** A FittedMaterial with method, directions, size and fit info filled in. */
    FittedMaterial writeCommon() const;
    /** assignFrom's shared part: checks the method, copies size, directions, fit info and source
     *  file, drops the cached StateSet; returns `other` as the caller's class. */
    template <typename T>
    const T& assignCommon(const Material& other) {
        const T* same = dynamic_cast<const T*>(&other);
        if (!same) throwMethodMismatch(other);
        _width = other._width;
        _height = other._height;
        _views = other._views;
        _lights = other._lights;
        fitInfo = other.fitInfo;
        sourceFile = other.sourceFile;
        _mipLayout = other._mipLayout;
        _sharedStateSet = nullptr;
        return *same;
    }

    int _width = 0, _height = 0;
    DirectionSet _views, _lights;

private:
    MipLayout _mipLayout;
    [[noreturn]] void throwMethodMismatch(const Material& other) const;
    mutable osg::ref_ptr<osg::StateSet> _sharedStateSet;
};

}  // namespace osgBTF
