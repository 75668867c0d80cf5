#pragma once

// The command-line options the analysing subcommands share and their resolution into the library's
// options.

#include <CLI/CLI.hpp>
#include <string>
#include <vector>

#include "rotorid/commands/command_input.h"
#include "rotorid/ident/identify.h"
#include "rotorid/io/flight_source.h"
#include "usage.h"

namespace rotorid::cli {

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

}  // namespace rotorid::cli
