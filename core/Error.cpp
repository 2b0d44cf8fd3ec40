#include "core/Error.h"

namespace osgBTF {

void fail(const std::string& file, const std::string& problem) {
    throw Error(file.empty() ? problem : file + ": " + problem);
}

}  // namespace osgBTF
