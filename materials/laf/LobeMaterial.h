// osgBTF: the lobe model LAF and SLAF share, and its one fitter.
//
//   BTF(x, v, l) ~ T(x, v) * (rho_d(x) + rho_s(x) * sum_{i<k} max(C_i . (v * l), 0)^n_i) * l_z
//
// LAF (materials/laf/Laf.h) is this model with the view table T fixed at 1; SLAF
// (materials/slaf/Slaf.h) stores T per texel and measured view. The class holds what both store
// (RGB albedos as 8-bit fixed point, scalar lobes as half floats, the cosine option), evaluates the
// bracket, writes, reads and binds those textures, and fits them: the per-texel luminance fit of
// Lobes.h, the colours in closed form, SLAF's alternation with T, the storage rounding and the
// divergence guard. The lobe functions and the luminance fit itself are in Lobes.h.
// LobeMethod<Self, Data> is what the two material classes share beyond the model: creation,
// memory, file and StateSet, with hooks for what SLAF adds (its view table T).
#pragma once

#include <string>
#include <vector>

#include <glm/vec3.hpp>

#include <osg/StateSet>

#include "materials/Material.h"
#include "materials/MaterialMath.h"
#include "materials/MaterialState.h"
#include "materials/MethodMaterial.h"
#include "materials/StoredValues.h"

namespace osgBTF {

/** LobeMaterial's members, copied and assigned by the compiler (materials/MethodMaterial.h). */
struct LobeData {
    // Held as the file stores them (materials/StoredValues.h): a loaded material takes its
    // file's size in memory, and every value set is rounded as the file and the GPU hold it.
    /** RGB per texel, rows bottom-up, 8-bit fixed point. */
    StoredValues rhoD, rhoS;
    /** [lobe][y][x][Cx, Cy, Cz, n], half. */
    StoredValues lobes;

protected:
    int _lobes = 0;
    bool _cosine = true;
};

/** The Base of LafMaterial's and SlafMaterial's MethodMaterial. */
class LobeMaterial : public Material, public LobeData {
public:
    int lobeCount() const { return _lobes; }
    /** True when the bracket is multiplied by l_z (option cosine=1, the default). */
    bool cosine() const { return _cosine; }

protected:
    LobeMaterial() = default;
    LobeMaterial(const LobeMaterial& other, const osg::CopyOp& copyop)
        : Material(other, copyop), LobeData(other) {}
    ~LobeMaterial() override = default;

    /** Material's, plus the lobe data: MethodMaterial::assignFrom calls this one. */
    template <typename T>
    const T& assignCommon(const Material& other) {
        const T& same = Material::assignCommon<T>(other);
        static_cast<LobeData&>(*this) = same;
        return same;
    }
    /** Zero colours, zero lobes (n = 1), cosine on, for the current size. */
    void initLobes(int lobeCount);

    /** (rho_d + rho_s * sum of lobes) * (l_z or 1) at texel t: the whole model when T = 1. */
    glm::vec3 bracket(std::size_t t, const glm::vec3& view, const glm::vec3& light) const;

    /** Adds the parameters lobes, cosine and the textures rhoD, rhoS, lobes (in this order). */
    void writeLobes(FittedMaterial& file) const;
    /** Reads and checks the parameters lobes and cosine. */
    void readLobeParameters(const FittedMaterial& file);
    /** Reads the textures rhoD, rhoS and lobes (after readLobeParameters). */
    void readLobeTextures(FittedMaterial& file);
    /** A texture of the file that must have this material's size, `depth` and `channels`, its
     *  values taken as `kind` stores them. */
    StoredValues readTexture(FittedMaterial& file, const std::string& name, int depth, int channels,
                             MaterialTexture::PixelKind kind) const;
    /** Binds rhoD, rhoS and the lobe atlas to units 0, 1, 2 as <prefix>RhoD, <prefix>RhoS,
     *  <prefix>Lobes, and the uniforms <prefix>LobeCount and <prefix>Cosine. */
    void addLobeState(osg::StateSet& stateSet, const std::string& prefix) const;

    /** Fits every texel of `btf` into this material (created with its size and directions).
     *  `scale` null: T fixed at 1 (LAF). Otherwise T is fitted, alternating `rounds` times with
     *  the lobes, and stored there as [view][y][x][rgb] (SLAF). Sets the fit info seconds,
     *  iterations, fallbacks and lobes. */
    void fitLobes(const BtfSource& btf, int iterations, int rounds, StoredValues* scale);
};

/** The base of LafMaterial and SlafMaterial (CRTP, materials/MethodMaterial.h): create, fromFile,
 *  memory, toFittedMaterial and createStateSet, written once. Self may shadow the hooks, which do
 *  nothing here: initExtra() (create, after the lobes), checkFile(file) (fromFile, before the
 *  textures), readExtra(file) (fromFile, after the lobe textures), writeExtra(file) and
 *  addExtraState(stateSet) (after the lobes' units 0..2). */
template <class Self, class Data>
class LobeMethod : public MethodMaterial<Self, Data, LobeMaterial> {
public:
    /** fromFile takes the file's 8-bit and half textures as they are stored. */
    static constexpr bool kLoadsBytes = true;
    static constexpr bool kLoadsHalves = true;

    /** An unfitted model of the given shape (zero colours, zero lobes; SLAF: T = 1): memory
     *  accounting and tests build models without fitting. */
    static osg::ref_ptr<Self> create(int width, int height, int lobeCount,
                                     const DirectionSet& views, const DirectionSet& lights) {
        osg::ref_ptr<Self> m = new Self;
        m->setGeometry(width, height, views, lights);
        m->initLobes(lobeCount);
        m->initExtra();
        return m;
    }
    static osg::ref_ptr<Self> fromFile(FittedMaterial file) {
        osg::ref_ptr<Self> m = new Self;
        m->readCommon(file);
        m->readLobeParameters(file);
        m->checkFile(file);
        m->readLobeTextures(file);
        m->readExtra(file);
        return m;
    }

    MemoryFootprint memory() const override {
        // Counted from the textures as stored, so the numbers follow their declared storage kinds.
        return footprintOf(toFittedMaterial(), this->texelCount());
    }
    FittedMaterial toFittedMaterial() const override {
        FittedMaterial file = this->writeCommon();
        this->writeLobes(file);
        self().writeExtra(file);
        return file;
    }
    osg::ref_ptr<osg::StateSet> createStateSet() const override {
        osg::ref_ptr<osg::StateSet> stateSet = new osg::StateSet;
        addCommonState(*stateSet, *this);
        this->addLobeState(*stateSet, Self::kMethod);
        self().addExtraState(*stateSet);
        return stateSet;
    }

protected:
    LobeMethod() = default;
    LobeMethod(const LobeMethod& other, const osg::CopyOp& copyop)
        : MethodMaterial<Self, Data, LobeMaterial>(other, copyop) {}
    ~LobeMethod() override = default;

    void initExtra() {}
    void checkFile(const FittedMaterial&) const {}
    void readExtra(FittedMaterial&) {}
    void writeExtra(FittedMaterial&) const {}
    void addExtraState(osg::StateSet&) const {}

private:
    const Self& self() const { return static_cast<const Self&>(*this); }
};

}  // namespace osgBTF
