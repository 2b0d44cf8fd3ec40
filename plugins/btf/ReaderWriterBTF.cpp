#include "plugins/btf/ReaderWriterBTF.h"

#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <filesystem>
#include <map>
#include <mutex>
#include <optional>
#include <sstream>
#include <system_error>

#include <osg/Geode>
#include <osg/Geometry>
#include <osg/Notify>
#include <osgDB/FileNameUtils>
#include <osgDB/FileUtils>
#include <osgDB/ReadFile>
#include <osgDB/Registry>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/Notify.h"
#include "loaders/LoadBtf.h"
#include "loaders/Rti.h"
#include "loaders/Ubo2003.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MethodRegistry.h"
#include "materials/RelightFolder.h"
#include "scene/MaterialNode.h"
#include "scene/OpenMaterial.h"
// The modules that fit on load (all but osgdb_btfmat) link libosgBTFFit for the fit and its
// cache; osgdb_btfmat renders fitted files only and is built without them (CMakeLists.txt).
#if OSGBTF_READERS_FIT
#include "fit/FitCache.h"
#endif

namespace fs = std::filesystem;

namespace osgBTF::plugin {

namespace {

const char* const kPseudoSyntax = "MODEL.(MATERIAL[,scale=S][,KEY=VALUE...]).btfmaterial";

/** What the option string asks of these readers. */
struct Settings {
    std::string method = pluginDefaultMethod().name;
    bool methodGiven = false;  // a UBO2014 file without method= opens as stored (fmf)
    std::map<std::string, std::string> values;  // every KEY=VALUE word, method options among them
    float textureScale = 1.0f;
    std::string cacheDir;  // empty: caching off
    std::string mapFile;   // a coordinate map to draw the material through; empty: none
    // Fit a mip-mapped material (fit/MipMapping.h): unset means yes, as `btf fit` (at most
    // 1.41x the file; mipmap=off for the base level alone).
    std::optional<bool> mipmap;
};

/** Parses option words; `extra` (from a pseudo-file name) wins over the -O string. */
Settings parseSettings(const osgDB::Options* options, const std::string& extra = {}) {
    Settings settings;
#if OSGBTF_READERS_FIT
    settings.cacheDir = defaultFitCacheFolder();
#endif
    std::string text = options ? options->getOptionString() : std::string();
    text += " " + extra;
    for (char& c : text)
        if (c == ',') c = ' ';
    std::istringstream words(text);
    std::string word;
    while (words >> word) {
        const auto eq = word.find('=');
        if (eq == std::string::npos || eq == 0) continue;  // another plugin's flag
        const std::string key = word.substr(0, eq), value = word.substr(eq + 1);
        if (key == "method") {
            settings.method = value;
            settings.methodGiven = true;
        } else if (key == "map") {
            if (value.empty()) throw Error("option map=: expected a coordinate map file");
            settings.mapFile = value;
        } else if (key == "mipmap") {
            if (value != "on" && value != "off")
                throw Error("option mipmap=" + value + ": expected on or off");
            settings.mipmap = value == "on";
        } else if (key == "cache") {
            settings.cacheDir = value == "off" ? std::string() : value;
        } else if (key == "scale") {
            char* end = nullptr;
            const float scale = std::strtof(value.c_str(), &end);
            if (value.empty() || *end || !(scale > 0.0f))
                throw Error("option scale=" + value + ": expected a positive number");
            settings.textureScale = scale;
        } else {
            settings.values[key] = value;
        }
    }
    return settings;
}

/** The fit options among the words, validated against the method's option table: every word
 *  whose key is an option of some registered method (so "method=laf components=4" is an error,
 *  not silently ignored); keys no method has belong to other plugins. */
FitOptions fitOptionsFor(const MethodInfo& method, const Settings& settings) {
    FitOptions options;
    for (const auto& [key, value] : settings.values)
        if (!methodsWithOption(key).empty()) options.set(key, value);
    validateOptions(method, options);
    return options;
}

/** A measured BTF fitted with the settings' method, through the fit cache (fit/FitCache.h). */
osg::ref_ptr<Material> fitMeasured(const std::string& path, const Settings& settings) {
    const MethodInfo& method = findMethod(settings.method);
    const FitOptions fitOptions = fitOptionsFor(method, settings);
#if OSGBTF_READERS_FIT
    return fitCached(path, method, fitOptions, settings.cacheDir, settings.mipmap.value_or(true));
#else
    throw Error(path + ": fitting a measured BTF needs libosgBTFFit, which this module (" +
                "osgdb_btfmat, fitted materials only) does not load");
#endif
}

/** A UBO2014 file without method=: its stored factorisation as a material of factorMethod()
 *  (fmf), nothing decoded or fitted (scene/OpenMaterial.h). Of the fit options only its
 *  `storage` applies. */
osg::ref_ptr<Material> openStored(const std::string& path, const Settings& settings) {
    MaterialTexture::PixelKind storage = MaterialTexture::Half;
    std::string ignored;
    for (const auto& [key, value] : settings.values) {
        if (key == "storage") {
            if (value != "half" && value != "float")
                throw Error("option storage=" + value +
                            ": expected half or float (the textures "
                            "of a UBO2014 file's stored factors)");
            storage = value == "float" ? MaterialTexture::Float : MaterialTexture::Half;
            continue;
        }
        if (!methodsWithOption(key).empty()) ignored += " " + key + "=" + value;
    }
    if (settings.mipmap.value_or(false)) ignored += " mipmap=on";
    OSGBTF_NOTIFY(
        osg::NOTICE,
        "osgBTF: " << path << ": opening its stored factorisation as an " << factorMethod().name
                   << " material (method=NAME fits a method instead)"
                   << (ignored.empty() ? std::string()
                                       : "; fit options without method= ignored:" + ignored));
    return loadSharedMaterial(path, storage);
}

/** Measured BTFs (and RTI captures: a .lp light file, or a folder or zip holding one) go through
 *  the fit; everything else is read as a fitted-material file. */
bool isMeasured(const std::string& path) {
    const std::string ext = osgDB::getLowerCaseFileExtension(path);
    std::error_code error;
    return ext == "btf" || ext == "zip" || ext == "lp" || fs::is_directory(path, error);
}

/** Whether a zip holds measured data this plugin reads: UBO2003/ATRIUM images or an RTI capture
 *  (loaders/Rti.h). Anything else is a model or texture archive, OSG's zip plugin's. */
bool isMeasuredZip(const std::string& path) {
    return mayBeUbo2003(path) || isRtiCapture(path);
}

osg::ref_ptr<Material> readMaterial(const std::string& path, const Settings& settings) {
    if (!settings.methodGiven && isUbo2014File(path)) return openStored(path, settings);
    return isMeasured(path) ? fitMeasured(path, settings) : loadSharedMaterial(path);
}

osgDB::ReaderWriter::ReadResult notFound(const std::string& file) {
    osgDB::ReaderWriter::ReadResult result(osgDB::ReaderWriter::ReadResult::FILE_NOT_FOUND);
    result.message() = file + ": no such file";
    return result;
}

osgDB::ReaderWriter::ReadResult error(const std::string& message) {
    return osgDB::ReaderWriter::ReadResult(message);  // ERROR_IN_READING_FILE
}

/** The one place where the option words reach a node, for every reader of this module: the
 *  texture scale and the coordinate map. Returns the problem (a missing or bad map file, a map
 *  into another sample size) as the error message, empty when fine. */
std::string applySettings(MaterialNode& node, const Settings& settings,
                          const osgDB::Options* options) {
    node.setTextureScale(settings.textureScale);
    if (settings.mapFile.empty()) return {};
    const std::string path = osgDB::findDataFile(settings.mapFile, options);
    if (path.empty()) return settings.mapFile + ": no such file";
    try {
        loadSharedCoordinateMap(path);  // the file's own problems, with its path, as an Error
    } catch (const std::exception& e) {
        return e.what();
    }
    // The name as given is what a scene written back refers to (found the same way again).
    node.setCoordinateMapFile(settings.mapFile, options);
    return node.getCoordinateMapError();
}

/** OpenSceneGraph's own zip archive reader (osgdb_zip), loaded on the first call where it is
 *  installed; null where it is not. Once libosgBTF has aliased ".zip" to this module, osgDB never
 *  loads osgdb_zip for a ".zip" itself, so the module is loaded here by its file name: ours with
 *  "btfzip" replaced, which keeps osgDB's folder, version, postfix and suffix. */
osgDB::ReaderWriter* osgZipReader() {
    osgDB::Registry* registry = osgDB::Registry::instance();
    static std::once_flag once;
    std::call_once(once, [registry] {
        std::string name = registry->createLibraryNameForExtension("btfzip");
        const auto at = name.rfind("osgdb_btfzip");
        if (at == std::string::npos) return;
        name.replace(at, std::strlen("osgdb_btfzip"), "osgdb_zip");
        if (!osgDB::findLibraryFile(name).empty()) registry->loadLibrary(name);
    });
    // Any other reader of ".zip" will do (a test stands one in for OSG's).
    for (const osg::ref_ptr<osgDB::ReaderWriter>& reader : registry->getReaderWriterList())
        if (reader->acceptsExtension("zip") && !dynamic_cast<ReaderWriterBTF*>(reader.get()))
            return reader.get();
    return nullptr;
}

/** OSG's zip reader when `file` is a ".zip" that is no BTF (a model or texture archive) and that
 *  reader is installed; null otherwise. */
osgDB::ReaderWriter* zipForOsg(const osgDB::ReaderWriter& self, const std::string& file,
                               const osgDB::Options* options) {
    if (osgDB::getLowerCaseFileExtension(file) != "zip" || !self.acceptsExtension("zip"))
        return nullptr;
    const std::string path = osgDB::findDataFile(file, options);
    if (path.empty() || isMeasuredZip(path)) return nullptr;
    return osgZipReader();
}

/** A flat rectangle of the material's aspect (height 1) in the XZ plane around the origin, normal
 *  -Y, texture coordinates 0..1 across it (s along +X, t along +Z). */
osg::ref_ptr<osg::Geode> rtiPatch(const Material& material) {
    const float aspect = float(material.width()) / float(material.height());
    osg::ref_ptr<osg::Geometry> geometry = new osg::Geometry;
    osg::ref_ptr<osg::Vec3Array> vertices = new osg::Vec3Array;
    osg::ref_ptr<osg::Vec2Array> texCoords = new osg::Vec2Array;
    for (const osg::Vec2 corner :
         {osg::Vec2(0, 0), osg::Vec2(1, 0), osg::Vec2(1, 1), osg::Vec2(0, 1)}) {
        vertices->push_back(osg::Vec3((corner.x() - 0.5f) * aspect, 0.0f, corner.y() - 0.5f));
        texCoords->push_back(corner);
    }
    geometry->setVertexArray(vertices.get());
    geometry->setTexCoordArray(0, texCoords.get());
    osg::ref_ptr<osg::Vec3Array> normals = new osg::Vec3Array(1);
    (*normals)[0] = osg::Vec3(0, -1, 0);
    geometry->setNormalArray(normals.get(), osg::Array::BIND_OVERALL);
    geometry->addPrimitiveSet(new osg::DrawArrays(GL_TRIANGLE_FAN, 0, 4));
    geometry->setName("osgBTF RTI patch");
    osg::ref_ptr<osg::Geode> geode = new osg::Geode;
    geode->addDrawable(geometry.get());
    return geode;
}

/** Splits "MODEL.(MATERIAL,k=v,...)" into model, material and the k=v words. */
bool splitPseudoName(const std::string& inner, std::string& model, std::string& material,
                     std::string& words) {
    if (inner.empty() || inner.back() != ')') return false;
    const auto open = inner.rfind(".(");
    if (open == std::string::npos || open == 0) return false;
    model = inner.substr(0, open);
    const std::string params = inner.substr(open + 2, inner.size() - open - 3);
    const auto comma = params.find(',');
    material = params.substr(0, comma);
    words = comma == std::string::npos ? std::string() : params.substr(comma + 1);
    return !material.empty() && material.find(')') == std::string::npos;
}

/** The pseudo-loader with a BSVTF tile set's index as the material: the tile set read through
 *  osgDB (osgdb_bsvtf: a StreamingGroup over a MaterialNode of the streamed material), the model
 *  under that MaterialNode. Through osgDB, so this module needs no streaming library. */
osgDB::ReaderWriter::ReadResult streamedUnder(const std::string& modelName,
                                              const std::string& indexName,
                                              const Settings& settings,
                                              const osgDB::Options* options) {
    osgDB::ReaderWriter::ReadResult read =
        osgDB::Registry::instance()->readNode(indexName, options);
    if (!read.success())
        return error(read.message().empty() ? indexName + ": cannot read the tile set"
                                            : read.message());
    osg::ref_ptr<osg::Group> group = dynamic_cast<osg::Group*>(read.getNode());
    MaterialNode* node = group && group->getNumChildren() == 1
                             ? dynamic_cast<MaterialNode*>(group->getChild(0))
                             : nullptr;
    if (!node) return error(indexName + ": did not read as a streamed material");
    osg::ref_ptr<osg::Node> model = osgDB::readRefNodeFile(modelName, options);
    if (!model) return error(modelName + ": cannot read the model");
    if (const std::string problem = applySettings(*node, settings, options); !problem.empty())
        return error(problem);
    node->addChild(model.get());
    return group.get();
}

}  // namespace

ReaderWriterBTF::ReaderWriterBTF(const std::string& extension) {
    if (extension == "btfmat")
        supportsExtension("btfmat", "osgBTF fitted material (OpenEXR inside) -> MaterialNode");
    else if (extension == "btf")
        supportsExtension("btf", "UBO2014 measured BTF: its stored factors as an " +
                                     factorMethod().name +
                                     " material, or fitted on load with method= -> MaterialNode");
    else if (extension == "btfzip") {
        supportsExtension("zip",
                          "UBO2003/ATRIUM measured BTF zip or RTI capture zip (photos and a .lp "
                          "light file), fitted on load -> MaterialNode (other zips go to OSG's "
                          "zip plugin where installed)");
        supportsExtension("btfzip",
                          "pseudo-loader: NAME.zip.btfzip reads NAME.zip as a UBO2003/ATRIUM "
                          "measured BTF zip (for programs in which \".zip\" reaches OSG's own "
                          "zip plugin)");
    } else if (std::string method;
               const ForeignFileFormat* format = findForeignFile("x." + extension, &method)) {
        // Another tool's fitted file that a method registered (materials/ForeignFiles.h).
        supportsExtension(extension, format->description + " -> MaterialNode (a " + method +
                                         " material) over a flat patch facing -Y");
    } else if (extension == "relight")
        supportsExtension(
            "relight",
            "pseudo-loader: DIR/info.json.relight reads relight's web layout (DIR/"
            "info.json + plane_N.jpg, as OpenLIME loads it; types " +
                [] {
                    std::string types;
                    for (const std::string& t : relightTypes())
                        types += (types.empty() ? "" : ", ") + t;
                    return types;
                }() +
                ") -> MaterialNode over a flat patch facing -Y");
    else if (extension == "lp")
        supportsExtension("lp",
                          "RTI capture: a light-position file (the image count, then \"IMAGE X Y "
                          "Z\" per photo) and the photos beside it, fitted on load -> "
                          "MaterialNode");
    else if (extension == "btfmaterial")
        supportsExtension(
            "btfmaterial",
            std::string("pseudo-loader: a model under an osgBTF material, ") + kPseudoSyntax);
    if (extension != "btfmat" && extension != "relight") {
        supportsOption("method=<name>",
                       "fit method for measured BTFs (default: " + pluginDefaultMethod().name +
                           "; a UBO2014 .btf opens as its stored factors unless method= is "
                           "given)");
        // Each fit option once, with what every method that has it makes of it.
        std::map<std::string, std::string> fitOptions;
        for (const std::string& name : methodNamesInOrder())
            for (const OptionSpec& option : findMethod(name).options) {
                std::string& text = fitOptions[option.name + "=<" + option.typeName() + ">"];
                text += (text.empty() ? "" : "; ") + name + ": " + optionHelp(option);
            }
        for (const auto& [key, text] : fitOptions) supportsOption(key, text);
        supportsOption("cache=<dir>|off", "fit cache folder (default ~/.cache/osgbtf)");
        supportsOption("mipmap=on|off",
                       "fit a mip-mapped material: minified surfaces without aliasing (default "
                       "on; off: the base level alone)");
    }
    supportsOption("scale=<s>", "texture scale (tiling) of the MaterialNode (default 1)");
    supportsOption("map=<file>",
                   "a coordinate map (btf synthesize -o map.exr) the material is drawn through: "
                   "the texture coordinates cover the map, each map texel shows the sample texel "
                   "it names");
}

osgDB::ReaderWriter::ReadResult ReaderWriterBTF::readObject(const std::string& file,
                                                            const Options* options) const {
    if (osgDB::ReaderWriter* zip = zipForOsg(*this, file, options))
        return zip->readObject(file, options);
    // As for every node format: osgconv reads its input with readObjectFile.
    return readNode(file, options);
}

osgDB::ReaderWriter::ReadResult ReaderWriterBTF::readImage(const std::string& file,
                                                           const Options* options) const {
    if (osgDB::ReaderWriter* zip = zipForOsg(*this, file, options))
        return zip->readImage(file, options);
    return ReadResult::FILE_NOT_HANDLED;
}

osgDB::ReaderWriter::ReadResult ReaderWriterBTF::openArchive(const std::string& file,
                                                             ArchiveStatus status,
                                                             unsigned int indexBlockSizeHint,
                                                             const Options* options) const {
    // Any zip, a BTF's too, is an archive to OSG's zip plugin.
    if (osgDB::getLowerCaseFileExtension(file) == "zip" && acceptsExtension("zip"))
        if (osgDB::ReaderWriter* zip = osgZipReader())
            return zip->openArchive(file, status, indexBlockSizeHint, options);
    return ReadResult::FILE_NOT_HANDLED;
}

osgDB::ReaderWriter::ReadResult ReaderWriterBTF::readNode(const std::string& file,
                                                          const Options* options) const {
    const std::string ext = osgDB::getLowerCaseFileExtension(file);
    if (!acceptsExtension(ext)) return ReadResult::FILE_NOT_HANDLED;
    try {
        if (ext == "btfmaterial") {
            std::string modelName, materialName, words;
            const std::string inner = osgDB::getNameLessExtension(file);
            if (!splitPseudoName(inner, modelName, materialName, words))
                return error(file + ": expected " + kPseudoSyntax);
            const Settings settings = parseSettings(options, words);
            if (osgDB::getLowerCaseFileExtension(materialName) == "bsvtf")
                return streamedUnder(modelName, materialName, settings, options);
            const std::string materialPath = osgDB::findDataFile(materialName, options);
            if (materialPath.empty()) return notFound(materialName);
            osg::ref_ptr<Material> material = readMaterial(materialPath, settings);
            osg::ref_ptr<osg::Node> model = osgDB::readRefNodeFile(modelName, options);
            if (!model) return error(modelName + ": cannot read the model");
            osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
            if (const std::string problem = applySettings(*node, settings, options);
                !problem.empty())
                return error(problem);
            node->addChild(model.get());
            return node.get();
        }

        const Settings settings = parseSettings(options);
        // "x.zip.btfzip": x.zip is a BTF zip, whatever else reads ".zip" in this program;
        // "DIR/info.json.relight": relight's folder DIR, named by its info.json.
        const bool namedBtfZip = ext == "btfzip";
        const std::string name =
            namedBtfZip || ext == "relight" ? osgDB::getNameLessExtension(file) : file;
        std::string path = osgDB::findDataFile(name, options);
        if (path.empty() && ext == "btfmat") {
            // "x.exr.btfmat": the fitted file x.exr, read as a material rather than an image.
            const std::string inner = osgDB::getNameLessExtension(file);
            if (!osgDB::getFileExtension(inner).empty()) path = osgDB::findDataFile(inner, options);
        }
        if (path.empty()) return notFound(name);
        if (namedBtfZip && !isMeasuredZip(path))
            return error(path +
                         ": not a measured BTF zip (no member named like \"tl000 pl000 tv000 "
                         "pv000\", no RTI light file .lp), read as one because of the name " +
                         file);
        // A zip that is no BTF (a model archive, say) is OSG's zip plugin's where installed;
        // elsewhere FILE_NOT_HANDLED lets osgDB go on to any other reader of ".zip" loaded.
        if (ext == "zip" && !isMeasuredZip(path)) {
            if (osgDB::ReaderWriter* zip = zipForOsg(*this, file, options))
                return zip->readNode(file, options);
            return ReadResult::FILE_NOT_HANDLED;
        }
        osg::ref_ptr<Material> material = ext == "btfmat" ? loadSharedMaterial(path)
                                          : namedBtfZip   ? fitMeasured(path, settings)
                                                          : readMaterial(path, settings);
        osg::ref_ptr<MaterialNode> node = new MaterialNode(material.get());
        if (!node->getMaterial()) return error(node->getMaterialError());
        if (const std::string problem = applySettings(*node, settings, options); !problem.empty())
            return error(problem);
        // An RTI file read by itself is shown as RTI viewers show it: a flat patch of its aspect,
        // here facing the home view of osgviewer (-Y), lit by its headlight.
        if (findForeignFile(path)) node->addChild(rtiPatch(*material).get());
        return node.get();
    } catch (const std::exception& e) {
        return error(e.what());
    }
}

}  // namespace osgBTF::plugin
