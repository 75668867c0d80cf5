#pragma once

// The simulated battery and motor drive (internal to the simulator, docs/simulator.md 2): the
// firmware turns the speed the controller wants into a command u through the vehicle's
// command_to_speed map at the map's voltage, without battery compensation; the motors turn at
// map(u (V / V_ref)^beta) (INTERFACE.md, `battery`), with the voltage sagging over the flight and
// under load.

#include <Eigen/Core>

#include "rotorid/core/vehicle.h"
#include "rotorid/sim/simulator.h"

namespace rotorid::internal {

class BatteryDrive {
 public:
  // `hover_load`: sum Omega_i^2 in hover (the load at which the voltage sags by hover_sag_v);
  // [start_s, end_s]: the flight, over which the open-circuit voltage falls from full_v to
  // empty_v. Throws rotorid::Error when the map does not increase over u in [0, 1].
  BatteryDrive(const BatteryOptions& options, const CommandToSpeed& map, double reference_voltage_v, double exponent,
               double hover_load, double start_s, double end_s);

  // V at time t with this sum of Omega_i^2.
  double Voltage(double t_s, double load) const;
  // The firmware's command for this wanted speed: the map's inverse at V_ref, within [0, 1].
  double Command(double speed_radps) const;
  // The speed the motor turns at: map(u (V / V_ref)^beta), clamped at 0 like the map.
  double Speed(double command, double voltage_v) const;
  // The command that gives this speed at this voltage (the trimmed start).
  double CommandFor(double speed_radps, double voltage_v) const;

 private:
  // x with map(x) = speed on the increasing branch (beyond the map's reach: its maximum's x).
  double InverseMap(double speed_radps) const;
  double VoltageFactor(double voltage_v) const;

  BatteryOptions options_;
  CommandToSpeed map_;
  double reference_voltage_v_, exponent_, hover_load_, start_s_, end_s_;
};

// The map a vehicle without one gets when its battery is simulated: concave like a real one
// (c2 = -c1 / 5), 0 at u = 0 and `max_speed_radps` at u = 1.
CommandToSpeed DefaultCommandToSpeed(double max_speed_radps);

}  // namespace rotorid::internal
