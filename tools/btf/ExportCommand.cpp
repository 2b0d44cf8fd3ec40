// btf export MATERIAL OUTPUT: a fitted material written as another file: relight's web layout
// (OUTPUT = DIR/info.json, with its options), another tool's file (.ptm, .rti) or osgBTF's own.
#include <iostream>
#include <memory>

#include "core/Error.h"
#include "materials/Material.h"
#include "materials/MaterialFiles.h"
#include "materials/RelightLayoutWriter.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

Runner addExportCommand(CLI::App& app, CommonOptions&) {
    auto* command = app.add_subcommand(
        "export",
        "Write a fitted material as another file: DIR/info.json publishes a ptm, hsh or rbf "
        "material as relight's web layout, which OpenLIME shows in a browser (docs/"
        "real-captures.md, \"Publishing a capture\"); .ptm, .rti, .btfmat and .exr as btf fit "
        "-o writes them");
    struct Options {
        std::string input, output, layout = "auto";
        RelightWriteOptions web;
    };
    auto options = std::make_shared<Options>();
    command->add_option("material", options->input, "A fitted material (any file btf info reads)")
        ->required();
    command->add_option("output", options->output, "The file to write (DIR/info.json, .ptm, ...)")
        ->required();
    command
        ->add_option("--layout", options->layout,
                     "relight's layout: image (plane_N.jpg), deepzoom (relight's tile pyramid "
                     "per plane: plane_N.dzi + plane_N_files/) or auto (deepzoom above " +
                         std::to_string(kDeepZoomAbove) + " pixels on a side)")
        ->check(CLI::IsMember({"auto", "image", "deepzoom"}))
        ->capture_default_str();
    command->add_option("--quality", options->web.quality, "JPEG quality of the planes")
        ->check(CLI::Range(1, 100))
        ->capture_default_str();
    command->add_option("--tile-size", options->web.tileSize, "Deep-zoom tile size (pixels)")
        ->check(CLI::Range(16, 4096))
        ->capture_default_str();
    command->add_option("--overlap", options->web.overlap, "Deep-zoom tile overlap (pixels)")
        ->check(CLI::Range(0, 2048))
        ->capture_default_str();
    command
        ->add_option("--range-quantile", options->web.rangeQuantile,
                     "Each plane's 8-bit range covers this central fraction of its values (the "
                     "rest clamps; relight's default); 1 keeps every value")
        ->check(CLI::Range(1e-6, 1.0))
        ->capture_default_str();
    return [options] {
        const osg::ref_ptr<Material> material = loadMaterial(options->input);
        std::string method;
        const ForeignFileFormat* format = findForeignFile(options->output, &method);
        std::string lost;
        if (format && format->methods) {
            // relight's layout: the options above apply.
            options->web.layout = options->layout == "image" ? RelightWriteOptions::Layout::Image
                                  : options->layout == "deepzoom"
                                      ? RelightWriteOptions::Layout::DeepZoom
                                      : RelightWriteOptions::Layout::Automatic;
            lost = writeRelightLayout(*material, options->output, options->web);
        } else {
            lost = saveMaterial(*material, options->output);
        }
        if (!lost.empty()) std::cout << lost << "\n";
        std::cout << "wrote " << options->output << "\n";
    };
}

}  // namespace osgBTF::tool
