// osgBTF: options shared by the measured-BTF loaders.
#pragma once

#include <string>

#include "core/MeasuredBtf.h"

namespace osgBTF {

class TexelFactorSink;

struct LoadOptions {
    /** Storage of the loaded MeasuredBtf; Half halves the memory at ~3 significant digits. */
    Storage storage = Storage::Float;

    /** How integer (8/16-bit) image values map to linear radiance; float images are used as is.
     *  Auto, the default, is each format's own convention: Linear for the Bonn formats (seed
     *  paper 004 says the UBO2003 8-bit data keep the central bits of linear 12-bit raw images),
     *  Srgb for RTI capture sets (camera photos are sRGB-encoded). Srgb and Gamma22 also serve
     *  other display-encoded data (btf-rendering assumes gamma 2.2). */
    enum class DecodeCurve { Auto, Linear, Srgb, Gamma22 };
    DecodeCurve curve = DecodeCurve::Auto;

    /** Where openBtfSource keeps an RTI capture's values: Memory (a MeasuredBtf), Disk (decoded
     *  once to a temporary file and read back in blocks: OutOfCoreImageSet, for captures larger
     *  than memory), or Auto, the default: Memory when its values take at most a quarter of the
     *  memory limit, else Disk. The tools' --storage disk; loadMeasuredBtf always reads into
     *  memory. */
    enum class Placement { Auto, Memory, Disk };
    Placement placement = Placement::Auto;

    /** Label of the progress bar (osgBTF::Progress draws only when enabled globally); empty means
     *  "loading <file name>". */
    std::string progressLabel;

    /** readUbo2014 only: read everything but the factor matrices U and SxV, which are skipped
     *  (every size still checked against the file) and left with 0 rows and their component
     *  count as columns (S is read). For describing a file (`btf info`) in milliseconds. */
    bool headerOnly = false;

    /** readUbo2014 only: where the texel factors (SxV) go as they are read, in the file's bytes,
     *  instead of float matrices (which are then left with 0 rows): for a material that keeps
     *  them in a layout of its own (core/FactoredBtf.h, TexelFactorSink). Not owned. */
    TexelFactorSink* texelFactors = nullptr;
};

/** "auto", "linear", "srgb", "gamma22" (the tools' --decode values) to the curve; anything else
 *  is Auto. */
inline LoadOptions::DecodeCurve decodeCurveFromName(const std::string& name) {
    using Curve = LoadOptions::DecodeCurve;
    return name == "linear"    ? Curve::Linear
           : name == "srgb"    ? Curve::Srgb
           : name == "gamma22" ? Curve::Gamma22
                               : Curve::Auto;
}

/** What `btf info` says a curve is: "linear", "sRGB", "gamma 2.2" ("auto" for Auto). */
inline const char* decodeCurveLabel(LoadOptions::DecodeCurve curve) {
    switch (curve) {
        case LoadOptions::DecodeCurve::Linear:
            return "linear";
        case LoadOptions::DecodeCurve::Srgb:
            return "sRGB";
        case LoadOptions::DecodeCurve::Gamma22:
            return "gamma 2.2";
        case LoadOptions::DecodeCurve::Auto:
            break;
    }
    return "auto";
}

}  // namespace osgBTF
