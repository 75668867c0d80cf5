#include "rotorid/refine/effect_model.h"

#include <ceres/jet.h>

#include "rotorid/model/rigid_body.h"
#include "rotorid/signal/butterworth.h"

namespace rotorid {

EffectiveRotor EffectiveRotorAtRows(const ProcessedFlight& flight, double delay_s, double tau_s) {
  using Jet2 = ceres::Jet<double, 2>;
  const Eigen::Matrix<Jet2, Eigen::Dynamic, Eigen::Dynamic> squared =
      DelayedLaggedRotorSquared<Jet2>(flight, Jet2(delay_s, 0), Jet2(tau_s, 1));
  const Eigen::Index n = squared.rows(), rotors = squared.cols();
  // The low-pass is linear: filter the value and each derivative separately.
  Eigen::MatrixXd value(n, rotors), d_delay(n, rotors), d_tau(n, rotors);
  for (Eigen::Index k = 0; k < n; ++k)
    for (Eigen::Index r = 0; r < rotors; ++r) {
      value(k, r) = squared(k, r).a;
      d_delay(k, r) = squared(k, r).v[0];
      d_tau(k, r) = squared(k, r).v[1];
    }
  const Eigen::MatrixXd speed = FilteredRotorSpeed(flight.filter, value);
  const Eigen::MatrixXd filtered_d_delay = FiltFiltColumns(flight.filter, d_delay);
  const Eigen::MatrixXd filtered_d_tau = FiltFiltColumns(flight.filter, d_tau);
  EffectiveRotor out;
  const int rows = flight.num_rows_samples();
  out.speed.resize(rows, rotors);
  out.d_delay.resize(rows, rotors);
  out.d_tau.resize(rows, rotors);
  for (int r = 0; r < rows; ++r) {
    const int i = flight.row_samples[r];
    for (Eigen::Index k = 0; k < rotors; ++k) {
      const double omega = speed(i, k);
      // d sqrt(z) = dz / (2 sqrt(z)).
      const double inv = omega > 0.0 ? 0.5 / omega : 0.0;
      out.speed(r, k) = omega;
      out.d_delay(r, k) = filtered_d_delay(i, k) * inv;
      out.d_tau(r, k) = filtered_d_tau(i, k) * inv;
    }
  }
  return out;
}

Eigen::MatrixXd BuildIdimMatrixWithEffects(const ProcessedFlight& flight, const Effects& effects) {
  const Eigen::MatrixXd rotor =
      effects.delay_s == 0.0 && effects.motor_tau_s == 0.0
          ? Eigen::MatrixXd(flight.rotor)
          : FilteredRotorSpeed(flight.filter,
                               DelayedLaggedRotorSquared<double>(flight, effects.delay_s, effects.motor_tau_s));
  const Eigen::Matrix3d imu_from_body = ExpSO3<double>(effects.misalignment_rad);
  const int rows = flight.num_rows_samples();
  Eigen::MatrixXd w(6 * rows, kNumIdimColumns);
  for (int r = 0; r < rows; ++r) {
    const int i = flight.row_samples[r];
    Eigen::Vector3d omega, omega_dot, s;
    CorrectImu<double>(imu_from_body, effects.acc_bias, effects.gyro_bias, flight.angular_velocity.row(i).transpose(),
                       flight.angular_acceleration.row(i).transpose(), flight.specific_force.row(i).transpose(),
                       &omega, &omega_dot, &s);
    w.middleRows<6>(6 * r) = IdimRows<double>(omega, omega_dot, s, rotor.row(i).transpose(), flight.vehicle);
  }
  return w;
}

}  // namespace rotorid
