#pragma once

// The unmodelled effects of INTERFACE.md section 1 acting on a processed flight's signals before
// the regressor is built (MODEL.md section 4). The refinement, the reports and the diagnosis all
// build effect-laden rows through these functions, so they cannot disagree.
//
// Rotor signal, per rotor at the base rate, in the order of the physics:
//   u = Omega_log(t - delay)  (linear interpolation, as the definition of `delay`)
//   y = first-order lag of u with time constant tau
//   the row's rotor entry is sqrt(lowpass(y^2))  (the rotor columns are linear in Omega^2)
// With delay = tau = 0 this is exactly ProcessedFlight::rotor.
// IMU effects act on the filtered signals, which is exact: v_body = Exp(r)^T (v_imu - bias) is
// linear and the low-pass has unit gain at DC.

#include <algorithm>
#include <cmath>
#include <type_traits>

#include <Eigen/Core>

#include "rotorid/ident/observation.h"
#include "rotorid/model/effects.h"
#include "rotorid/model/rotation.h"

namespace rotorid {

// The value of a double or of a ceres::Jet (its .a), for decisions that carry no derivative.
template <typename T>
double ScalarPart(const T& x) {
  if constexpr (std::is_arithmetic_v<T>) {
    return static_cast<double>(x);
  } else {
    return x.a;
  }
}

// y^2 of the delayed and lagged raw rotor signal (n_base x n_rotors), before the low-pass.
// The lag uses the exact discretisation for a piecewise-linear input,
//   y[k+1] = a y[k] + (c - a) u[k] + (1 - c) u[k+1],  a = exp(-dt/tau), c = (tau/dt)(1 - a),
// with the tau -> 0 limit (a = 0, c = tau/dt) taken analytically so that the derivative at
// tau = 0 is the first-order one instead of vanishing like exp(-dt/tau).
template <typename T>
Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> DelayedLaggedRotorSquared(const ProcessedFlight& flight,
                                                                           const T& delay, const T& tau) {
  using std::exp;
  const Eigen::Index n = flight.rotor_raw.rows(), rotors = flight.rotor_raw.cols();
  const double dt = flight.dt_s;
  const T shift = delay / dt;
  const double shift_value = ScalarPart(shift);
  const double whole = std::floor(shift_value);
  const T frac = shift - T(whole);  // in [0, 1): u[k] = x(k - whole - frac)
  const Eigen::Index offset = static_cast<Eigen::Index>(whole);
  T a, c;
  if (ScalarPart(tau) > 1e-6 * dt) {
    a = exp(-T(dt) / tau);
    c = (tau / dt) * (T(1.0) - a);
  } else {
    a = T(0.0);
    c = tau / dt;
  }
  const T b0 = c - a, b1 = T(1.0) - c;
  Eigen::Matrix<T, Eigen::Dynamic, Eigen::Dynamic> out(n, rotors);
  for (Eigen::Index r = 0; r < rotors; ++r) {
    const auto x = flight.rotor_raw.col(r);
    auto sample = [&](Eigen::Index k) { return x[std::clamp<Eigen::Index>(k, 0, n - 1)]; };
    T y(0.0), u_prev(0.0);
    for (Eigen::Index k = 0; k < n; ++k) {
      // Between samples k - offset - 1 and k - offset.
      const double upper = sample(k - offset), lower = sample(k - offset - 1);
      const T u = T(upper) + frac * (lower - upper);
      y = k == 0 ? u : a * y + b0 * u_prev + b1 * u;  // start in steady state
      u_prev = u;
      out(k, r) = y * y;
    }
  }
  return out;
}

// The rotor entries of the rows at the row samples with delay and lag applied, and their
// derivatives with respect to delay and tau (row sample x rotor).
struct EffectiveRotor {
  Eigen::MatrixXd speed;
  Eigen::MatrixXd d_delay;
  Eigen::MatrixXd d_tau;
};
EffectiveRotor EffectiveRotorAtRows(const ProcessedFlight& flight, double delay_s, double tau_s);

// Body-frame signals from IMU-frame ones: v_body = Exp(r)^T (v_imu - bias) (w' has no bias).
template <typename T>
void CorrectImu(const Eigen::Matrix<T, 3, 3>& imu_from_body, const Eigen::Matrix<T, 3, 1>& acc_bias,
                const Eigen::Matrix<T, 3, 1>& gyro_bias, const Eigen::Vector3d& w_imu, const Eigen::Vector3d& w_dot_imu,
                const Eigen::Vector3d& s_imu, Eigen::Matrix<T, 3, 1>* w, Eigen::Matrix<T, 3, 1>* w_dot,
                Eigen::Matrix<T, 3, 1>* s) {
  const Eigen::Matrix<T, 3, 3> body_from_imu = imu_from_body.transpose();
  *w = body_from_imu * (w_imu.cast<T>() - gyro_bias);
  *w_dot = body_from_imu * w_dot_imu.cast<T>();
  *s = body_from_imu * (s_imu.cast<T>() - acc_bias);
}

// The IDIM rows of a flight (as BuildIdimMatrix) with the effects applied.
Eigen::MatrixXd BuildIdimMatrixWithEffects(const ProcessedFlight& flight, const Effects& effects);

}  // namespace rotorid
