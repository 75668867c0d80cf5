#pragma once

// Internal: turns an effect's templated models into the virtual hooks of EffectDescriptor, so that
// an effect's file holds its models once, templated on the scalar, and the library calls them for
// doubles and for each Jet type it differentiates with.
//
//   struct MyImuModel {
//     template <typename T> static void Correct(const T* p, ImuSample<T>* sample);        // model
//     template <typename T> static void ApplyToSensor(const T* p, ImuSample<T>* sample);  // simulator
//   };
//   const EffectDescriptor& MyEffect() { static const ImuEffect<MyImuModel> e(Info{...}); return e; }

#include <ceres/jet.h>

#include "rotorid/model/effects.h"

namespace rotorid::internal {

// The size below which a timing effect (delay, motor lag, accelerometer delay) is negligible. On
// simulated Crazyflie flights with per-rotor thrust scales and no timing effect, the blind diagnosis
// selected a motor lag of 0.10-0.11 +- 0.04 ms (held-out shrink 2-3 %); with a floor on the lag, a
// delay of the same size; with one on the delay too, an accelerometer delay of the same size: to
// first order each is the same small time shift, which stands in for the flights' small misfits.
inline NegligibleSize SubMillisecondTimeShift() {
  return {1e-3,
          "a time shift under a millisecond is below half a sample of a 500 Hz log, and smaller than any "
          "motor's response or filter's delay that matters to a controller"};
}

//   and optionally  static double AccelerometerDelay(const Eigen::VectorXd& v);  // series shift
template <class Model>
constexpr auto HasAccelerometerDelay(int) -> decltype(Model::AccelerometerDelay(Eigen::VectorXd()), bool()) {
  return true;
}
template <class Model>
constexpr bool HasAccelerometerDelay(long) {
  return false;
}

template <class Model>
class ImuEffect final : public EffectDescriptor {
 public:
  explicit ImuEffect(Info info) : EffectDescriptor(std::move(info)) {}
  double SimulatedAccelerometerDelay(const Eigen::VectorXd& v) const override {
    if constexpr (HasAccelerometerDelay<Model>(0)) {
      return Model::AccelerometerDelay(v);
    } else {
      return 0.0;
    }
  }
  void CorrectImu(const double* p, ImuSample<double>* s) const override { Model::Correct(p, s); }
  void CorrectImu(const ImuJet* p, ImuSample<ImuJet>* s) const override { Model::Correct(p, s); }
  void CorrectImu(const MidImuJet* p, ImuSample<MidImuJet>* s) const override { Model::Correct(p, s); }
  void CorrectImu(const WideImuJet* p, ImuSample<WideImuJet>* s) const override { Model::Correct(p, s); }
  void ApplyToSensor(const double* p, ImuSample<double>* s) const override { Model::ApplyToSensor(p, s); }
};

//   struct MyRotorModel {
//     template <typename T>
//     static void Transform(const T* p, const RotorSignalInput& input, const VectorT& in, VectorT* out);
//     static double CommandDelay(const Eigen::VectorXd& v);        // what the simulator delays by
//     static double MotorTimeConstant(const Eigen::VectorXd& v);   // the lag the simulator adds
//     static double EquivalentValue(double delay_s);               // about this rotor-signal delay
//   };
//   and optionally  static SlowActuation SlowComponent(const Eigen::VectorXd& v);  // after the lag
template <class Model>
constexpr auto HasSlowComponent(int) -> decltype(Model::SlowComponent(Eigen::VectorXd()), bool()) {
  return true;
}
template <class Model>
constexpr bool HasSlowComponent(long) {
  return false;
}

template <class Model>
class RotorSignalEffect final : public EffectDescriptor {
 public:
  explicit RotorSignalEffect(Info info) : EffectDescriptor(std::move(info)) {}
  void TransformRotorSignal(const double* p, const RotorSignalInput& input, const Eigen::VectorXd& in,
                            Eigen::VectorXd* out) const override {
    Model::Transform(p, input, in, out);
  }
  void TransformRotorSignal(const RotorJet* p, const RotorSignalInput& input, const Eigen::Matrix<RotorJet, -1, 1>& in,
                            Eigen::Matrix<RotorJet, -1, 1>* out) const override {
    Model::Transform(p, input, in, out);
  }
  double SimulatedCommandDelay(const Eigen::VectorXd& v) const override { return Model::CommandDelay(v); }
  double SimulatedMotorTimeConstant(const Eigen::VectorXd& v) const override { return Model::MotorTimeConstant(v); }
  SlowActuation SimulatedSlowActuation(const Eigen::VectorXd& v) const override {
    if constexpr (HasSlowComponent<Model>(0)) {
      return Model::SlowComponent(v);
    } else {
      return {};
    }
  }
  Eigen::VectorXd FromEquivalentDelay(double delay_s) const override {
    return Clamp(Eigen::VectorXd::Constant(info().dimension, Model::EquivalentValue(delay_s)));
  }
};

//   struct MyWrenchModel {
//     template <typename T>
//     static void Add(const T* p, const RotorSample<T>& sample, RotorWrenchTerms<T>* terms);
//   };
template <class Model>
class RotorWrenchEffect final : public EffectDescriptor {
 public:
  explicit RotorWrenchEffect(Info info) : EffectDescriptor(std::move(info)) {}
  void AddRotorWrench(const double* p, const RotorSample<double>& s, RotorWrenchTerms<double>* t) const override {
    Model::Add(p, s, t);
  }
  void AddRotorWrench(const ImuJet* p, const RotorSample<ImuJet>& s, RotorWrenchTerms<ImuJet>* t) const override {
    Model::Add(p, s, t);
  }
  void AddRotorWrench(const MidImuJet* p, const RotorSample<MidImuJet>& s,
                      RotorWrenchTerms<MidImuJet>* t) const override {
    Model::Add(p, s, t);
  }
  void AddRotorWrench(const WideImuJet* p, const RotorSample<WideImuJet>& s,
                      RotorWrenchTerms<WideImuJet>* t) const override {
    Model::Add(p, s, t);
  }
};

}  // namespace rotorid::internal
