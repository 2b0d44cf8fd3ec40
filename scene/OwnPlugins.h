#pragma once
// Lets a program find osgBTF's own osgDB plugins (osgdb_exr's float EXR images, the material
// readers) without OSG_LIBRARY_PATH, from the build tree and from any install prefix.
#include <string>

namespace osgBTF {

/** Adds the folder holding this libosgBTF (where its plugins live, below osgPlugins-<OSG
 *  version>) to osgDB's library search path, once per process: first when OSG_LIBRARY_PATH is
 *  unset (this build's plugins before any other install's), after the user's folders when it is
 *  set. Returns the folder added, or an empty string when the folder has no plugin folder (the
 *  library was moved alone) or was on the path already. The btf tool, btfviewer and btf-examples
 *  call it first; applications may too. */
std::string useOwnPlugins();

}  // namespace osgBTF
