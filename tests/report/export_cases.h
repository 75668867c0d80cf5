#pragma once

// Vehicles and reports for the export tests: the bundled B (plus quad), a Crazyflie and the TU Delft
// quad (X, from data/vehicles) and an X hexa, each with a physically possible body; reports shaped
// as identify's (discarded parameters, one predicted with) and refine's (effects).

#include <Eigen/Core>
#include <cmath>
#include <nlohmann/json.hpp>
#include <string>
#include <vector>

#include "rotorid/core/vehicle.h"
#include "rotorid/io/vehicle_yaml.h"
#include "rotorid/model/parameters.h"
#include "support/test_support.h"

namespace rotorid::testing {

struct Case {
  Vehicle vehicle;
  VehicleParameters truth;
  double max_rotor_speed_radps;
};

inline Vehicle HexaX() {
  Vehicle v;
  v.name = "hexa";
  v.mass_kg = 2.0;
  const double arm = 0.3;
  int spin = +1;
  for (const double bearing : {30.0, 90.0, 150.0, -150.0, -90.0, -30.0}) {
    const double b = bearing * M_PI / 180.0;
    v.rotors.push_back({Eigen::Vector3d(arm * std::cos(b), -arm * std::sin(b), 0.0), spin});
    spin = -spin;
  }
  return v;
}

// A consistent body: inertia i_c about a centre of mass c, moved to O_d.
inline VehicleParameters Truth(double m, const Eigen::Vector3d& c, const Eigen::Matrix3d& i_c, double kt, double kd) {
  VehicleParameters p;
  p.mass_kg = m;
  p.body.first_moment = m * c;
  p.body.inertia = i_c + m * (c.squaredNorm() * Eigen::Matrix3d::Identity() - c * c.transpose());
  p.rotor = {kt, kd};
  return p;
}

inline std::vector<Case> Cases() {
  const std::string data = SourceDir() + "/data/";
  Eigen::Matrix3d i_b;
  i_b << 1.8e-2, 0, 4e-4, 0, 1.9e-2, 0, 4e-4, 0, 2.9e-2;
  return {
      {ReadVehicleYaml(data + "sim/B.yaml"), Truth(1.452, Eigen::Vector3d(3e-3, -2e-3, -6e-3), i_b, 3.6e-6, 5.1e-8),
       1200.0},
      {ReadVehicleYaml(data + "vehicles/crazyflie21_brushed.yaml"),
       Truth(0.0347, Eigen::Vector3d(4e-4, -2e-4, -1e-3), Eigen::Vector3d(1.66e-5, 1.67e-5, 2.93e-5).asDiagonal(),
             2.9e-8, 1.5e-10),
       0.0},  // its command_to_speed gives the rotor speed at full command
      {ReadVehicleYaml(data + "vehicles/tudelft_indiflight_3inch.yaml"),
       Truth(0.3, Eigen::Vector3d(1e-3, 0, -2e-3), Eigen::Vector3d(3.0e-4, 3.2e-4, 5.5e-4).asDiagonal(), 9.4e-8,
             1.5e-9),
       4000.0},
      {HexaX(),
       Truth(2.0, Eigen::Vector3d(-5e-3, 2e-3, -1e-2), Eigen::Vector3d(5e-2, 5.2e-2, 9e-2).asDiagonal(), 8e-6, 1.2e-7),
       1000.0}};
}

inline nlohmann::json Entry(double value, bool essential = true) {
  return {{"value", value}, {"std", 0.01 * std::abs(value) + 1e-12}, {"essential", essential}};
}

// An identify report: I_xy discarded (predicted with 0), I_zz discarded and predicted with its
// estimate; or a refine report with every parameter kept and four effects.
inline nlohmann::json Report(const Case& c, bool refined) {
  const Eigen::Matrix<double, kNumBodyParameters, 1> chi = c.truth.body.ToVector();
  nlohmann::json parameters = {{"kt", Entry(c.truth.rotor.kt)}, {"kd", Entry(c.truth.rotor.kd)}};
  for (int k = 0; k < kNumBodyParameters; ++k)
    parameters[c.vehicle.name + "." + kBodyParameterNames[k]] = Entry(chi[k]);
  nlohmann::json report = {{"checks", {{{"name", "gravity"}, {"status", "ok"}, {"message", "fine"}}}}};
  if (!refined) {
    parameters[c.vehicle.name + ".I_xy"] = Entry(0.0, false);
    parameters[c.vehicle.name + ".I_zz"] = Entry(0.0, false);
    parameters[c.vehicle.name + ".I_zz"]["predicts_with"] = chi[5];
    report["linear"] = {{"parameters", parameters}};
    return report;
  }
  report["linear"] = {{"parameters", parameters}};
  report["refined"] = {
      {"parameters", parameters},
      {"effects",
       {{"motor_tau_s", {{"value", 0.02}, {"std", 0.001}, {"enabled", true}}},
        {"delay_s", {{"value", 0.005}, {"std", 0.001}, {"enabled", true}}},
        {"rotor_drag_coefficient", {{"value", 3e-3 * c.truth.rotor.kt / 3.6e-6}, {"enabled", true}}},
        {"flapping_moment_coefficient", {{"value", 1e-4 * c.truth.rotor.kt / 3.6e-6}, {"enabled", true}}},
        {"acc_bias", {{"value", {0.1, 0.0, 0.0}}, {"enabled", true}}},
        {"ground_effect_coefficient", {{"value", 0.0}, {"enabled", false}}}}}};
  return report;
}

}  // namespace rotorid::testing
