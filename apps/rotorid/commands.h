#pragma once

// Subcommands of the rotorid CLI. Each Add*Command registers its options on `root` and returns
// the function that runs it once the command line is parsed. apps/ holds only argument parsing
// and printing; the work is done by the library.

#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "options.h"
#include "rotorid/ident/checks.h"
#include "rotorid/ident/identify.h"
#include "rotorid/ident/tls.h"
#include "rotorid/io/flight_selection.h"
#include "rotorid/io/flight_source.h"
#include "rotorid/report/html_report.h"

namespace rotorid::cli {

using RunFunction = std::function<int()>;
struct Command {
  CLI::App* app = nullptr;
  RunFunction run;
  // --out may name an existing folder (export's model directories), else it must be a file.
  bool out_may_be_folder = false;
};

// --config FILE.yaml (apps/rotorid/config.cc), on the root once every subcommand is registered,
// and the file's options for the report of `app` (null when no file was given).
void AddConfigOption(CLI::App* root);
nlohmann::json ConfigJson(const CLI::App& app);

// Human-readable output.
void PrintWarnings(const std::vector<std::string>& warnings);
// Prints the checks that did not pass (errors even under --quiet) and a summary line; returns the
// exit code they call for: 3 when a check has status error, else 0.
int PrintChecks(const std::vector<Check>& checks, bool quiet);

Command AddSimulateCommand(CLI::App& root);
Command AddIdentifyCommand(CLI::App& root);
Command AddValidateCommand(CLI::App& root);
Command AddRefineCommand(CLI::App& root);
Command AddDelayCommand(CLI::App& root);
Command AddAblateCommand(CLI::App& root);
Command AddDiagnoseCommand(CLI::App& root);
Command AddVehicleCommand(CLI::App& root);
Command AddExportCommand(CLI::App& root);
Command AddBatchCommand(CLI::App& root);
Command AddPredictCommand(CLI::App& root);

// Output-path and effect-list checks at parse time, and --config, on every command.
void ApplyConventions(const std::vector<Command>& commands);
// Once parsed, before any work: no output (--json, --out, --truth, --vehicle-out, --report) is one
// of the command's input files (the same file, also through a hard link or a symlink) or another
// output. Throws UsageError naming both options.
void CheckOutputsAgainstInputs(const CLI::App& app);
// "run 'rotorid SUB --help' for its options", for the subcommand on the command line.
std::string UsageHint(const CLI::App& root, int argc, char** argv);
// Non-empty when argv names no known subcommand: what to tell the user.
std::string UnknownSubcommand(const CLI::App& root, int argc, char** argv);

}  // namespace rotorid::cli
