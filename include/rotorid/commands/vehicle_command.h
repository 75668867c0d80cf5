#pragma once

// rotorid vehicle as a library call (docs/cli.md): a vehicle file from what a log knows, with the
// mass from a scale, written atomically with a header naming where the layout came from.

#include <string>

#include "rotorid/io/vehicle_suggestion.h"

namespace rotorid {

struct VehicleCommandOptions {
  std::string log;
  std::string out;
  VehicleSuggestionOptions suggestion;
};

// Reads the log, writes `out`; throws rotorid::Error naming the file at fault.
VehicleSuggestion RunVehicleCommand(const VehicleCommandOptions& options);

// "rotorid vehicle: 4 rotors from <source> -> <out>"
std::string VehicleConsoleLine(const VehicleCommandOptions& options, const VehicleSuggestion& suggestion);

}  // namespace rotorid
