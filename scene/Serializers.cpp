// osgDB serializers of libosgBTF's scene classes (.osgt / .osgb / .osgx).
//
// osgBTF::MaterialNode (associates osg::Object osg::Node osg::Group osgBTF::MaterialNode):
//   MaterialFile      the fitted-material file the node refers to (written as given; read back
//                     through osgDB's file search, which includes the folder of the scene
//                     file). Reading it loads the material; a missing or bad file is an OSG_WARN
//                     naming the file, the node then draws its children without the material.
//   TextureScale      tiling (default 1).
//   CoordinateMapFile the coordinate map the material is drawn through (setCoordinateMapFile;
//                     written as given, found like MaterialFile); only when the node has a map
//                     file. A map set in memory (setCoordinateMap) is not stored.
//   ShadowTerminator, TerminatorAlpha, TerminatorSoftness
//                     Sattler et al. 2003's smooth terminator (on, 15 degrees, 0.1 by default).
//   ShadowLight       the light an osgShadow::ShadowMap above shadows (-1: the last).
//   EmbeddedMaterial  only for a material that has no file (fitted in memory): its whole
//                     FittedMaterial (method, parameters, direction sets, textures with their
//                     float bits as hex text, so .osgt is exact too).
// Every registered method's material class gets its wrapper from registerMethod
// (materials/MaterialSerializer.h): FittedData, the same whole FittedMaterial, so
// osgDB::writeObjectFile / readObjectFile round-trip a material on its own (.osgt exact).
#include <osgDB/InputStream>
#include <osgDB/ObjectWrapper>
#include <osgDB/OutputStream>
#include <osgDB/Registry>

#include "core/Notify.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/MaterialSerializer.h"
#include "scene/MaterialNode.h"
#include "scene/ShadowTerminator.h"

namespace {

bool checkMaterialFile(const osgBTF::MaterialNode& node) {
    return !node.getMaterialFile().empty();
}

bool readMaterialFile(osgDB::InputStream& is, osgBTF::MaterialNode& node) {
    std::string file;
    if (!osgBTF::readWrappedStringChecked(is, file)) return false;
    node.setMaterialFile(file, is.getOptions());
    return true;
}

bool writeMaterialFile(osgDB::OutputStream& os, const osgBTF::MaterialNode& node) {
    os.writeWrappedString(node.getMaterialFile());
    os << std::endl;
    return true;
}

bool checkEmbeddedMaterial(const osgBTF::MaterialNode& node) {
    return node.getMaterial() && node.getMaterialFile().empty();
}

bool readEmbeddedMaterial(osgDB::InputStream& is, osgBTF::MaterialNode& node) {
    try {
        osgBTF::FittedMaterial fitted;
        if (!osgBTF::readFittedMaterial(is, fitted)) return false;
        node.setMaterial(osgBTF::materialFromFile(std::move(fitted)).get());
    } catch (const std::exception& e) {
        OSGBTF_NOTIFY(osg::WARN, "osgBTF::MaterialNode: "
                                     << e.what()
                                     << " (the node draws its children without the material)");
    }
    return true;
}

bool writeEmbeddedMaterial(osgDB::OutputStream& os, const osgBTF::MaterialNode& node) {
    return osgBTF::writeFittedMaterial(os, node.getMaterial()->toFittedMaterial());
}

bool checkCoordinateMapFile(const osgBTF::MaterialNode& node) {
    return !node.getCoordinateMapFile().empty();
}

bool readCoordinateMapFile(osgDB::InputStream& is, osgBTF::MaterialNode& node) {
    std::string file;
    if (!osgBTF::readWrappedStringChecked(is, file)) return false;
    node.setCoordinateMapFile(file, is.getOptions());
    return true;
}

bool writeCoordinateMapFile(osgDB::OutputStream& os, const osgBTF::MaterialNode& node) {
    os.writeWrappedString(node.getCoordinateMapFile());
    os << std::endl;
    return true;
}

}  // namespace

REGISTER_OBJECT_WRAPPER(osgBTF_MaterialNode, new osgBTF::MaterialNode, osgBTF::MaterialNode,
                        "osg::Object osg::Node osg::Group osgBTF::MaterialNode") {
    ADD_USER_SERIALIZER(MaterialFile);
    ADD_USER_SERIALIZER(EmbeddedMaterial);
    ADD_FLOAT_SERIALIZER(TextureScale, 1.0f);
    ADD_USER_SERIALIZER(CoordinateMapFile);  // after the older ones: .osgt files written before
    ADD_BOOL_SERIALIZER(ShadowTerminator, true);  // these still read (defaults)
    ADD_FLOAT_SERIALIZER(TerminatorAlpha, osgBTF::kDefaultTerminatorAlpha);
    ADD_FLOAT_SERIALIZER(TerminatorSoftness, osgBTF::kDefaultTerminatorSoftness);
    ADD_INT_SERIALIZER(ShadowLight, -1);
}
