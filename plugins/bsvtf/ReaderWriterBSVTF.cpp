// osgdb_bsvtf: a BSVTF tile set (`btf tiles`) streamed into any OSG application by name. The
// name is the set's index: DIR/index.bsvtf, or http(s)://HOST/PATH/index.bsvtf (the module
// claims the http and https protocols for ".bsvtf", so osgDB gives it URLs instead of its curl
// plugin). The result is an osgBTF::StreamingGroup whose streamer streams that set, over an
// osgBTF::MaterialNode of the streamed material without children: what the other readers give
// for a material, for the application (or the pseudo-loader's model) to put geometry under.
// It links libosgBTFStreaming (libcurl); the render plugin osgdb_btfmat does not.
//
// Options (-O "...", words of other plugins left alone):
//   cache=N     texels per side of the tile cache (TileStreamerOptions::cacheSize, 4032)
//   feedback=N  screen pixels per feedback pixel along each axis (StreamingGroup, 4)
#include <cstdlib>
#include <sstream>
#include <string>

#include <osgDB/FileNameUtils>
#include <osgDB/FileUtils>
#include <osgDB/Registry>

#include "scene/MaterialNode.h"
#include "streaming/StreamedMaterial.h"
#include "streaming/StreamingGroup.h"

namespace {

constexpr char kIndexName[] = "index.bsvtf";

class ReaderWriterBSVTF : public osgDB::ReaderWriter {
public:
    ReaderWriterBSVTF() {
        supportsExtension("bsvtf",
                          "osgBTF BSVTF tile set, named by its index.bsvtf (a folder or an "
                          "http(s) URL) -> StreamingGroup over a MaterialNode of the streamed "
                          "material");
        supportsProtocol("http", "BSVTF tile sets from a static HTTP server (libcurl)");
        supportsProtocol("https", "BSVTF tile sets from a static HTTPS server (libcurl)");
        supportsOption("cache=<n>", "texels per side of the tile cache (default 4032)");
        supportsOption("feedback=<n>", "screen pixels per feedback pixel (default 4)");
    }
    const char* className() const override { return "osgBTF BSVTF stream reader"; }

    ReadResult readObject(const std::string& file, const Options* options) const override {
        return readNode(file, options);
    }

    ReadResult readNode(const std::string& file, const Options* options) const override {
        if (!acceptsExtension(osgDB::getLowerCaseFileExtension(file)))
            return ReadResult::FILE_NOT_HANDLED;
        if (osgDB::getSimpleFileName(file) != kIndexName)
            return error(file + ": name a tile set by its " + kIndexName +
                         " (DIR/index.bsvtf or http://HOST/PATH/index.bsvtf)");
        std::string location;
        if (osgDB::containsServerAddress(file)) {
            location = osgDB::getFilePath(file);
        } else {
            const std::string index = osgDB::findDataFile(file, options);
            if (index.empty()) return ReadResult(ReadResult::FILE_NOT_FOUND);
            location = osgDB::getFilePath(index);
            if (location.empty()) location = ".";
        }
        try {
            osgBTF::TileStreamerOptions streamerOptions;
            int feedbackScale = 4;
            if (options) {
                std::istringstream words(options->getOptionString());
                for (std::string word; words >> word;) {
                    if (word.rfind("cache=", 0) == 0)
                        streamerOptions.cacheSize = positive(word, file);
                    else if (word.rfind("feedback=", 0) == 0)
                        feedbackScale = positive(word, file);
                }
            }
            osg::ref_ptr<osgBTF::StreamingGroup> group =
                new osgBTF::StreamingGroup(new osgBTF::TileStreamer(streamerOptions));
            group->setFeedbackScale(feedbackScale);
            osg::ref_ptr<osgBTF::StreamedFmfMaterial> material = group->streamer()->open(location);
            group->addChild(new osgBTF::MaterialNode(material.get()));
            return group.get();
        } catch (const std::exception& e) {
            return error(e.what());
        }
    }

private:
    // The message goes to the caller, as with osgBTF's other readers (osgviewer prints it).
    static ReadResult error(const std::string& message) { return ReadResult(message); }
    static int positive(const std::string& word, const std::string& file) {
        const std::string value = word.substr(word.find('=') + 1);
        char* end = nullptr;
        const long n = std::strtol(value.c_str(), &end, 10);
        if (value.empty() || *end != '\0' || n < 1 || n > 65536)
            throw std::runtime_error(file + ": option " + word + ": expected a positive integer");
        return int(n);
    }
};

}  // namespace

REGISTER_OSGPLUGIN(bsvtf, ReaderWriterBSVTF)
