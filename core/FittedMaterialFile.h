// osgBTF: the one-file-per-fitted-material container shared by every compression method.
//
// File format (container version 1): an OpenEXR multi-part file, ZIP-compressed (lossless).
//   - one part per texture; part name = texture name;
//   - channels "<texture>.Y" (1 channel), "<texture>.R/.G" (2), "<texture>.R/.G/.B" (3),
//     "<texture>.R/.G/.B/.A" (4), "<texture>.c0" .. "<texture>.c<N-1>" (5 or more), all HALF or
//     all FLOAT; prefixed so that exrheader/oiiotool list every part's channels distinctly;
//   - the part's data window is width x (height * depth): a 3D texture stores its slices one
//     below the other, slice 0 at the top; each slice is stored upright (top row first, as EXR
//     viewers expect), so a file opened in a viewer looks like the texture;
//   - every part carries the same string attributes "osgBTF.method", "osgBTF.views",
//     "osgBTF.lights" (DirectionSet::serialize()) and "osgBTF.param.<key>", the int attribute
//     "osgBTF.version" (= 1), and its own int attribute "osgBTF.depth".
#pragma once

#include <cstdint>
#include <functional>
#include <map>
#include <string>
#include <utility>
#include <vector>

#include <Imath/half.h>

#include "core/Directions.h"

namespace osgBTF {

/** Version written into "osgBTF.version"; loadFittedMaterial refuses any other. */
constexpr int kFittedMaterialVersion = 1;

/** One texture of a fitted material: a 2D image, or a 3D one made of `depth` slices.
 *
 *  data layout: [z][y][x][channel], rows BOTTOM-UP within each slice (y = 0 is the bottom row, as
 *  in osg::Image and MeasuredBtf), so data can be handed to an osg::Image as it is:
 *  data[((z * height + y) * width + x) * channels + c]. */
struct MaterialTexture {
    enum PixelKind { Half, Float, UNorm8 };
    /** "half", "float", "unorm8": the name the methods' storage options use. */
    static const char* kindName(PixelKind kind) {
        return kind == UNorm8 ? "unorm8" : kind == Half ? "half" : "float";
    }

    std::string name;
    int width = 0;
    int height = 0;
    int depth = 1;
    int channels = 0;
    /** Precision in the file (and on the GPU). Half data is rounded to half when saved; kept as
     *  float in memory. UNorm8 data (8-bit fixed point, as Meseth et al. 2003 store colours) must
     * be multiples of 1/255 in [0, 1]; the file holds the integers 0..255 in half channels (exact)
     *  with the part attribute osgBTF.storage = "unorm8", and GPUs get GL_RGBA8-style textures. */
    PixelKind kind = Float;
    std::vector<float> data;
    /** A UNorm8 texture may hold its values here instead, as the integers 0..255 (value = byte /
     *  255.0f): a quarter of the memory, for models of gigabytes (PCA of a full-size UBO2014
     *  file holds 1.2 GB instead of 4.6). */
    std::vector<std::uint8_t> bytes = {};  // "= {}": aggregate initialisers may leave it out
    /** A Half texture may hold its values here instead, as they are stored: half the memory
     *  (fmf keeps a full-size UBO2014 file's Eigen-Textures this way, 92 MiB instead of 183).
     *  At most one of `data`, `bytes` and `halves` is non-empty; saveFittedMaterial and the GPU
     *  upload take any; loadFittedMaterial fills `data` or, as CompactTextures says, these. */
    std::vector<Imath::half> halves = {};

    std::size_t valueCount() const {
        return std::size_t(width) * std::size_t(height) * std::size_t(depth) *
               std::size_t(channels);
    }
    /** Values held, in `data`, `bytes` or `halves`. */
    std::size_t storedCount() const {
        return !bytes.empty() ? bytes.size() : !halves.empty() ? halves.size() : data.size();
    }
    /** Value i, from `data`, `bytes` or `halves`. */
    float value(std::size_t i) const {
        return !bytes.empty()    ? float(bytes[i]) / 255.0f
               : !halves.empty() ? float(halves[i])
                                 : data[i];
    }
    /** Turns `bytes` or `halves`, if any, into `data`. */
    void unpack() {
        if (bytes.empty() && halves.empty()) return;
        data.resize(storedCount());
        for (std::size_t i = 0; i < data.size(); ++i) data[i] = value(i);
        std::vector<std::uint8_t>().swap(bytes);
        std::vector<Imath::half>().swap(halves);
    }
};

/** Everything a compression method fitted for one material. */
struct FittedMaterial {
    /** Method name, e.g. "lpca" (the key the renderers use to pick their shaders). */
    std::string method;
    /** Method-specific settings and scalars, as text (e.g. "components" -> "8"). */
    std::map<std::string, std::string> parameters;
    DirectionSet views, lights;
    std::vector<MaterialTexture> textures;
    /** Where it was loaded from (set by loadFittedMaterial); used in error messages. */
    std::string source;

    /** The texture called `name`, or nullptr. */
    const MaterialTexture* findTexture(const std::string& name) const;
    /** The texture called `name`; throws Error "SOURCE: fitted material 'METHOD' has no texture
     *  'NAME' (textures: a, b)". */
    const MaterialTexture& texture(const std::string& name) const;
    /** The same, to take its values (a method's fromFile owns the loaded file). */
    MaterialTexture& texture(const std::string& name) {
        return const_cast<MaterialTexture&>(std::as_const(*this).texture(name));
    }
    /** The parameter `key`; throws Error naming the missing key. */
    const std::string& parameter(const std::string& key) const;
};

/** Writes `material` to `path` (format above) atomically: on any error the Error names the file
 *  and the problem, and an existing file at `path` is left as it was. Throws Error for an empty
 *  method, no textures, empty/duplicate texture names, empty parameter keys, data whose size does
 *  not match width*height*depth*channels, and half textures with finite values beyond 65504. */
void saveFittedMaterial(const FittedMaterial& material, const std::string& path);

/** Which textures loadFittedMaterial hands over as stored rather than as floats in `data`: a
 *  method that keeps them so takes them without a copy (loadMaterial asks for what the file's
 *  method takes, MethodInfo::compactTextures). */
struct CompactTextures {
    bool bytes = false;   ///< 8-bit textures in `bytes`: a quarter of the floats' memory
    bool halves = false;  ///< half textures in `halves`: half of it
};

/** Reads a file written by saveFittedMaterial. Float textures come back bit-exact, half ones as
 *  the half values, 8-bit ones as the byte / 255 values; in `data` unless `compact` says
 *  otherwise. Throws Error "PATH: problem" for a missing, empty, corrupt or truncated file, a
 *  file that is not OpenEXR, "PATH: not an osgBTF fitted-material file (no osgBTF.method
 *  attribute)", an unsupported "osgBTF.version", or a part whose channels do not follow the
 *  layout above. */
FittedMaterial loadFittedMaterial(const std::string& path, CompactTextures compact = {});
/** The same, with the forms chosen for the file's method (read before any texture). */
FittedMaterial loadFittedMaterial(
    const std::string& path,
    const std::function<CompactTextures(const std::string& method)>& compactFor);

}  // namespace osgBTF
