// `acc_delay` (INTERFACE.md, "Effects of real vehicles (v2)"): the accelerometer stream lags the
// gyro stream (different on-board filters), acc_log(t) = s(t - acc_delay_s); the rotor-to-gyro
// timing stays `delay_s`. Last in the sensor chain (next to the log).
//
// The model undoes it on the filtered signals with the second-order Taylor step
//   s(t) = acc_log(t + d) ~ acc_log + d acc_log' + d^2/2 acc_log'',
// exact to (2 pi f d)^3 / 6 of a component at f: 0.1 % at 10 Hz for d = 5 ms, where the rows'
// low-pass already leaves little. The simulator shifts its accelerometer series exactly instead.

#include "model/effect_adapter.h"

namespace rotorid::internal {
namespace {

struct AccDelayModel {
  template <typename T>
  static void Correct(const T* p, ImuSample<T>* s) {
    const T& d = p[0];
    s->specific_force += d * s->specific_force_rate + (T(0.5) * d * d) * s->specific_force_rate2;
  }
  // The simulator applies the delay to the whole accelerometer series (AccelerometerDelay).
  template <typename T>
  static void ApplyToSensor(const T*, ImuSample<T>*) {}
  static double AccelerometerDelay(const Eigen::VectorXd& v) { return v[0]; }
};

}  // namespace

const EffectDescriptor& AccDelayEffect() {
  static const ImuEffect<AccDelayModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "acc_delay";
    i.parameter_name = "acc_delay_s";
    i.unit = "s";
    // acc_log(t) = s(t - acc_delay_s): the accelerometer lags the gyro
    i.stage = EffectStage::kImuSensor;
    i.chain_position = 3;
    i.inputs = {FlightInput::kSpecificForceRates};
    i.dimension = 1;
    // Either stream may be the later one; beyond 50 ms no flight controller's filters reach.
    i.lower_bound = -0.05;
    i.upper_bound = 0.05;
    i.draw = {DrawShape::kUniform, 0.002, 0.008};
    i.simulator_limit = {true, -0.05, 0.05};
    // Accelerometer and gyro filters on board differ by a few ms (PX4's 30 Hz accelerometer low-pass about
    // 5 ms behind its gyro's); beyond 20 ms either way the streams are misaligned by something else.
    i.plausible = {true, -0.02, 0.03, PlausibleScale::kNone,
                   "on-board filters put the accelerometer a few ms behind the gyro"};
    i.negligible = SubMillisecondTimeShift();
    i.settle_tolerance = 1e-5;
    i.display_scale = 1e3;
    i.display_unit = "ms";
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal
