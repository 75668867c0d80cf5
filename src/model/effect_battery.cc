// `battery` (INTERFACE.md, "Effects of real vehicles (v2)"): for command logs with a voltage, the
// speed a command u gives is map(u (V / V_ref)^beta), beta = battery_exponent, V_ref the vehicle's
// command_to_speed_voltage or else the flight's mean voltage. beta = 1: the motor sees the duty
// cycle times the battery voltage (a Crazyflie logs the duty cycle after its firmware's battery
// compensation); beta = 0: the map as measured. First in the rotor-signal chain: it turns the
// logged command into the speed that the delay and the lag then act on.

#include <algorithm>
#include <cmath>

#include "model/effect_adapter.h"
#include "rotorid/core/vehicle.h"

namespace rotorid::internal {
namespace {

struct BatteryModel {
  template <typename T>
  static void Transform(const T* p, const RotorSignalInput& input, const Eigen::Matrix<T, -1, 1>& in,
                        Eigen::Matrix<T, -1, 1>* out) {
    using std::exp;
    // Without a command, a voltage and a map there is nothing to scale (the descriptor's inputs
    // keep the effect out of such flights).
    if (!input.command || !input.voltage || !input.map || !(input.reference_voltage > 0.0) ||
        input.command->size() != in.size() || input.voltage->size() != in.size()) {
      *out = in;
      return;
    }
    const Eigen::Vector3d& c = input.map->coefficients;
    out->resize(in.size());
    for (Eigen::Index k = 0; k < in.size(); ++k) {
      // A logged 0 V (a dropped sample) must not send the log to -inf.
      const double ratio = std::max((*input.voltage)[k] / input.reference_voltage, 1e-3);
      const T x = (*input.command)[k] * exp(p[0] * std::log(ratio));
      const T speed = T(c[0]) + x * (T(c[1]) + x * T(c[2]));
      (*out)[k] = ScalarPart(speed) > 0.0 ? speed : T(0.0);  // the map's own clamp at 0
    }
  }
  static double CommandDelay(const Eigen::VectorXd&) { return 0.0; }
  static double MotorTimeConstant(const Eigen::VectorXd&) { return 0.0; }
  // Not a timing effect: the diagnosis starts it at 0, not from the coarse delay search.
  static double EquivalentValue(double /*delay_s*/) { return 0.0; }
};

}  // namespace

const EffectDescriptor& BatteryEffect() {
  static const RotorSignalEffect<BatteryModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "battery";
    i.parameter_name = "battery_exponent";
    i.unit = "1";
    // Omega = map(u (V / V_ref)^beta), beta = battery_exponent; command logs with a voltage
    i.stage = EffectStage::kRotorSignal;
    i.chain_position = -1;
    i.dimension = 1;
    i.lower_bound = 0.0;
    i.upper_bound = 3.0;
    // Realistic: 1 for a firmware without battery compensation (the motor sees duty x voltage),
    // less with partial compensation, a little more where the speed grows faster than the voltage.
    // The simulator flies it with its battery (SimulationOptions::battery: a command log with a voltage).
    i.draw = {DrawShape::kUniform, 0.5, 1.5};
    i.simulator_limit = {true, 0.0, 3.0};
    // beta = 1: the motor sees duty x voltage; a motor's load curve keeps it within 0..2. Negative:
    // faster on a flatter battery.
    i.plausible = {true, 0.0, 2.0, PlausibleScale::kNone, "the motor sees about duty x voltage (beta = 1)"};
    i.settle_tolerance = 1e-4;
    i.inputs = {FlightInput::kRotorCommand, FlightInput::kVoltage};
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal
