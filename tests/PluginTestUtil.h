// Reading through the osgDB plugins of this build (not an installed copy) in the unit tests.
#pragma once

#include <algorithm>
#include <cstdlib>
#include <string>

#include <osgDB/ReadFile>
#include <osgDB/Registry>

#include "scene/MaterialNode.h"
#include "scene/OwnPlugins.h"
#include "tests/TestUtil.h"

namespace osgBTF::test {

/** Puts the build's plugin folder first on OSG's library path (once per process), and ".zip"
 *  and ".exr" on osgBTF's modules there (which libosgBTF did when it was loaded only if the
 *  folder was on the path already, as OSG_LIBRARY_PATH puts it under ctest). */
inline void usePluginsFromBuild() {
    static const bool done = [] {
        const std::string dir = buildDir() + "/lib";
        setenv("OSG_LIBRARY_PATH", dir.c_str(), 0);
        osgDB::FilePathList& paths = osgDB::Registry::instance()->getLibraryFilePathList();
        if (std::find(paths.begin(), paths.end(), dir) == paths.end()) paths.push_front(dir);
        aliasOwnPlugins();
        return true;
    }();
    (void)done;
}

inline osgDB::ReaderWriter::ReadResult readNode(const std::string& file,
                                                const std::string& optionString = {}) {
    usePluginsFromBuild();
    osg::ref_ptr<osgDB::Options> options = new osgDB::Options(optionString);
    return osgDB::Registry::instance()->readNode(file, options.get());
}

inline MaterialNode* asMaterialNode(const osgDB::ReaderWriter::ReadResult& result) {
    using ReadResult = osgDB::ReaderWriter::ReadResult;
    return dynamic_cast<MaterialNode*>(const_cast<ReadResult&>(result).getNode());
}

}  // namespace osgBTF::test
