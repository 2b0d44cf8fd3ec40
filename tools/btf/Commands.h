// The `btf` tool: one file per subcommand (`make-tileable` shares SynthesizeCommand.cpp with
// `synthesize`: both drive synthesis/), registered from main.cpp.
#pragma once

#include <functional>
#include <map>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "loaders/LoadOptions.h"

namespace osgBTF::tool {

/** Options every subcommand that reads a measured BTF shares. */
struct CommonOptions {
    std::string memoryLimit;
    std::string storage = "auto";
    std::string decode = "auto";
    LoadOptions loadOptions() const;
};

/** Each adds its subcommand and returns what runs it (after the global options are applied). */
using Runner = std::function<void()>;
Runner addInfoCommand(CLI::App& app, CommonOptions& common);
Runner addSampleCommand(CLI::App& app, CommonOptions& common);
Runner addContactSheetCommand(CLI::App& app, CommonOptions& common);
Runner addFitCommand(CLI::App& app, CommonOptions& common);
Runner addEvalCommand(CLI::App& app, CommonOptions& common);
Runner addCompareCommand(CLI::App& app, CommonOptions& common);
Runner addSynthesizeCommand(CLI::App& app, CommonOptions& common);
Runner addMakeTileableCommand(CLI::App& app, CommonOptions& common);
Runner addTilesCommand(CLI::App& app, CommonOptions& common);
Runner addBatchCommand(CLI::App& app, CommonOptions& common);
Runner addExportCommand(CLI::App& app, CommonOptions& common);

/** "laf, slaf, rf": the registered methods that have fit option `key` (for help texts). */
std::string methodListWithOption(const std::string& key);

/** "a,b,,c" -> {a, b, c}. */
std::vector<std::string> splitList(const std::string& text);
/** Parses --set METHOD:KEY=VALUE settings into METHOD -> KEY -> VALUE; throws Error
 *  "--set: 'X' is not METHOD:KEY=VALUE". */
void addMethodSettings(const std::vector<std::string>& settings,
                       std::map<std::string, std::map<std::string, std::string>>& into);

/** Adds --storage, --decode to a subcommand that loads measured data. */
void addLoadOptions(CLI::App& command, CommonOptions& common);

}  // namespace osgBTF::tool
