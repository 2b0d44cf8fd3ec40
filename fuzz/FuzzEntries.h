// osgBTF: the bodies of the libFuzzer targets (fuzz/targets/), one per parser, compiled both into
// the fuzzers (clang, -fsanitize=fuzzer) and into the regression test that replays
// fuzz/regression/ in every normal build (tests/fuzz_regression_test.cpp), so CI replays every
// input that once crashed without needing clang. An entry may throw osgBTF::Error (refusing bad
// input is its job); anything else escaping it, a crash, a hang or a sanitizer report is a bug.
#pragma once

#include <cstddef>
#include <cstdint>
#include <string>
#include <vector>

namespace osgBTF::fuzz {

/** One parser under test: `name` is its fuzz target (fuzz_<name>) and its folders
 *  fuzz/regression/<name>/ and fuzz/dict/<name>.dict. */
struct Target {
    const char* name;
    void (*run)(const std::uint8_t* data, std::size_t size);
};

/** Every target, in the order of fuzz/README.md. */
const std::vector<Target>& targets();
/** The target called `name`, or nullptr. */
const Target* findTarget(const std::string& name);

/** Once per process, before any entry: a 256 MiB memory limit for the measured-data guard (so a
 *  claimed size is refused rather than allocated), progress bars and OSG notices off, and
 *  `fixtures` as the folder of the files the plugin-name target may name (fuzz/fixtures/). */
void setUp(const std::string& fixtures);

/** The bytes as a UBO2003 zip archive: mayBeUbo2003 (member names only), then loadUbo2003
 *  (archive handling, member names, image decoding of every member through OpenImageIO). */
void ubo2003Zip(const std::uint8_t* data, std::size_t size);
/** The bytes as a UBO2014 .btf: readUbo2014 header-only, then whole, then decodeUbo2014 when the
 *  decoded BTF is small (DFMF colour models, FMF dynamic-range reduction, cosine flag). */
void ubo2014(const std::uint8_t* data, std::size_t size);
/** The bytes as a fitted-material file (core/FittedMaterialFile, OpenEXR multi-part). */
void fittedMaterial(const std::uint8_t* data, std::size_t size);
/** The RTI field's fitted files: .ptm (input starting "PTM") or .rti, read as materials. */
void rtiFiles(const std::uint8_t* data, std::size_t size);
/** The bytes as a coordinate map (core/CoordinateMap, OpenEXR). */
void coordinateMap(const std::uint8_t* data, std::size_t size);
/** The bytes as "input.btfmat" through the osgdb_btfmat reader (ReaderWriterBTF::readNode): the
 *  fitted-material file, then the method's own checks of its textures (materialFromFile). */
void btfmatPlugin(const std::uint8_t* data, std::size_t size);
/** First line: a file name for the readers (a pseudo-loader name MODEL.(MATERIAL,...).btfmaterial,
 *  or a .btfmat/.btf/.zip name); the rest: the -O option string. Names resolve in the fixtures
 *  folder only (names with '/' or "..", and cache=, are skipped: they would reach the rest of the
 *  file system); the fit cache is off. */
void pluginNames(const std::uint8_t* data, std::size_t size);
/** The bytes as an OSG ASCII scene (.osgt) holding osgBTF::MaterialNodes, read from a
 *  std::istream by osgDB's osgt reader with osgBTF's serializers (material file names resolve in
 *  the fixtures folder, embedded FittedMaterials are parsed). */
void sceneFile(const std::uint8_t* data, std::size_t size);

/** BSVTF tile sets (streaming/TileSet.h): bytes starting with "osgBTF-bsvtf" as an index
 *  (TileSetIndex::parse), anything else as a dct tile payload of a 16-texel tile (T = 8, P = 4)
 *  decoded without and with a prediction (TileCodec's decodeTile). */
void bsvtfTiles(const std::uint8_t* data, std::size_t size);

}  // namespace osgBTF::fuzz
