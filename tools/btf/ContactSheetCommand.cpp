// btf contact-sheet FILE -o PNG: a grid of (view, light) images for a first look at a BTF.
#include <algorithm>
#include <iostream>
#include <memory>
#include <sstream>

#include <glm/geometric.hpp>

#include "core/Error.h"
#include "core/FloatImage.h"
#include "core/MeasuredBtf.h"
#include "loaders/LoadBtf.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

namespace {

std::vector<Direction> parseDirections(const std::string& text, const std::string& option) {
    std::vector<Direction> result;
    std::istringstream in(text);
    std::string item;
    while (std::getline(in, item, ';')) {
        Direction d;
        char comma = 0;
        std::istringstream pair(item);
        if (!(pair >> d.theta >> comma >> d.phi) || comma != ',')
            throw Error(option + ": '" + item + "' is not THETA,PHI in degrees");
        result.push_back(d);
    }
    if (result.empty()) throw Error(option + ": no directions given");
    return result;
}

/** Index of the measured direction closest to d. */
std::size_t nearest(const DirectionSet& set, const Direction& d) {
    std::size_t best = 0;
    float bestDot = -2;
    for (std::size_t i = 0; i < set.size(); ++i) {
        const float dot = glm::dot(set.vector(i), d.toVector());
        if (dot > bestDot) {
            bestDot = dot;
            best = i;
        }
    }
    return best;
}

/** The measured directions nearest to the asked ones, each once, in the order asked: a capture
 *  with one view (an RTI set) gets one row, not the same row three times. */
std::vector<std::size_t> nearestDistinct(const DirectionSet& set,
                                         const std::vector<Direction>& asked) {
    std::vector<std::size_t> result;
    for (const Direction& d : asked) {
        const std::size_t i = nearest(set, d);
        if (std::find(result.begin(), result.end(), i) == result.end()) result.push_back(i);
    }
    return result;
}

}  // namespace

Runner addContactSheetCommand(CLI::App& app, CommonOptions& common) {
    auto* command = app.add_subcommand(
        "contact-sheet",
        "Write a PNG grid of (view, light) images: one row per view, one column per light "
        "(nearest measured directions, each once)");
    struct Options {
        std::string input, output;
        std::string views = "0,0;45,0;75,0";
        std::string lights = "0,0;45,0;75,0;75,90;75,180";
        float exposure = 1.0f;
    };
    auto options = std::make_shared<Options>();
    command->add_option("FILE", options->input, "Measured BTF (zip, folder or .btf)")->required();
    command->add_option("-o,--output", options->output, "Output image (.png, .jpg or .exr)")
        ->required();
    command->add_option("--views", options->views, "View directions THETA,PHI;THETA,PHI;...")
        ->capture_default_str();
    command->add_option("--lights", options->lights, "Light directions THETA,PHI;...")
        ->capture_default_str();
    command->add_option("--exposure", options->exposure, "Scale applied before writing")
        ->capture_default_str();
    addLoadOptions(*command, common);
    return [&common, options] {
        const MeasuredBtf btf = loadMeasuredBtf(options->input, common.loadOptions());
        const auto views = nearestDistinct(btf.views(), parseDirections(options->views, "--views"));
        const auto lights =
            nearestDistinct(btf.lights(), parseDirections(options->lights, "--lights"));
        const int gap = 2, w = btf.width(), h = btf.height();
        FloatImage sheet(int(lights.size()) * (w + gap) + gap, int(views.size()) * (h + gap) + gap,
                         3);
        std::fill(sheet.pixels.begin(), sheet.pixels.end(), 0.15f);
        for (std::size_t row = 0; row < views.size(); ++row) {
            const std::size_t v = views[row];
            for (std::size_t col = 0; col < lights.size(); ++col) {
                const std::size_t l = lights[col];
                const std::vector<float> image = btf.image(v, l);
                for (int y = 0; y < h; ++y)
                    for (int x = 0; x < w; ++x)
                        for (int c = 0; c < 3; ++c)
                            // MeasuredBtf rows are bottom-up; image files are top-down.
                            sheet.at(gap + int(col) * (w + gap) + x, gap + int(row) * (h + gap) + y,
                                     c) =
                                options->exposure * image[(std::size_t(h - 1 - y) * w + x) * 3 + c];
            }
        }
        writeFloatImage(sheet, options->output);
        std::cout << "wrote " << options->output << ": " << views.size()
                  << (views.size() == 1 ? " view x " : " views x ") << lights.size()
                  << (lights.size() == 1 ? " light of " : " lights of ") << options->input << "\n";
    };
}

}  // namespace osgBTF::tool
