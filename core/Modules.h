// osgBTF: modules, shared objects of this project that a library loads on first use instead of
// linking them, so that programs which never need them do not pay for their dependencies at
// start: libosgBTFImageCodecs (OpenImageIO, core/ImageCodecs.h) and libosgBTFNeuralTraining
// (libtorch, materials/neural/). A module lives in the folder of the library that loads it (the
// build tree's lib/, or the installed libdir), so no search path is involved.
#pragma once

#include <string>

namespace osgBTF {

/** The address of `symbol` in the module `fileName` (e.g. "libosgBTFImageCodecs.so"), loaded
 *  from the folder of the shared library that holds `addressInLibrary` (any function of the
 *  caller's library). Returns null and sets `error` (the loader's reason, which names the file)
 *  when the module cannot be loaded or lacks the symbol. */
void* loadModuleSymbol(const void* addressInLibrary, const std::string& fileName,
                       const char* symbol, std::string& error);

}  // namespace osgBTF
