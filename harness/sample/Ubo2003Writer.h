// osgBTF: writes a MeasuredBtf as a UBO2003/ATRIUM-style archive (formats.md section 1), for tests,
// benchmarks and exchange with tools that read the Bonn layout.
#pragma once

#include <string>

#include "core/MeasuredBtf.h"

namespace osgBTF {

/** Jpeg and Png store 8-bit values round(clamp(v, 0, 1) * 255) (no transfer curve, matching
 *  LoadOptions::DecodeCurve::Linear); Hdr is Radiance RGBE like ATRIUM_HDR; Exr is 32-bit float. */
enum class Ubo2003ImageFormat { Jpeg, Png, Hdr, Exr };

/** The member name "NNNNN tlTTT plPPP tvTTT pvPPP.ext" of one image. */
std::string ubo2003MemberName(int index, const Direction& light, const Direction& view,
                              Ubo2003ImageFormat format);

/** Writes every (light, view) image as a member named by ubo2003MemberName with index
 *  lightIndex * viewCount + viewIndex (81 * light + view for the Bonn set). Directions must be
 *  integer degrees (the names hold nothing else). Images are encoded in parallel; JPEG, PNG and
 *  EXR members are stored uncompressed (deflate gains nothing on them), HDR members deflated. The
 *  archive appears atomically: it is written to zipPath + ".tmp<pid>" and renamed. */
void writeUbo2003Zip(const MeasuredBtf& btf, const std::string& zipPath,
                     Ubo2003ImageFormat format = Ubo2003ImageFormat::Jpeg, int jpegQuality = 95);

/** The same images as files in a new folder (written as folder + ".tmp<pid>", then renamed; an
 * existing folder is an error rather than being merged into). */
void writeUbo2003Folder(const MeasuredBtf& btf, const std::string& folder,
                        Ubo2003ImageFormat format = Ubo2003ImageFormat::Jpeg, int jpegQuality = 95);

}  // namespace osgBTF
