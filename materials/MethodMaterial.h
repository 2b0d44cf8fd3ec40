// osgBTF: what every method's material class has in common, written once: copying (META_Object's
// clone()), assigning in place (assignFrom: osg::Object forbids operator=, and the osgDB
// serializers fill an object OSG created), its method's name, and its registration.
//
// Written by hand, the copy constructor and assignFrom each list every member, and a member added
// to the class but left out of one list is silently dropped by copies. Here the members live in a
// plain struct whose copy and assignment the compiler generates, so there is no list to forget a
// member in; the name is one constant of the class, read by methodName() and the registration.
#pragma once

#include <string>
#include <type_traits>
#include <utility>

#include <osg/CopyOp>
#include <osg/Object>

#include "materials/Material.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

/** Base of a method's material class Self (CRTP), e.g.
 *
 *    struct LambertData {
 *        std::vector<float> albedo;
 *    };
 *    class LambertMaterial : public MethodMaterial<LambertMaterial, LambertData> {
 *    public:
 *        static constexpr const char* kMethod = "lambert";
 *        LambertMaterial() = default;
 *        LambertMaterial(const LambertMaterial& other,
 *                        const osg::CopyOp& copyop = osg::CopyOp::SHALLOW_COPY)
 *            : MethodMaterial(other, copyop) {}
 *        META_Object(osgBTF, LambertMaterial)
 *        ...
 *
 *  Data holds all of Self's per-material members, public or protected (Self's code names them as
 *  its own); copies and assignFrom copy them as the compiler does. A member that must not be
 *  copied so (a cache, a mutex) belongs in Self, whose constructor and an assignFrom override
 *  then say what happens to it. Self keeps the one-line constructor above because META_Object's
 *  clone() calls Self(*this, copyop) and C++ does not inherit it as a copy constructor.
 *
 *  Base is Material, or a class between them holding data that several methods share
 *  (materials/laf/LobeMaterial.h): such a class copies its data in its own copy constructor and
 *  assigns it in its own assignCommon<T>, which hides Material's: assignFrom calls that one. */
template <class Self, class Data, class Base = Material>
class MethodMaterial : public Base, public Data {
public:
    std::string methodName() const override { return Self::kMethod; }

    void assignFrom(const Material& other) override {
        const Self& same = this->template assignCommon<Self>(other);
        static_cast<Data&>(*this) = same;
    }

protected:
    MethodMaterial() = default;
    MethodMaterial(const MethodMaterial& other, const osg::CopyOp& copyop)
        : Base(other, copyop), Data(other) {}
    ~MethodMaterial() override = default;
};

/** Whether M::fromFile takes 8-bit textures in MaterialTexture::bytes: M declares
 *  `static constexpr bool kLoadsBytes = true;` (otherwise they come as values in `data`). */
template <class M, class = void>
struct LoadsBytes : std::false_type {};
template <class M>
struct LoadsBytes<M, std::void_t<decltype(M::kLoadsBytes)>> : std::bool_constant<M::kLoadsBytes> {};
/** The same for half textures in MaterialTexture::halves (`kLoadsHalves`). */
template <class M, class = void>
struct LoadsHalves : std::false_type {};
template <class M>
struct LoadsHalves<M, std::void_t<decltype(M::kLoadsHalves)>>
    : std::bool_constant<M::kLoadsHalves> {};

/** registerMethod for material class M: the registry name is M::kMethod, the loader
 *  M::fromFile(FittedMaterial) (or const FittedMaterial&), and createInstance makes an M, so
 *  that a method states its name and class once; `info` brings the rest. */
template <class M>
bool registerMethodClass(MethodInfo info) {
    info.name = M::kMethod;
    info.compactTextures = {LoadsBytes<M>::value, LoadsHalves<M>::value};
    info.load = [](FittedMaterial&& file) -> osg::ref_ptr<Material> {
        for (MaterialTexture& texture : file.textures)
            if ((!LoadsBytes<M>::value && !texture.bytes.empty()) ||
                (!LoadsHalves<M>::value && !texture.halves.empty()))
                texture.unpack();
        return M::fromFile(std::move(file));
    };
    info.createInstance = []() -> osg::Object* { return new M; };
    return registerMethod(std::move(info));
}

/** registerFitter for material class M: its static M::fit(const BtfSource&, const FitOptions&)
 *  under M::kMethod. Only a method's <Name>Fit.cpp (libosgBTFFit) calls it: instantiating it
 *  references M::fit, which the render library must not. */
template <class M>
bool registerFitterClass() {
    return registerFitter(
        M::kMethod, [](const BtfSource& btf, const FitOptions& options) -> osg::ref_ptr<Material> {
            return M::fit(btf, options);
        });
}

}  // namespace osgBTF
