// osgdb_serializers_osgbtf (CMakeLists.txt says why it exists). Loading it loads libosgBTF and
// libosgBTFEnvironment, whose static initialisers register the osgBTF:: wrappers; osgDB then
// finds them.
#include "environment/EnvironmentLitGroup.h"
#include "scene/MaterialNode.h"

// A use of libosgBTF, so that the linker keeps it as a dependency even with --as-needed.
extern "C" osg::Object* osgdb_serializers_osgbtf_anchor() {
    return new osgBTF::MaterialNode;
}

// The same for libosgBTFEnvironment (EnvironmentLitGroup's wrapper).
extern "C" osg::Object* osgdb_serializers_osgbtf_environment_anchor() {
    return new osgBTF::EnvironmentLitGroup;
}
