// `slow_actuation`: a part of each rotor's Omega^2 that acts only through a slow first-order low-pass
// (the IDSIA benchmark's "low-frequency component of the actuation", MODEL.md 11),
//   Omega_acting^2 = (1 - a) Omega^2 + a LP(Omega^2),  LP: S' = 2 pi f_c (Omega^2 - S),
// after the delay and the motor lag, on thrust and drag torque alike (it is a rotor-signal stage).
// Parameters (a, f_c): the fraction a in [0, 1] and the low-pass's cut-off f_c in Hz, in [0, 1] (a time
// constant of at least 0.16 s: a faster one is the motor lag's). The cut-off, not the time constant, is
// the parameter so that the all-zero value (a = 0, absent) is no saddle: at f_c = 0 the low-pass holds
// its first value and the criterion's slope in a is not zero, so a refinement started there moves.
// Measured on the IMRC jana01 / jana04 Crazyflie flights (docs/prediction.md).

#include <cmath>

#include "model/effect_adapter.h"
#include "rotorid/core/units.h"

namespace rotorid::internal {
namespace {

struct SlowActuationModel {
  // The low-pass of the piecewise-linear Omega^2 discretised exactly (as motor_lag's lag):
  //   y[k+1] = d y[k] + (c - d) u[k] + (1 - c) u[k+1],  d = exp(-x), c = (1 - d) / x,  x = 2 pi f_c dt,
  // with c's series near x = 0 (where it tends to 1 and the low-pass holds). Starts in steady state.
  template <typename T>
  static void Transform(const T* p, const RotorSignalInput& input, const Eigen::Matrix<T, -1, 1>& speed,
                        Eigen::Matrix<T, -1, 1>* out) {
    using std::exp;
    using std::sqrt;
    const T& fraction = p[0];
    const T x = T(2.0 * kPi * input.dt) * p[1];
    const T d = exp(-x);
    const T c = ScalarPart(x) > 1e-4 ? (T(1.0) - d) / x : T(1.0) - x / T(2.0) + x * x / T(6.0);
    const T b0 = c - d, b1 = T(1.0) - c;
    const Eigen::Index n = speed.size();
    out->resize(n);
    T slow(0.0), previous(0.0);
    for (Eigen::Index k = 0; k < n; ++k) {
      const T square = speed[k] * speed[k];
      slow = k == 0 ? square : d * slow + b0 * previous + b1 * square;
      previous = square;
      const T acting = (T(1.0) - fraction) * square + fraction * slow;
      // A rotor at rest: zero, with a zero derivative instead of sqrt's infinite one.
      (*out)[k] = ScalarPart(acting) > 0.0 ? sqrt(acting) : T(0.0) * acting;
    }
  }
  static double CommandDelay(const Eigen::VectorXd&) { return 0.0; }
  static double MotorTimeConstant(const Eigen::VectorXd&) { return 0.0; }
  static SlowActuation SlowComponent(const Eigen::VectorXd& v) { return {v[0], 2.0 * kPi * v[1]}; }
  // No delay is this component: the diagnosis starts it absent.
  static double EquivalentValue(double) { return 0.0; }
};

}  // namespace

const EffectDescriptor& SlowActuationEffect() {
  static const RotorSignalEffect<SlowActuationModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "slow_actuation";
    i.parameter_name = "slow_actuation";
    i.labels = {"slow_actuation_fraction", "slow_actuation_cutoff_hz"};
    i.unit = "1, Hz";
    // Omega_acting^2 = (1 - a) Omega^2 + a LP_fc(Omega^2), after the delay and the lag
    i.stage = EffectStage::kRotorSignal;
    i.chain_position = 2;
    i.dimension = 2;
    i.lower_bound = 0.0;
    i.upper_bound = 1.0;
    i.draw = {DrawShape::kUniform, 0.2, 0.5};
    i.simulator_limit = {true, 0.0, 0.6};
    i.plausible = {true, 0.0, 1.0, PlausibleScale::kNone, "a fraction of the actuation, a cut-off below 1 Hz"};
    i.settle_tolerance = 1e-4;
    // Named only: on real flights it was measured on one vehicle (docs/prediction.md).
    i.default_candidate = false;
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal
