// `acc_bias` and `gyro_bias` (INTERFACE.md section 1): constant offsets of the IMU in its frame,
//   acc_log = Exp(r) s_body + acc_bias + noise,  gyro_log = Exp(r) w_body + gyro_bias + noise
// (w' has no bias). They sit last in the sensor chain, next to the log.

#include "model/effect_adapter.h"

namespace rotorid::internal {
namespace {

struct AccBiasModel {
  template <typename T>
  static void Correct(const T* p, ImuSample<T>* s) {
    s->specific_force -= Eigen::Map<const Eigen::Matrix<T, 3, 1>>(p);
  }
  template <typename T>
  static void ApplyToSensor(const T* p, ImuSample<T>* s) {
    s->specific_force += Eigen::Map<const Eigen::Matrix<T, 3, 1>>(p);
  }
};

struct GyroBiasModel {
  template <typename T>
  static void Correct(const T* p, ImuSample<T>* s) {
    s->angular_velocity -= Eigen::Map<const Eigen::Matrix<T, 3, 1>>(p);
  }
  template <typename T>
  static void ApplyToSensor(const T* p, ImuSample<T>* s) {
    s->angular_velocity += Eigen::Map<const Eigen::Matrix<T, 3, 1>>(p);
  }
};

}  // namespace

const EffectDescriptor& AccBiasEffect() {
  static const ImuEffect<AccBiasModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "acc_bias";
    i.parameter_name = "acc_bias";
    i.unit = "m/s^2";
    // acc_log = Exp(r) s_body + acc_bias (IMU frame)
    i.stage = EffectStage::kImuSensor;
    i.chain_position = 2;
    i.dimension = 3;
    i.lower_bound = -2.0;
    i.upper_bound = 2.0;
    i.draw = {DrawShape::kSignedPerAxis, 0.1, 0.5};
    i.simulator_limit = {false, 0.0, 5.0};
    // A MEMS accelerometer's zero-g offset, uncalibrated and over temperature, is at most ~150 mg.
    i.plausible = {true, -2.0, 2.0, PlausibleScale::kNone, "a MEMS accelerometer's zero-g offset is under ~150 mg"};
    // On the independent simulator's battery + motor lag flight, once both were in (every held-out
    // component at its noise floor), the blind diagnosis selected (0.08, -0.31, 2.0) mm/s^2: 0.2 mg.
    i.negligible.below = 0.01;
    i.negligible.why = "no accelerometer's offset is calibrated or stable to better than about 1 mg (0.01 m/s^2)";
    i.settle_tolerance = 1e-4;
    i.display_unit = "m/s^2";
    return i;
  }());
  return effect;
}

const EffectDescriptor& GyroBiasEffect() {
  static const ImuEffect<GyroBiasModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "gyro_bias";
    i.parameter_name = "gyro_bias";
    i.unit = "rad/s";
    // gyro_log = Exp(r) w_body + gyro_bias (IMU frame)
    i.stage = EffectStage::kImuSensor;
    i.chain_position = 2;
    i.dimension = 3;
    i.lower_bound = -0.2;
    i.upper_bound = 0.2;
    i.draw = {DrawShape::kSignedPerAxis, 0.005, 0.03};
    i.simulator_limit = {false, 0.0, 0.5};
    // A MEMS gyro's zero-rate offset is at most a few deg/s before the boot calibration removes it.
    i.plausible = {true, -0.1, 0.1, PlausibleScale::kNone, "a MEMS gyro's zero-rate offset is a few deg/s"};
    i.settle_tolerance = 1e-4;
    i.display_unit = "rad/s";
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal
