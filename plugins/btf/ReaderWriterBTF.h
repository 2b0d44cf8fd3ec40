/* osgBTF's osgDB readers: BTF materials as scene-graph nodes (osgBTF::MaterialNode).
 *
 * One class, eight plugin modules (osgDB loads osgdb_<ext>.so per extension; plugins/README.md
 * says why one class serves them, plugins/btf/CMakeLists.txt lists them); each module claims only
 * its own extension (osgdb_btfzip also ".zip", see there). Besides the four below: osgdb_lp (an
 * RTI capture by its .lp light file, fitted on load), osgdb_ptm and osgdb_rti (the RTI field's
 * fitted files, materials/ForeignFiles.h) and osgdb_relight (relight's web layout,
 * DIR/info.json.relight).
 *
 *   osgdb_btfmat       x.btfmat       a fitted-material file (`btf fit -o x.btfmat`; OpenEXR
 *                                     inside) -> MaterialNode. Files named otherwise
 *                                     (`btf fit -o x.exr`) read as the pseudo-file name
 *                                     x.exr.btfmat.
 *   osgdb_btf          x.btf          a UBO2014 measured BTF -> MaterialNode: its stored
 *                                     factors as an fmf material (nothing decoded or fitted),
 *                                     or fitted on load when method= is given
 *   osgdb_btfzip       x.zip          a UBO2003/ATRIUM measured BTF zip, fitted on load. Not
 *                      x.zip.btfzip   named osgdb_zip, OpenSceneGraph's zip archive plugin:
 *                                     osgDB reaches this module for ".zip" through the
 *                                     extension alias zip -> btfzip that libosgBTF registers
 *                                     (scene/OwnPlugins.h), `-e btfzip`, or the pseudo-file
 *                                     name x.zip.btfzip. A zip that is no BTF goes to OSG's
 *                                     osgdb_zip where one is installed (loaded by its own
 *                                     name, since the alias hides it from osgDB), else it is
 *                                     FILE_NOT_HANDLED.
 *   osgdb_btfmaterial  (pseudo-loader) puts a model under a material, all in one file name:
 *
 *       MODEL.(MATERIAL[,scale=S][,KEY=VALUE...]).btfmaterial
 *
 *     e.g.  osgviewer "cow.osgt.(wool-lpca.btfmat,scale=4).btfmaterial"
 *           osgviewer "cow.osgt.(wool.btf,method=lambert).btfmaterial"
 *     MODEL is any file osgDB reads; MATERIAL a fitted-material file (any extension), a
 *     UBO2014 .btf (as stored, or fitted with method=) or a measured BTF (.zip, or a folder of
 *     UBO2003 images) fitted on load; scale=S is the texture scale (the material repeats S times
 *     per texture-coordinate unit); other KEY=VALUE pairs are fit options, as with -O. The
 *     parentheses let names and values contain dots; names cannot contain ',' or ')'. Quote the
 *     name in a shell.
 *
 * Options (-O "...", words separated by spaces; unknown words belong to other plugins):
 *   method=NAME      fit method for measured BTFs (default lpca; `btf fit --help` lists them);
 *                    without it a UBO2014 file opens as stored, an fmf material of its factors
 *   storage=half|float  that material's textures (float only for files storing floats); other
 *                    fit options without method= are ignored there (OSG_NOTICE says so)
 *   KEY=VALUE        an option of that method (e.g. clusters=32 components=8); options the
 *                    method does not have are ignored
 *   scale=S          texture scale of the MaterialNode (default 1; with map=, map repeats)
 *   map=FILE         a coordinate map (core/CoordinateMap.h, `btf synthesize -o FILE`) the
 *                    material is drawn through (MaterialNode::setCoordinateMapFile); a missing
 *                    file, a bad one or a map into another sample size is an error naming the
 *                    file (the pseudo-loader takes it as MODEL.(MATERIAL,map=FILE).btfmaterial)
 *   cache=DIR        folder of fitted measured BTFs (default $OSGBTF_CACHE_DIR, else
 *                    $XDG_CACHE_HOME/osgbtf, else ~/.cache/osgbtf); cache=off fits every time
 *
 * Fit cache (fit/FitCache.h, in libosgBTFFit, which osgdb_btfmat does not load): a measured BTF
 * is fitted once; the result is saved (atomically) as
 * DIR/<name>-<method>-<16 hex digits>.btfmat, the digits a hash of the input's absolute path,
 * size, modification time, the method and its options. The next load of the same input with the
 * same options reads that file instead of fitting. OSG_NOTICE says which of the two happened.
 *
 * Results: FILE_NOT_HANDLED for another extension, FILE_NOT_FOUND (message "FILE: no such
 * file") and ERROR_IN_READING_FILE with the osgBTF::Error message "FILE: problem". */
#pragma once

#include <string>

#include <osgDB/ReaderWriter>

namespace osgBTF::plugin {

class ReaderWriterBTF : public osgDB::ReaderWriter {
public:
    /** Claims `extension` (one of the eight above; btfzip also claims zip). */
    explicit ReaderWriterBTF(const std::string& extension);

    const char* className() const override { return "osgBTF material reader"; }

    ReadResult readNode(const std::string& file, const Options* options) const override;
    /** The same MaterialNode (osgconv reads its input through readObjectFile). */
    ReadResult readObject(const std::string& file, const Options* options) const override;
    /** Images and archives are OSG's zip plugin's business: for a ".zip" handed over to it where
     *  it is installed, FILE_NOT_HANDLED otherwise. */
    ReadResult readImage(const std::string& file, const Options* options) const override;
    using osgDB::ReaderWriter::openArchive;  // the stream overload stays the base's
    ReadResult openArchive(const std::string& file, ArchiveStatus status,
                           unsigned int indexBlockSizeHint, const Options* options) const override;
};

}  // namespace osgBTF::plugin
