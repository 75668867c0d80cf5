#pragma once

#include <string>

#include "rotorid/core/vehicle.h"

namespace rotorid {

// Most rotors a vehicle file may list (octo-coaxial is 16): a larger count is a mistake, and every
// log's rotor columns scale with it.
inline constexpr int kMaxVehicleRotors = 64;

// Reads a vehicle file (INTERFACE.md section 3). Throws rotorid::Error naming file, line and
// column of what is wrong.
Vehicle ReadVehicleYaml(const std::string& path);
Vehicle ParseVehicleYaml(const std::string& text, const std::string& source_name);
std::string VehicleToYaml(const Vehicle& vehicle);

}  // namespace rotorid
