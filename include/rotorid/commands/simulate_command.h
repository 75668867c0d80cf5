#pragma once

// rotorid simulate as a library call (docs/simulator.md): the command line's values resolved into
// SimulationOptions, the flight simulated, and its files written (log, truth, vehicle file, run
// summary). apps/rotorid/simulate.cc only parses and prints.
//
//   SimulateCommandOptions options;
//   options.out_path = "flight.csv";
//   options.truth_path = "truth.json";
//   const SimulateCommandResult result = RunSimulateCommand(ResolveSimulateCommand(options));

#include <map>
#include <optional>
#include <string>
#include <vector>

#include "rotorid/sim/presets.h"
#include "rotorid/sim/simulator.h"

namespace rotorid {

struct SimulateCommandOptions {
  // Files to write; only the log is required.
  std::string out_path, truth_path, vehicle_out_path, json_path;
  // A preset (A, B, CF) or a vehicle file, not both (preset_given: --preset was on the command line).
  std::string preset = "A";
  bool preset_given = false;
  std::string vehicle_path;
  std::string noise;  // empty: the preset's (pixhawk for A, B and vehicle files)
  std::string profile = "paper";
  std::vector<std::string> effects;    // name=value, vectors name=x,y,z
  std::vector<double> external_force;  // world x, y, z in N, or empty
  // Text, not a number: a parser would wrap "-1" around to 2^64 - 1.
  std::string seed = "1";
  // A preset logs at its own rate unless the rate was given.
  bool rate_given = false;
  SimulationOptions simulation;
};

// The options checked and resolved: what the simulator flies with and, for a preset, its vehicle.
struct ResolvedSimulateCommand {
  SimulateCommandOptions options;
  SimulationOptions simulation;
  std::optional<SimulationVehicle> preset;
};

// Throws rotorid::Error (a usage error: nothing read yet) naming the option at fault.
ResolvedSimulateCommand ResolveSimulateCommand(const SimulateCommandOptions& options);

struct SimulateCommandResult {
  SimulationResult simulation;
  // What was written, by role (log, truth, vehicle, json) in the order of the console line.
  std::map<std::string, std::string> outputs;
};

// Reads the vehicle file (if any), simulates and writes the requested files atomically; throws
// rotorid::Error naming the file at fault.
SimulateCommandResult RunSimulateCommand(const ResolvedSimulateCommand& command);

// The console's summary and "wrote role=path ..." lines.
std::string SimulateConsoleText(const SimulateCommandResult& result);

}  // namespace rotorid
