#include "rotorid/core/vehicle.h"

#include <algorithm>
#include <cmath>

namespace rotorid {

double Vehicle::MeanArm() const {
  double sum = 0.0;
  for (const Rotor& rotor : rotors) sum += rotor.position_m.head<2>().norm();
  return rotors.empty() ? 0.0 : sum / static_cast<double>(rotors.size());
}

double CommandToSpeed::operator()(double u) const {
  return std::max(0.0, coefficients[0] + u * (coefficients[1] + u * coefficients[2]));
}

std::string CommandToSpeed::Validate() const {
  if (!coefficients.allFinite()) return "command_to_speed coefficients must be finite";
  if (coefficients[1] == 0.0 && coefficients[2] == 0.0)
    return "command_to_speed must depend on the command (c1 or c2 non-zero)";
  return {};
}

std::string Vehicle::Validate() const {
  if (name.empty()) return "vehicle name is empty";
  if (name.find('.') != std::string::npos) return "vehicle name '" + name + "' must not contain '.'";
  if (!(mass_kg > 0.0) || !std::isfinite(mass_kg)) return "mass must be a positive number of kg";
  if (rotors.empty()) return "vehicle has no rotors";
  for (size_t i = 0; i < rotors.size(); ++i) {
    if (!rotors[i].position_m.allFinite()) return "rotor " + std::to_string(i + 1) + " position is not finite";
    if (rotors[i].spin != 1 && rotors[i].spin != -1) return "rotor " + std::to_string(i + 1) + " spin must be +1 or -1";
  }
  if (command_to_speed) return command_to_speed->Validate();
  return {};
}

}  // namespace rotorid
