// osgBTF: files of other tools that a method reads and writes as its materials (the RTI field's
// .ptm for `ptm`, .rti for `hsh`, relight's info.json folder for ptm, hsh and rbf), registered with
// the method (MethodInfo::foreignFiles) so that loadMaterial, saveMaterial, `btf info`, `btf fit
// -o` and the osgDB plugins find them by extension.
#pragma once

#include <functional>
#include <string>
#include <vector>

#include <osg/ref_ptr>

#include "core/Directions.h"

namespace osgBTF {

class Material;

struct ForeignFileFormat {
    /** How the file's name ends, lower case: an extension with its dot (".ptm"), or a whole file
     *  name ("info.json": relight's folder, named by its info file) that the name ends with. */
    std::string extension;
    std::string description;  ///< one line for help texts
    /** The file as a material of the method. Throws Error "PATH: problem". */
    std::function<osg::ref_ptr<Material>(const std::string& path)> read;
    /** Writes a material of the method; returns one line on what the format's quantisation
     *  lost. Throws Error "PATH: problem" for a material the format cannot hold. Empty for a
     *  format osgBTF only reads (saveMaterial and `btf fit -o` refuse it). */
    std::function<std::string(const Material&, const std::string& path)> write;
    /** For a format that holds materials of several methods (relight's layout): those methods
     *  (saveMaterial and `btf fit -o` accept them). Empty: only the method that registered it. */
    std::function<std::vector<std::string>()> methods;
    /** Whether `write` takes a material of `method`. */
    bool writes(const std::string& owner, const std::string& method) const;
    /** The file's header as `btf info` prints it (lines). */
    std::function<std::string(const std::string& path)> info;
};

/** The lights a file that records none gets (evaluateMeasured needs a set): the 81 Bonn lights,
 *  named as nominal. */
DirectionSet nominalFileLights();

/** A float as text that reads back as the same float. */
std::string floatText(float value);

}  // namespace osgBTF
