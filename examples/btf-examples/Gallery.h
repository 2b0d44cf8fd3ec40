// btf-examples --gallery: every method in the situations a user first looks at (a close-up, the
// surface receding into the distance, a grazing view, environment lighting, cast shadows),
// rendered headless to PNG, with each method's error, size and pass time on one HTML page.
#pragma once

#include <string>
#include <vector>

namespace osgBTF::examples {

struct GalleryOptions {
    std::string outputDir;
    int size = 32;                     ///< texels per side of the built-in sample
    std::vector<std::string> methods;  ///< empty: every method `btf compare --methods all` runs
    int pictureSize = 256;             ///< pixels per side of each picture
};

/** One picture column of the gallery. */
struct GalleryView {
    std::string name;  ///< file name part, e.g. "close-up"
    std::string caption;
};

/** The gallery's views, in column order. */
const std::vector<GalleryView>& galleryViews();

/** Writes into options.outputDir (replaced as a whole: built in a temporary folder beside it and
 *  renamed at the end, so a failure leaves any previous gallery as it was):
 *    sample.zip                      the built-in sample at size x size (a UBO2003 zip)
 *    compare/                        `btf compare` of it with the methods (fits, report.md)
 *    pictures/METHOD-VIEW.png        one per method and galleryViews() entry (sRGB)
 *    index.html                      the pictures side by side, a row per method, with its
 *                                    average error, bytes per texel and pass time
 *  Fits run as `btf fit` processes (the btf tool beside this program). Throws Error naming the
 *  folder or file and the problem; a method whose fit fails gets a row saying so. Returns the
 *  path of index.html. */
std::string writeGallery(const GalleryOptions& options);

}  // namespace osgBTF::examples
