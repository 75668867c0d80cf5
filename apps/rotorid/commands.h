#pragma once

// Subcommands of the rotorid CLI. Each Add*Command registers its options on `root` and returns
// the function that runs it once the command line is parsed. apps/ holds only argument parsing
// and printing; the work is done by the library.

#include <CLI/CLI.hpp>
#include <functional>
#include <nlohmann/json.hpp>
#include <stdexcept>
#include <string>
#include <vector>

#include "rotorid/commands/command_input.h"
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

// Options every analysing subcommand shares (INTERFACE.md section 4).
struct FlightOptions {
  std::vector<std::string> vehicle_paths;
  std::vector<std::string> log_paths;
  std::vector<double> weights;
  std::vector<std::string> validate_vehicle_paths;
  std::vector<std::string> validate_log_paths;
  std::vector<std::string> windows;           // --window START,END, paired in order with --log
  std::vector<std::string> validate_windows;  // --validate-window, paired with --validate-log
  std::string segment = "auto";
  std::string json_path;
  std::string report_dir;
  bool quiet = false;
  bool verbose = false;
};

// Options of the identification shared by identify, refine, delay, ablate and diagnose.
struct IdentifyCliOptions {
  std::string method = "noise-aware";
  std::string source = "imu";
  std::vector<std::string> fixed_zero;
  std::string rotor_signal = "auto";
  std::string column_map;
  std::string first_moment = "shared";
  IdentifyOptions identify;
};

// Registers --vehicle/--log/--weight/--window (and --validate-vehicle/--validate-log/--validate-window
// when `held_out`), --segment, --json, --report, --quiet, --verbose.
void AddFlightOptions(CLI::App* app, FlightOptions* options, bool held_out);
// Registers the signal-processing and TLS options.
void AddIdentifyOptions(CLI::App* app, IdentifyCliOptions* options);
// Registers --first-moment (identify, refine, delay: the commands whose every flight is one the
// parameters are identified on, or whose held-out flights get their own first moment fitted).
void AddFirstMomentOption(CLI::App* app, IdentifyCliOptions* options);
// Turns the parsed strings into library options (throws rotorid::Error on invalid values).
IdentifyOptions ResolveIdentifyOptions(IdentifyCliOptions* options);
// The reader options of --rotor-signal and --column-map (checked by ResolveCommandInput).
FlightSourceOptions SourceOptions(const IdentifyCliOptions& options);

// The library's input options of a command line (the flights, --segment, the rotor signal and
// column map, --config, --report, --quiet; "read:" lines and notes printed unless quiet). Throws
// UsageError for unpaired options; the caller then validates its own and calls MarkOptionsValidated.
CommandInputOptions ResolveCommandInput(const CLI::App& app, const FlightOptions& flights,
                                        const FlightSourceOptions& source);

// --config FILE.yaml (apps/rotorid/config.cc), on the root once every subcommand is registered,
// and the file's options for the report of `app` (null when no file was given).
void AddConfigOption(CLI::App* root);
nlohmann::json ConfigJson(const CLI::App& app);

// A mistake on the command line (exit code 2, INTERFACE.md 4). rotorid::Error thrown while a
// command still validates its options counts as one too: see MarkOptionsValidated.
class UsageError : public std::runtime_error {
 public:
  using std::runtime_error::runtime_error;
};
// Called once a command has validated its options and starts reading input: rotorid::Error from
// here on is bad input (exit 1), before it a usage error (exit 2).
void MarkOptionsValidated();
bool OptionsValidated();

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

// A CLI11 check (empty when valid, else the message) from a parser that throws rotorid::Error, so
// that a bad value is a usage error found while parsing.
template <class Parse>
std::function<std::string(const std::string&)> ParsesWith(Parse parse) {
  return [parse](const std::string& text) -> std::string {
    try {
      parse(text);
    } catch (const std::exception& e) {
      return e.what();
    }
    return {};
  };
}

// A CLI11 check: a number in [low, high] (NaN and infinities refused).
CLI::Validator Within(double low, double high);

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
