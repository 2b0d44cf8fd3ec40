#include "synthesis/Tileable.h"

#include <algorithm>
#include <string>

#include <tbb/parallel_for.h>

#include "core/Error.h"
#include "core/Progress.h"

namespace osgBTF {

namespace {

/** Spreads the jump between element 0 and element count-1 (stride apart) over the bands. */
void blendLine(float* line, std::size_t stride, int count, int border) {
    const float jump = line[std::size_t(count - 1) * stride] - line[0];
    for (int x = 0; x < border; ++x) {
        const float shift = 0.5f * jump * float(border - x) / (float(border) + 0.5f);
        line[std::size_t(x) * stride] += shift;
        line[std::size_t(count - 1 - x) * stride] -= shift;
    }
}

}  // namespace

int defaultTileBorder(int width, int height) {
    return std::max(1, std::min(width, height) / 8);
}

void validateTileBorder(int border, int width, int height) {
    if (border < 1 || 2 * border > std::min(width, height))
        throw Error("--border " + std::to_string(border) + ": must be in 1.." +
                    std::to_string(std::min(width, height) / 2) + " (half the " +
                    std::to_string(width) + "x" + std::to_string(height) +
                    " sample's smaller side)");
}

MeasuredBtf makeTileable(const MeasuredBtf& sample, int border) {
    const int w = sample.width(), h = sample.height();
    validateTileBorder(border, w, h);
    MeasuredBtf out(w, h, sample.views(), sample.lights(), sample.storage());
    out.source = sample.source;
    Progress progress("make-tileable", sample.imageCount());
    tbb::parallel_for(std::size_t(0), sample.imageCount(), [&](std::size_t i) {
        const std::size_t view = i / sample.lightCount(), light = i % sample.lightCount();
        std::vector<float> image = sample.image(view, light);
        for (int c = 0; c < 3; ++c) {
            for (int y = 0; y < h; ++y)  // left/right edges: along each row
                blendLine(image.data() + std::size_t(y) * w * 3 + c, 3, w, border);
            for (int x = 0; x < w; ++x)  // then top/bottom edges: along each column
                blendLine(image.data() + std::size_t(x) * 3 + c, std::size_t(w) * 3, h, border);
        }
        out.setImage(view, light, image.data());
        progress.advance();
    });
    progress.finish();
    return out;
}

}  // namespace osgBTF
