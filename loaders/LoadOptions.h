// osgBTF: options shared by the measured-BTF loaders.
#pragma once

#include <string>

#include "core/MeasuredBtf.h"

namespace osgBTF {

struct LoadOptions {
    /** Storage of the loaded MeasuredBtf; Half halves the memory at ~3 significant digits. */
    Storage storage = Storage::Float;

    /** How integer (8/16-bit) image values map to linear radiance; float images are used as is.
     *  Linear is the default because seed paper 004 says the UBO2003 8-bit data keep the central
     *  bits of linear 12-bit raw images; Srgb and Gamma22 exist for data sets that were
     *  display-encoded (btf-rendering assumes gamma 2.2). */
    enum class DecodeCurve { Linear, Srgb, Gamma22 };
    DecodeCurve curve = DecodeCurve::Linear;

    /** Label of the progress bar (osgBTF::Progress draws only when enabled globally); empty means
     *  "loading <file name>". */
    std::string progressLabel;

    /** readUbo2014 only: read everything but the factor matrices U and SxV, which are skipped
     *  (every size still checked against the file) and left with 0 rows and their component
     *  count as columns (S is read). For describing a file (`btf info`) in milliseconds. */
    bool headerOnly = false;
};

}  // namespace osgBTF
