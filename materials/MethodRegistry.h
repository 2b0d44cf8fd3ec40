// osgBTF: the method registry. Each method (materials/<name>/) registers a MethodInfo from a
// static initialiser in its own .cpp (registerMethodClass, materials/MethodMaterial.h) and its
// fitter from its <Name>Fit.cpp in libosgBTFFit (registerFitterClass); the tools, the harness,
// the plugins and the serializers find methods here by name. Loading and saving any method's
// file: materials/MaterialFiles.h; its programs: materials/MethodPrograms.h.
#pragma once

#include <functional>
#include <optional>
#include <string>
#include <vector>

#include "materials/EnvironmentHooks.h"
#include "materials/FactorHooks.h"
#include "materials/ForeignFiles.h"
#include "materials/Material.h"
#include "materials/MethodOptions.h"

namespace osgBTF {

/** A compression method: everything the tools, the harness, the serializers and the tests need
 *  to know about it, so that a new method is one folder that registers one of these. */
struct MethodInfo {
    std::string name;         ///< "laf"
    std::string description;  ///< one line for --help
    /** The fit options, in the order help texts list them (see MethodOptions.h). */
    std::vector<OptionSpec> options;
    /** Fits the method. Implementations start with validateOptions(), so every caller gets the
     *  one error format; they read typed values from its result. The built-in methods' fitters
     *  live in libosgBTFFit (materials/<name>/<Name>Fit.cpp), which sets them with
     *  registerFitter when it is loaded; without it, fit throws Error "method 'X': fitting
     *  needs libosgBTFFit ...". */
    std::function<osg::ref_ptr<Material>(const BtfSource&, const FitOptions&)> fit;
    /** Makes the method's material from its file, and may take the file's textures (no copy:
     *  loading a material of gigabytes holds it once). Textures in `bytes` or `halves` are
     *  unpacked to `data` first unless the method takes them so (registerMethodClass: the
     *  method's kLoadsBytes and kLoadsHalves, which also set compactTextures). */
    std::function<osg::ref_ptr<Material>(FittedMaterial&&)> load;
    /** The textures `load` takes as stored: what loadMaterial asks loadFittedMaterial for. */
    CompactTextures compactTextures;
    /** A new empty material of the method's class (e.g. `[]() -> osg::Object* { return new
     *  LafMaterial; }`): registerMethod adds an osgDB object wrapper for that class, named by its
     *  libraryName()::className(), so .osgt/.osgb read and write the material (property
     *  FittedData: the whole FittedMaterial). */
    osg::Object* (*createInstance)() = nullptr;
    /** Static ALU/TEX count of one fragment of a fitted material's shader (harness Table 3). */
    std::function<ShaderCost(const Material&)> shaderCost;
    /** The fragment shader's source when it is not built into the library as <name>.frag (from
     *  materials/<name>/<name>.frag; a method defined outside the library's sources). An override
     *  file shaders/<name>.frag on OSG_FILE_PATH still wins, as for the built-in shaders. */
    std::string fragmentShader;
    /** Folded environment lighting; none: the method is lit by representative lights. */
    std::optional<EnvironmentHooks> environment;
    /** The shader filters the per-texel parameters (GL's bilinear filter with wrap-around, or its
     *  own blend of them) and evaluates once (Material::TexelFilter::Parameters): for a method
     *  whose value is linear in them (up to Material::finishLinear), so that filtering the
     *  parameters blends the texels' values. False: btf_main.glsl blends four evaluations
     *  (TexelFilter::Values), which any method's shader supports unchanged. */
    bool filtersParameters = false;
    /** The shader blends the method's per-texel inputs over the texels a lookup filters (four,
     *  eight between two mip levels, each tap of a coordinate map) and evaluates the blend once
     *  (Material::TexelFilter::Inputs; btf_main.glsl's btfBlendInputs, Material::evaluateTaps on
     *  the CPU): for a method not linear in its inputs whose fit makes blended inputs decode
     *  well (neural's latents). Overrides filtersParameters. */
    bool blendsInputs = false;
    /** The baseline every comparison starts with (baselineMethod()); one method sets it. */
    bool baseline = false;
    /** A material that is a factorisation in the UBO2014 files' terms (materials/FactorHooks.h):
     *  saved as a .btf, opened from one as stored, streamed as BSVTF tiles; factorMethod()
     *  finds it. One method sets it. */
    std::optional<FactorHooks> factors;
    /** The method the .btf/.btfmaterial plugins fit when the options name none
     *  (pluginDefaultMethod()); one method sets it. */
    bool pluginDefault = false;
    /** Part of `btf compare --methods all` (false for the baseline, which is always added). */
    bool compareAll = true;
    /** Position in `--methods all` and other lists that follow the paper's order. */
    int order = 100;
    /** Options for a fit that is quick on a few texels (tests fit every method with these). */
    std::string quickFitOptions;
    /** A fit's memory beyond its input, in multiples of the input's values as floats (width x
     *  height x views x lights x 12 bytes), measured with margin: what `btf batch` budgets a
     *  job for (docs/batch.md). The default suits methods that read blocks of texels. */
    double fitWorkingSet = 0.25;
    /** At most this for a UBO2014 file fitted from its factors (block by block), in GiB: what a
     *  400 x 400 file took. */
    double fitWorkingSetFullSizeGiB = 3;
    /** And what a fit holds whatever the input's size (tables per cluster and direction), MiB. */
    double fitTablesMiB = 0;
    /** Other tools' files this method reads and writes as its materials (materials/
     *  ForeignFiles.h), found by extension by loadMaterial and saveMaterial. */
    std::vector<ForeignFileFormat> foreignFiles;
};

/** Adds a method; each method's .cpp calls it from a static initialiser. Returns true. */
bool registerMethod(MethodInfo info);
/** Sets the fit of method `name`, registered now or later (libosgBTFFit's static initialisers
 *  call it, so the render library holds no fitting code). Returns true. */
bool registerFitter(const std::string& name, decltype(MethodInfo::fit) fit);
/** Throws Error "unknown method 'X' (known: laf, slaf, ...)". */
const MethodInfo& findMethod(const std::string& name);
/** findMethod without the error: nullptr for a name no method registered. */
const MethodInfo* findMethodIfRegistered(const std::string& name);
/** The method with MethodInfo::baseline; throws Error when none is registered. */
const MethodInfo& baselineMethod();
/** The method with MethodInfo::factors; throws Error when none is registered. */
const MethodInfo& factorMethod();
/** The method with MethodInfo::pluginDefault; throws Error when none is registered. */
const MethodInfo& pluginDefaultMethod();
/** Registered method names, alphabetically. */
std::vector<std::string> methodNames();
/** Registered method names by MethodInfo::order (then name). */
std::vector<std::string> methodNamesInOrder();
/** The registered methods that have fit option `option` in their table (MethodInfo::options), by
 *  MethodInfo::order; empty when none has it. Which method an option word belongs to: the
 *  plugins' -O string and the command lines ask here instead of reading every table. */
std::vector<std::string> methodsWithOption(const std::string& option);
/** The methods with folded environment lighting (MethodInfo::environment), in order, as prose:
 *  "pca, fmf and lpca" (help texts and captions name them from here). */
std::string environmentMethodsText();

}  // namespace osgBTF
