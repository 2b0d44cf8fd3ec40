// One osgDB plugin module per extension (compiled once per module with OSGBTF_PLUGIN_EXTENSION
// set, see CMakeLists.txt): osgDB looks for osgdb_<ext>.so, and each module claims only its
// extension, so loading several of them never registers two readers for one extension.
#include <osgDB/Registry>

#include "plugins/btf/ReaderWriterBTF.h"

#define OSGBTF_STRINGIFY2(x) #x
#define OSGBTF_STRINGIFY(x) OSGBTF_STRINGIFY2(x)

namespace {
class ReaderWriterForThisModule : public osgBTF::plugin::ReaderWriterBTF {
public:
    ReaderWriterForThisModule() : ReaderWriterBTF(OSGBTF_STRINGIFY(OSGBTF_PLUGIN_EXTENSION)) {}
};
}  // namespace

#define OSGBTF_REGISTER(ext) REGISTER_OSGPLUGIN(ext, ReaderWriterForThisModule)
OSGBTF_REGISTER(OSGBTF_PLUGIN_EXTENSION)
