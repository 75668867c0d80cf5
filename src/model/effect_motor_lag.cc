// `motor_lag` (INTERFACE.md section 1): a first-order motor response to the (delayed) log signal,
//   tau dOmega/dt = Omega_cmd - Omega,  tau = motor_tau_s >= 0.

#include <cmath>

#include "model/effect_adapter.h"

namespace rotorid::internal {
namespace {

struct MotorLagModel {
  // The exact discretisation for a piecewise-linear input,
  //   y[k+1] = a y[k] + (c - a) u[k] + (1 - c) u[k+1],  a = exp(-dt/tau), c = (tau/dt)(1 - a),
  // with the tau -> 0 limit (a = 0, c = tau/dt) taken analytically so that the derivative at
  // tau = 0 is the first-order one instead of vanishing like exp(-dt/tau). Starts in steady state.
  template <typename T>
  static void Transform(const T* p, const RotorSignalInput& input, const Eigen::Matrix<T, -1, 1>& u,
                        Eigen::Matrix<T, -1, 1>* out) {
    using std::exp;
    const double dt = input.dt;
    const T& tau = p[0];
    T a, c;
    if (ScalarPart(tau) > 1e-6 * dt) {
      a = exp(-T(dt) / tau);
      c = (tau / dt) * (T(1.0) - a);
    } else {
      a = T(0.0);
      c = tau / dt;
    }
    const T b0 = c - a, b1 = T(1.0) - c;
    const Eigen::Index n = u.size();
    out->resize(n);
    T y(0.0);
    for (Eigen::Index k = 0; k < n; ++k) {
      y = k == 0 ? u[k] : a * y + b0 * u[k - 1] + b1 * u[k];
      (*out)[k] = y;
    }
  }
  static double CommandDelay(const Eigen::VectorXd&) { return 0.0; }
  static double MotorTimeConstant(const Eigen::VectorXd& v) { return v[0]; }
  // A first-order lag delays the low frequencies by about its time constant.
  static double EquivalentValue(double delay_s) { return delay_s; }
};

}  // namespace

const EffectDescriptor& MotorLagEffect() {
  static const RotorSignalEffect<MotorLagModel> effect([] {
    EffectDescriptor::Info i;
    i.name = "motor_lag";
    i.parameter_name = "motor_tau_s";
    i.unit = "s";
    // tau dOmega/dt = Omega_cmd - Omega, tau = motor_tau_s >= 0
    i.stage = EffectStage::kRotorSignal;
    i.chain_position = 1;
    i.dimension = 1;
    i.lower_bound = 0.0;
    i.upper_bound = 0.3;
    i.screening_grid = {0.01, 0.02, 0.04, 0.08, 0.15, 0.3};
    i.checked_at_half_cutoff = true;
    i.draw = {DrawShape::kUniform, 0.020, 0.060};
    i.simulator_limit = {true, 0.0, 0.08};
    // Motor and propeller time constants: 10-30 ms small brushless, 20-60 ms brushed (the Crazyflie's
    // measured PWM -> RPM 59 ms), ~100 ms the largest propellers. A longer lag smooths away something else
    // (MODEL.md 9: it ran to 300 ms on PWM-driven Crazyflies).
    i.plausible = {true, 0.0, 0.15, PlausibleScale::kNone, "motors and propellers respond within ~100 ms"};
    i.negligible = SubMillisecondTimeShift();
    i.settle_tolerance = 1e-5;
    i.display_scale = 1e3;
    i.display_unit = "ms";
    return i;
  }());
  return effect;
}

}  // namespace rotorid::internal
