#include "rotorid/commands/vehicle_command.h"

#include "rotorid/io/atomic_file.h"
#include "rotorid/io/vehicle_yaml.h"

namespace rotorid {

VehicleSuggestion RunVehicleCommand(const VehicleCommandOptions& options) {
  VehicleSuggestion suggestion = SuggestVehicle(options.log, options.suggestion);
  WriteFileAtomically(options.out, "# written by rotorid vehicle from " + suggestion.source +
                                       "\n# mass: given on the command line\n" + VehicleToYaml(suggestion.vehicle));
  return suggestion;
}

std::string VehicleConsoleLine(const VehicleCommandOptions& options, const VehicleSuggestion& suggestion) {
  return "rotorid vehicle: " + std::to_string(suggestion.vehicle.num_rotors()) + " rotors from " + suggestion.source +
         " -> " + options.out;
}

}  // namespace rotorid
