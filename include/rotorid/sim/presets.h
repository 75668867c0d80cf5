#pragma once

// Vehicles to simulate, with their true parameters: the paper's configurations A and B
// (MODEL.md section 6), or any vehicle file with an optional `simulation:` mapping
//
//   simulation:              # all keys optional; missing ones are derived (see below)
//     kt: 3.6e-6             # N s^2
//     kd: 5.1e-8             # N m s^2
//     ms: [-4e-3, -2e-3, -6e-3]                        # kg m, first moment at O_d
//     inertia: [1.8e-2, 1.9e-2, 2.9e-2, 2e-5, -4e-5, 1e-5]  # kg m^2 at O_d: Ixx Iyy Izz Ixy Ixz Iyz
//
// (the main vehicle reader ignores the mapping).

#include <string>

#include "rotorid/core/vehicle.h"
#include "rotorid/model/parameters.h"

namespace rotorid {

struct SimulationVehicle {
  Vehicle vehicle;                // what the vehicle file says (name, mass, rotors)
  VehicleParameters parameters;   // the truth the simulator flies with
  std::string parameters_source;  // where `parameters` came from, for the truth JSON
  // How such a vehicle logs (the CLI's defaults for --rate and --noise).
  double log_rate_hz = 200.0;
  std::string noise = "pixhawk";
};

// The paper's configuration "A" (plus quad, d = 0.225 m), "B" (A with 0.125 kg at
// (0.375, 0, -0.04) m and 0.042 kg at (0, -0.43, -0.04) m, added exactly), or "CF", a Crazyflie 2.1
// brushed-like quad (34.7 g, X layout, arm 0.046 m, kt 2e-8, 500 Hz, BMI088-like noise; its
// sources in docs/simulator.md 5). Throws rotorid::Error for other names.
SimulationVehicle PresetVehicle(const std::string& name);

// Plausible parameters for any layout from its mass and mean arm length, scaled from the paper's
// vehicle: kt ~ arm^4 (propeller diameter^4), kd/kt ~ arm, 40 % of the mass in the motors and
// arms (point masses at the rotors) and the rest in a central box; centre of mass slightly off
// O_d and below it, as on a real airframe.
VehicleParameters DeriveSimulationParameters(const Vehicle& vehicle);

// Reads a vehicle file and its optional `simulation:` mapping. Throws rotorid::Error naming file,
// line and column of what is wrong.
SimulationVehicle LoadSimulationVehicle(const std::string& path);
SimulationVehicle ParseSimulationVehicle(const std::string& text, const std::string& source_name);

}  // namespace rotorid
