#pragma once

#include <string>
#include <vector>

#include <Eigen/Core>

namespace rotorid {

// One rotor: position of its hub in the body frame F_d (m) and turning direction:
// spin = +1 when the rotor's angular velocity points along +z_d (counter-clockwise seen from above).
struct Rotor {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  int spin = 1;
};

// A vehicle configuration (INTERFACE.md section 3). The mass is the one known parameter.
struct Vehicle {
  std::string name = "A";
  double mass_kg = 0.0;
  std::vector<Rotor> rotors;

  int num_rotors() const { return static_cast<int>(rotors.size()); }
  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

}  // namespace rotorid
