#pragma once

// Subcommands of the rotorid CLI. Each Add*Command registers its options on `root` and returns
// the function that runs it once the command line is parsed. apps/ holds only argument parsing
// and printing; the work is done by the library.

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "rotorid/ident/checks.h"
#include "rotorid/ident/identify.h"
#include "rotorid/ident/tls.h"
#include "rotorid/io/flight_source.h"

namespace rotorid::cli {

using RunFunction = std::function<int()>;
struct Command {
  CLI::App* app = nullptr;
  RunFunction run;
};

// Options every analysing subcommand shares (INTERFACE.md section 4).
struct FlightOptions {
  std::vector<std::string> vehicle_paths;
  std::vector<std::string> log_paths;
  std::vector<double> weights;
  std::vector<std::string> validate_vehicle_paths;
  std::vector<std::string> validate_log_paths;
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
  IdentifyOptions identify;
};

// Registers --vehicle/--log/--weight (and --validate-vehicle/--validate-log when `held_out`),
// --json, --report, --quiet, --verbose.
void AddFlightOptions(CLI::App* app, FlightOptions* options, bool held_out);
// Registers the signal-processing and TLS options.
void AddIdentifyOptions(CLI::App* app, IdentifyCliOptions* options);
// Turns the parsed strings into library options (throws rotorid::Error on invalid values).
IdentifyOptions ResolveIdentifyOptions(IdentifyCliOptions* options);
FlightSourceOptions SourceOptions(const IdentifyCliOptions& options);

// Reads the paired flights; throws rotorid::Error naming the file at fault.
std::vector<FlightData> LoadFlights(const std::vector<std::string>& vehicle_paths,
                                    const std::vector<std::string>& log_paths, const std::vector<double>& weights,
                                    const FlightSourceOptions& source);
std::vector<FlightData> LoadTrainingFlights(const FlightOptions& options, const FlightSourceOptions& source);
std::vector<FlightData> LoadValidationFlights(const FlightOptions& options, const FlightSourceOptions& source);

// Human-readable output.
std::string FormatComponents(const std::vector<std::optional<double>>& values);
void PrintParameterTable(std::ostream& out, const std::vector<std::string>& names, const TlsSolution& solution);
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

}  // namespace rotorid::cli
