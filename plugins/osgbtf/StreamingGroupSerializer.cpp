// osgDB serializer of osgBTF::StreamingGroup (.osgt / .osgb / .osgx), in osgdb_osgbtf
// (CMakeLists.txt says how osgDB finds it), not in libosgBTFStreaming, because it gives streamed
// materials to MaterialNodes (scene/, a layer above streaming/):
//   CacheSize      texels per side of the streamer's tile cache (TileStreamerOptions::cacheSize)
//   FeedbackScale  screen pixels per feedback pixel
//   Streams        the tile sets the streamer streams, in the order opened (folders or URLs)
// The group's children come first (osg::Group's Children): their MaterialNodes name their
// streamed materials by the tile set's index (LOCATION/index.bsvtf, the material's sourceFile),
// which MaterialNode leaves to this group. Reading Streams opens each tile set again and gives
// its material to every MaterialNode below that names it; a tile set that cannot be opened is
// an OSG_WARN naming it and the problem, and its nodes draw their children without it.
#include <osg/NodeVisitor>
#include <osgDB/InputStream>
#include <osgDB/ObjectWrapper>
#include <osgDB/OutputStream>
#include <osgDB/Registry>

#include "core/Notify.h"
#include "materials/MaterialSerializer.h"
#include "scene/MaterialNode.h"
#include "streaming/StreamedMaterial.h"
#include "streaming/StreamingGroup.h"

namespace {

/** Gives `material` to every MaterialNode below the group that names it and has none. */
class GiveStreamedMaterial : public osg::NodeVisitor {
public:
    explicit GiveStreamedMaterial(osgBTF::StreamedFmfMaterial* material)
        : osg::NodeVisitor(TRAVERSE_ALL_CHILDREN), _material(material) {}
    void apply(osg::Group& group) override {
        if (auto* node = dynamic_cast<osgBTF::MaterialNode*>(&group))
            if (!node->getMaterial() && node->getMaterialFile() == _material->sourceFile)
                node->setMaterial(_material);
        traverse(group);
    }

private:
    osgBTF::StreamedFmfMaterial* _material;
};

bool checkCacheSize(const osgBTF::StreamingGroup&) {
    return true;
}
bool readCacheSize(osgDB::InputStream& is, osgBTF::StreamingGroup& group) {
    int size = 0;
    is >> size;
    osgBTF::TileStreamerOptions options = group.streamer()->options();
    options.cacheSize = size;
    try {
        group.setStreamer(new osgBTF::TileStreamer(options));
    } catch (const std::exception& e) {
        OSGBTF_NOTIFY(osg::WARN, "osgBTF::StreamingGroup: CacheSize " << size << ": " << e.what()
                                                                      << " (default kept)");
    }
    return true;
}
bool writeCacheSize(osgDB::OutputStream& os, const osgBTF::StreamingGroup& group) {
    os << group.streamer()->options().cacheSize << std::endl;
    return true;
}

bool checkFeedbackScale(const osgBTF::StreamingGroup&) {
    return true;
}
bool readFeedbackScale(osgDB::InputStream& is, osgBTF::StreamingGroup& group) {
    int scale = 4;
    is >> scale;
    group.setFeedbackScale(scale);
    return true;
}
bool writeFeedbackScale(osgDB::OutputStream& os, const osgBTF::StreamingGroup& group) {
    os << group.feedbackScale() << std::endl;
    return true;
}

bool checkStreams(const osgBTF::StreamingGroup& group) {
    return group.streamer()->materialCount() > 0;
}
bool readStreams(osgDB::InputStream& is, osgBTF::StreamingGroup& group) {
    unsigned count = is.readSize();
    is >> is.BEGIN_BRACKET;
    for (unsigned i = 0; i < count; ++i) {
        std::string location;
        if (!osgBTF::readWrappedStringChecked(is, location)) return false;
        try {
            osg::ref_ptr<osgBTF::StreamedFmfMaterial> material = group.streamer()->open(location);
            GiveStreamedMaterial give(material.get());
            group.accept(give);
        } catch (const std::exception& e) {
            OSGBTF_NOTIFY(osg::WARN, "osgBTF::StreamingGroup: "
                                         << e.what()
                                         << " (its nodes draw their children without it)");
        }
    }
    is >> is.END_BRACKET;
    return true;
}
bool writeStreams(osgDB::OutputStream& os, const osgBTF::StreamingGroup& group) {
    const int count = group.streamer()->materialCount();
    os.writeSize(unsigned(count));
    os << os.BEGIN_BRACKET << std::endl;
    for (int i = 0; i < count; ++i) {
        os.writeWrappedString(group.streamer()->material(i)->location());
        os << std::endl;
    }
    os << os.END_BRACKET << std::endl;
    return true;
}

}  // namespace

REGISTER_OBJECT_WRAPPER(osgBTF_StreamingGroup, new osgBTF::StreamingGroup, osgBTF::StreamingGroup,
                        "osg::Object osg::Node osg::Group osgBTF::StreamingGroup") {
    ADD_USER_SERIALIZER(CacheSize);
    ADD_USER_SERIALIZER(FeedbackScale);
    ADD_USER_SERIALIZER(Streams);
}
