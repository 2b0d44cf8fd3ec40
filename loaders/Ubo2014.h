// osgBTF: reader for UBO2014 ".btf" files (DFMF and FMF factorised BTFs, formats.md section 2).
#pragma once

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "core/FactoredBtf.h"
#include "core/MeasuredBtf.h"
#include "loaders/LoadOptions.h"

namespace osgBTF {

/** Everything a UBO2014 file holds: the factorisation (which an FMF material renders directly)
 *  plus the file's own meta data, kept so that files round-trip. */
struct Ubo2014Factors : FactoredBtf {
    std::string signature;      ///< as read, e.g. "!DFMF08FCR"; the writer derives its own
    bool hasRotations = false;  ///< the trailing 'R' of the signature

    std::uint32_t metaVersion = 4;  ///< 1..4; decides which optional meta fields exist
    std::string measurementSetup, imageSensor, lightSource;
    float ppmm = 0.0f;
    std::array<float, 3> rgbScale{1.0f, 1.0f, 1.0f};  ///< stored, never applied (as btflib)
    std::string xml;
    std::vector<std::string> channelNames{"R", "G", "B"};

    std::vector<std::array<float, 9>> rotations;  ///< only with hasRotations; unused for decoding

    int scalarSize = 4;  ///< bytes per stored scalar (2 = half, 4 = float, 8 = double)

    std::uint32_t maxComponents = 0;  ///< DFMF only

    // FMF only.
    bool extendedHeader = true;  ///< "!FMF12FCE" (header version byte present) vs "!FMF06FC"
    int headerVersion = 0;       ///< 0..2
    int heightMapWidth = 0, heightMapHeight = 0;
    std::vector<float> heightMap;  ///< rows of heightMapWidth values, file order
};

/** Reads and validates a .btf file completely (every byte accounted for). Refuses PVF, BDI,
 *  unknown signatures, unsupported colour models and channel counts other than 3, and checks
 *  memoryLimit() and the file size before every large allocation. */
Ubo2014Factors readUbo2014(const std::string& path, const LoadOptions& options = {});

/** Reconstructs every value (colour model, then dynamic-range reduction, then cosine division,
 *  as btflib) into a MeasuredBtf with bottom-up rows: FactoredBtf::decode with the options'
 *  storage and progress label. */
MeasuredBtf decodeUbo2014(const Ubo2014Factors& factors, const LoadOptions& options = {});

/** readUbo2014 + decodeUbo2014. */
MeasuredBtf loadUbo2014(const std::string& path, const LoadOptions& options = {});

/** Writes factors as a .btf file (meta version factors.metaVersion, scalars of
 *  factors.scalarSize). Meant for synthetic files in tests and benchmarks; the file appears
 *  atomically (path + ".tmp", then renamed). */
void writeUbo2014(const Ubo2014Factors& factors, const std::string& path);

/** Writes a factorisation made elsewhere (e.g. a fitted `fmf` material's, FmfMaterial::factors)
 *  as a .btf file in the form the format's reference readers expect (formats.md 2.9): FMF as
 *  "!FMF12FCE" with header version 1 (its DRR flag, no height map), DFMF as "!DFMF08FC"; meta
 *  version 4 with channels R, G, B and the factors' cosine flag; scalars of `scalarSize` (2 half,
 *  4 float). The measurement meta data (setup, sensor, light source, ppmm, rgb scale, XML) come
 *  from `meta` when given (the input file's, say), else stay empty. Atomic like writeUbo2014. */
void writeFactorsAsUbo2014(const FactoredBtf& factors, const std::string& path, int scalarSize,
                           const Ubo2014Factors* meta = nullptr);

}  // namespace osgBTF
