#include "core/ImageCodecs.h"

#include "core/Error.h"
#include "core/Modules.h"

namespace osgBTF {

const ImageCodecs& imageCodecs() {
    static const ImageCodecs* const codecs = [] {
        std::string error;
        void* entry = loadModuleSymbol(reinterpret_cast<const void*>(&imageCodecs),
                                       "libosgBTFImageCodecs.so", "osgbtfImageCodecs", error);
        if (!entry)
            throw Error(
                "osgBTF's image codecs (OpenImageIO) for formats other than EXR could not "
                "be loaded: " +
                error);
        return reinterpret_cast<const ImageCodecs* (*)()>(entry)();
    }();
    return *codecs;
}

}  // namespace osgBTF
