#pragma once

// A vehicle file from what a log knows (`rotorid vehicle`): PX4's CA_ROTOR* parameters, the
// Crazyflie 2.x layout for a Crazyflie micro-SD log, or a column map's metadata
// (`rotor_positions: [[x, y, z], ...]` and `rotor_spins: [+1, -1, ...]`, body frame FLU, m).
// The mass is never in a log: the caller gives it.

#include <string>

#include "rotorid/core/vehicle.h"

namespace rotorid {

struct VehicleSuggestion {
  Vehicle vehicle;
  std::string source;  // where the layout came from, for the file's header comment
};

// The Bitcraze Crazyflie 2.x: 92 mm motor to motor on the diagonal (+-0.0325 m in x and y), the
// firmware's motor order M1 front-right (CCW), M2 back-right (CW), M3 back-left, M4 front-left.
Vehicle CrazyflieLayout(const std::string& name);

// Dispatches on the log's format; `column_map_path` is needed for a CSV export of another tool.
// Throws rotorid::Error naming the file when its format says nothing about the rotors.
VehicleSuggestion SuggestVehicle(const std::string& log_path, const std::string& column_map_path, double mass_kg,
                                 const std::string& name = "A");

}  // namespace rotorid
