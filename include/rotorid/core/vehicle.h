#pragma once

#include <Eigen/Core>
#include <map>
#include <optional>
#include <string>
#include <vector>

namespace rotorid {

// One rotor: position of its hub in the body frame F_d (m) and turning direction:
// spin = +1 when the rotor's angular velocity points along +z_d (counter-clockwise seen from above).
struct Rotor {
  Eigen::Vector3d position_m = Eigen::Vector3d::Zero();
  int spin = 1;
};

// Rotor speed from a logged motor command, for logs without measured speed (docs/input_formats.md):
//   Omega = c0 + c1 u + c2 u^2 (rad/s, clamped at 0), u the command as the log's rotor columns hold
//   it (Crazyflie: PWM / 65535; PX4 actuator_motors: 0..1; a mapped CSV: per its column map).
// Typically fitted to thrust-stand data with a tachometer; the same for every rotor.
struct CommandToSpeed {
  Eigen::Vector3d coefficients = Eigen::Vector3d::Zero();

  double operator()(double u) const;
  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

// A vehicle configuration (INTERFACE.md section 3). The mass is the one known parameter.
struct Vehicle {
  std::string name = "A";
  double mass_kg = 0.0;
  std::vector<Rotor> rotors;
  // Applied to command logs only (a measured rotor speed is used as it is).
  std::optional<CommandToSpeed> command_to_speed;
  // Propeller radius (m), for the ground effect.
  std::optional<double> rotor_radius_m = std::nullopt;
  // The battery voltage command_to_speed was measured at (V), for the battery effect.
  std::optional<double> command_to_speed_voltage_v = std::nullopt;
  // Known values of effects, by effect name, from the vehicle file keys their descriptors name
  // (imu_position: a known IMU lever arm). Processing corrects the IMU data by them.
  std::map<std::string, Eigen::VectorXd> known_effects = {};
  // The file it was read from (empty when built in code), for messages. Last, so that aggregate
  // initialisations {name, mass, rotors, map} stay valid.
  std::string source = "";

  int num_rotors() const { return static_cast<int>(rotors.size()); }
  // Mean distance of the rotors from the body's z axis (m); 0 without rotors.
  double MeanArm() const;
  // Empty when valid, else what is wrong.
  std::string Validate() const;
};

}  // namespace rotorid
