// osgBTF: loading and saving a fitted material of any registered method, in osgBTF's container
// (core/FittedMaterialFile.h) or in another tool's file that a method registered
// (MethodInfo::foreignFiles, materials/ForeignFiles.h).
#pragma once

#include <string>

#include <osg/ref_ptr>

#include "core/FittedMaterialFile.h"
#include "materials/ForeignFiles.h"
#include "materials/Material.h"

namespace osgBTF {

/** Saves through the fitted-material container (atomic), or as another tool's file where a method
 *  registered the extension (MethodInfo::foreignFiles; the material must be of a method it holds,
 *  else Error "PATH: a .ptm file holds a ptm material, not hsh"). Returns what the foreign format's
 *  quantisation lost (one line), empty for the container. */
std::string saveMaterial(const Material& material, const std::string& path);
/** Loads any registered method's file, or another tool's file by its registered extension;
 *  throws Error naming the file and the problem. */
osg::ref_ptr<Material> loadMaterial(const std::string& path);
/** The foreign file format registered for `path`'s extension (any case), with the name of the
 *  method that registered it; null when none. */
const ForeignFileFormat* findForeignFile(const std::string& path, std::string* method = nullptr);
/** "a ptm" or, for a format of several methods, "a hsh, ptm or rbf": what `format` holds, for
 *  messages. */
std::string writtenMethodsText(const ForeignFileFormat& format, const std::string& owner);
/** Any registered method's material from its file, which the method may take apart. */
osg::ref_ptr<Material> materialFromFile(FittedMaterial file);

}  // namespace osgBTF
