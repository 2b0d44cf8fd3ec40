#pragma once
// Lets a program find osgBTF's own osgDB plugins (osgdb_btfexr's float EXR images, the material
// readers) without OSG_LIBRARY_PATH, from the build tree and from any install prefix, and reach
// the two whose extensions are not their names (".zip" and ".exr", plugins/README.md).
#include <string>
#include <vector>

namespace osgBTF {

/** Adds the folder holding this libosgBTF (where its plugins live, below osgPlugins-<OSG
 *  version>) to osgDB's library search path, once per process: first when OSG_LIBRARY_PATH is
 *  unset (this build's plugins before any other install's), after the user's folders when it is
 *  set. Returns the folder added, or an empty string when the folder has no plugin folder (the
 *  library was moved alone) or was on the path already. The btf tool, btfviewer and btf-examples
 *  call it first; applications may too. */
std::string useOwnPlugins();

/** Points osgDB's ".zip" at osgdb_btfzip and ".exr" at osgdb_btfexr (Registry extension
 *  aliases zip -> btfzip, exr -> btfexr), each only when osgDB finds that module on its library
 *  path now, so that a program without osgBTF's plugins keeps whatever reads those extensions.
 *  The modules are not named osgdb_zip and osgdb_exr because those are OpenSceneGraph's own
 *  plugins; osgdb_btfzip hands zips that are no BTF to OSG's osgdb_zip where installed. Called
 *  when libosgBTF is loaded and by useOwnPlugins(); call it again after changing the library
 *  path. Returns the extensions aliased by this call or before. */
std::vector<std::string> aliasOwnPlugins();

}  // namespace osgBTF
