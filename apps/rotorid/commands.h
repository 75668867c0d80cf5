#pragma once

// Subcommands of the rotorid CLI. Each Add*Command registers its options on `root` and returns
// the function that runs it once the command line is parsed. apps/ holds only argument parsing
// and printing; the work is done by the library.

#include <functional>
#include <string>
#include <vector>

#include <CLI/CLI.hpp>

#include "rotorid/core/flight_log.h"
#include "rotorid/core/vehicle.h"

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

// One flight with its vehicle, as given on the command line.
struct Flight {
  Vehicle vehicle;
  FlightLog log;
  double weight = 1.0;
};

// Registers --vehicle/--log/--weight (and --validate-vehicle/--validate-log when `held_out`),
// --json, --report, --quiet, --verbose.
void AddFlightOptions(CLI::App* app, FlightOptions* options, bool held_out);
// Reads the paired flights; throws rotorid::Error naming the file at fault.
std::vector<Flight> LoadFlights(const std::vector<std::string>& vehicle_paths, const std::vector<std::string>& log_paths,
                                const std::vector<double>& weights);
std::vector<Flight> LoadTrainingFlights(const FlightOptions& options);
std::vector<Flight> LoadValidationFlights(const FlightOptions& options);

Command AddSimulateCommand(CLI::App& root);
Command AddIdentifyCommand(CLI::App& root);
Command AddValidateCommand(CLI::App& root);
Command AddRefineCommand(CLI::App& root);
Command AddDelayCommand(CLI::App& root);
Command AddAblateCommand(CLI::App& root);
Command AddDiagnoseCommand(CLI::App& root);

}  // namespace rotorid::cli
