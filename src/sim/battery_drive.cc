#include "sim/battery_drive.h"

#include <algorithm>
#include <cmath>

#include "rotorid/core/error.h"

namespace rotorid::internal {

BatteryDrive::BatteryDrive(const BatteryOptions& options, const CommandToSpeed& map, double reference_voltage_v,
                           double exponent, double hover_load, double start_s, double end_s)
    : options_(options),
      map_(map),
      reference_voltage_v_(reference_voltage_v),
      exponent_(exponent),
      hover_load_(hover_load),
      start_s_(start_s),
      end_s_(end_s) {
  const Eigen::Vector3d& c = map.coefficients;
  // The slope c1 + 2 c2 u is linear in u: positive at both ends means positive throughout.
  if (!(c[1] > 0.0) || !(c[1] + 2.0 * c[2] > 0.0))
    throw Error("the simulated battery needs a command_to_speed map that increases over u in [0, 1] (got [" +
                std::to_string(c[0]) + ", " + std::to_string(c[1]) + ", " + std::to_string(c[2]) + "])");
  if (!(reference_voltage_v > 0.0)) throw Error("the simulated battery needs the map's voltage (> 0 V)");
}

double BatteryDrive::Voltage(double t_s, double load) const {
  const double fraction = end_s_ > start_s_ ? std::clamp((t_s - start_s_) / (end_s_ - start_s_), 0.0, 1.0) : 0.0;
  const double open_circuit = options_.full_v + fraction * (options_.empty_v - options_.full_v);
  return open_circuit - options_.hover_sag_v * load / hover_load_;
}

double BatteryDrive::VoltageFactor(double voltage_v) const {
  // As the effect does: a 0 V sample must not send the speed to 0 ** -beta.
  return std::pow(std::max(voltage_v / reference_voltage_v_, 1e-3), exponent_);
}

double BatteryDrive::InverseMap(double speed_radps) const {
  const Eigen::Vector3d& c = map_.coefficients;
  const double rise = speed_radps - c[0];
  const double discriminant = c[1] * c[1] + 4.0 * c[2] * rise;
  // Beyond a concave map's maximum: its vertex.
  if (discriminant <= 0.0) return -c[1] / (2.0 * c[2]);
  // The increasing branch's root of c2 x^2 + c1 x - rise = 0, in the form exact for c2 = 0 too.
  return 2.0 * rise / (c[1] + std::sqrt(discriminant));
}

double BatteryDrive::Command(double speed_radps) const { return std::clamp(InverseMap(speed_radps), 0.0, 1.0); }

double BatteryDrive::CommandFor(double speed_radps, double voltage_v) const {
  return InverseMap(speed_radps) / VoltageFactor(voltage_v);
}

double BatteryDrive::Speed(double command, double voltage_v) const { return map_(command * VoltageFactor(voltage_v)); }

CommandToSpeed DefaultCommandToSpeed(double max_speed_radps) {
  return CommandToSpeed{Eigen::Vector3d(0.0, 1.25 * max_speed_radps, -0.25 * max_speed_radps)};
}

}  // namespace rotorid::internal
