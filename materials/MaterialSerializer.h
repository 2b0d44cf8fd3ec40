// osgBTF: materials in .osgt / .osgb (osgDB serializers).
//
// A material travels as its whole FittedMaterial (method, parameters, direction sets, textures
// with their float bits as hex text, so .osgt is exact too). Every registered method's class gets
// an object wrapper (associates "osg::Object osgBTF::<Class>", one property FittedData) from
// registerMethod; MaterialNode's EmbeddedMaterial (scene/Serializers.cpp) uses the same format.
#pragma once

#include <string>

#include <osgDB/InputStream>
#include <osgDB/OutputStream>

#include "core/FittedMaterialFile.h"
#include "materials/MethodRegistry.h"

namespace osgBTF {

struct MethodInfo;

/** is.readWrappedString(text), except that in an ASCII stream (.osgt) a string the stream ends
 *  before (truncated or damaged input) is refused first: OSG 3.6.5's own reader
 *  (AsciiInputIterator::readWrappedString in osgdb_osg) never returns there (fuzz/README.md).
 *  Returns false, with the stream's exception set, on a refusal or a stream error. For
 *  serializers: only right after InputStream matched the property name (nothing pre-read). */
bool readWrappedStringChecked(osgDB::InputStream& is, std::string& text);

/** Reads what writeFittedMaterial wrote. Returns false on a stream error; throws Error for data
 *  that read but make no material. */
bool readFittedMaterial(osgDB::InputStream& is, FittedMaterial& fitted);
/** Writes a whole FittedMaterial. */
bool writeFittedMaterial(osgDB::OutputStream& os, const FittedMaterial& fitted);

/** Adds (or replaces) the object wrapper of the method's material class (needs
 *  MethodInfo::createInstance; does nothing without one). Called by registerMethod. */
void addMaterialWrapper(const MethodInfo& method);

}  // namespace osgBTF
