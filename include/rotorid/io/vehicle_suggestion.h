#pragma once

// A vehicle file from what a log knows (`rotorid vehicle`): PX4's CA_ROTOR* parameters, the
// Crazyflie 2.x layout for a Crazyflie micro-SD log, a Quad-X in Betaflight's motor order from a
// blackbox header (with the arm length given), or a column map's metadata
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

// What the log may not say. `column_map_path` is needed for a CSV export of another tool;
// a Betaflight/INAV blackbox header gives the mixer and motor count but no geometry, so a Quad-X
// suggestion from it needs `arm_length_m` (hub to centre) and whether the props turn outwards.
struct VehicleSuggestionOptions {
  double mass_kg = 0.0;  // required: from a scale
  std::string name = "A";
  std::string column_map_path;
  double arm_length_m = 0.0;
  bool props_out = false;
};

// Dispatches on the log's format. Throws rotorid::Error naming the file when its format says
// nothing about the rotors, or what is missing to say it.
VehicleSuggestion SuggestVehicle(const std::string& log_path, const VehicleSuggestionOptions& options);

}  // namespace rotorid
