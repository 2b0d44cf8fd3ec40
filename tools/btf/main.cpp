// btf: inspect, generate, fit, evaluate, compare, synthesize, tile, export and batch-score measured
// BTFs. `btf --help` and `btf <command> --help` document every option.
#include <sys/prctl.h>
#include <unistd.h>

#include <csignal>
#include <cstdio>
#include <cstdlib>
#include <iostream>
#include <string>

#include "core/Error.h"
#include "core/MeasuredBtf.h"
#include "core/Progress.h"
#include "scene/OwnPlugins.h"
#include "tools/btf/Commands.h"

namespace osgBTF::tool {

LoadOptions CommonOptions::loadOptions() const {
    LoadOptions options;
    options.storage = storage == "half" ? Storage::Half : Storage::Float;
    options.placement = storage == "disk"   ? LoadOptions::Placement::Disk
                        : storage == "auto" ? LoadOptions::Placement::Auto
                                            : LoadOptions::Placement::Memory;
    options.curve = decodeCurveFromName(decode);
    return options;
}

void addLoadOptions(CLI::App& command, CommonOptions& common) {
    command
        .add_option("--storage", common.storage,
                    "Where measured values are kept: float or half in memory, disk (an RTI "
                    "capture's photos decoded once to a temporary file in $OSGBTF_CACHE_DIR, "
                    "$TMPDIR or /tmp and read back in blocks: captures larger than memory), or "
                    "auto (float in memory when it takes at most a quarter of the memory limit, "
                    "else disk)")
        ->check(CLI::IsMember({"auto", "float", "half", "disk"}))
        ->capture_default_str();
    command
        .add_option("--decode", common.decode,
                    "Decode curve for 8/16-bit images: auto (the format's own: linear for the "
                    "Bonn data, linear per Sattler 2003; srgb for RTI photos), linear, srgb or "
                    "gamma22")
        ->check(CLI::IsMember({"auto", "linear", "srgb", "gamma22"}))
        ->capture_default_str();
}

}  // namespace osgBTF::tool

namespace {

/** A fit that `btf compare` runs dies with it: SIGKILL gives compare no chance to stop its
 *  children, and an orphaned fit would go on for as long as the fit takes, writing into a work
 *  folder nobody reads. Compare names itself in OSGBTF_PARENT_PID (harness/FitRunner.cpp). */
void dieWithParent() {
    const char* parent = std::getenv("OSGBTF_PARENT_PID");
    if (!parent || !*parent) return;
    prctl(PR_SET_PDEATHSIG, SIGKILL);
    // The parent may have died before prctl: then this process already has a new parent.
    if (std::to_string(getppid()) != parent) _exit(1);
}

}  // namespace

int main(int argc, char** argv) {
    using namespace osgBTF;
    dieWithParent();
    useOwnPlugins();  // osgdb_btfexr for --env sky.exr, without OSG_LIBRARY_PATH
    CLI::App app{
        "btf: measured Bidirectional Texture Functions for OpenSceneGraph.\n"
        "Reads UBO2003/ATRIUM zips or folders, UBO2014 .btf files; writes the built-in sample."};
    app.require_subcommand(1);
    tool::CommonOptions common;
    bool progress = isatty(STDERR_FILENO);
    app.add_option("--memory-limit", common.memoryLimit,
                   "Largest allowed allocation of measured data, e.g. 8G (default: 3/4 of RAM or "
                   "$OSGBTF_MEMORY_LIMIT)");
    app.add_flag("--progress,!--no-progress", progress,
                 "Show progress bars on stderr (default: when stderr is a terminal)");
    const std::vector<tool::Runner> runners{
        tool::addInfoCommand(app, common),         tool::addSampleCommand(app, common),
        tool::addContactSheetCommand(app, common), tool::addFitCommand(app, common),
        tool::addEvalCommand(app, common),         tool::addCompareCommand(app, common),
        tool::addSynthesizeCommand(app, common),   tool::addMakeTileableCommand(app, common),
        tool::addTilesCommand(app, common),        tool::addBatchCommand(app, common),
        tool::addExportCommand(app, common)};
    try {
        app.parse(argc, argv);
        Progress::setEnabled(progress);
        if (!common.memoryLimit.empty()) setMemoryLimit(parseBytes(common.memoryLimit));
        const auto subcommands = app.get_subcommands({});
        for (std::size_t i = 0; i < subcommands.size(); ++i)
            if (subcommands[i]->parsed()) runners.at(i)();
    } catch (const CLI::ParseError& e) {
        return app.exit(e);
    } catch (const Error& e) {
        std::cerr << "btf: error: " << e.what() << "\n";
        return 1;
    } catch (const std::exception& e) {
        std::cerr << "btf: unexpected error: " << e.what() << "\n";
        return 2;
    }
    return 0;
}
