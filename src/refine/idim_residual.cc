#include "refine/idim_residual.h"

#include "rotorid/ident/tls.h"
#include "rotorid/model/rigid_body.h"

namespace rotorid::internal {

bool IdimResidualBlock::Evaluate(double const* const* parameters, double* residuals, double** jacobians) const {
  const int p = context_->num_parameters;
  Eigen::VectorXd chi_t(p + 1);
  chi_t << Eigen::Map<const Eigen::VectorXd>(parameters[0], p).cwiseProduct(context_->chi_scale), 1.0;
  const Eigen::VectorXd n_chi = context_->metric * chi_t;
  const double d_sq = chi_t.dot(n_chi) / context_->total_rows;
  if (!(d_sq > 0.0)) return false;
  const double d = std::sqrt(d_sq);
  const int c0 = IdimSystem::ConfigColumn(config_);
  Eigen::Matrix<double, kNumIdimColumns, 1> flight_chi;
  flight_chi << chi_t[0], chi_t[1], chi_t.segment(c0, kNumBodyParameters), 1.0;

  const double delay = parameters[1][0], tau = parameters[2][0];
  const std::shared_ptr<const RotorSignalCache::State> cached = rotor_->Get(delay, tau);
  const EffectiveRotor& rotor = cached->rotor;
  const EffectJet jet_delay(delay, 0), jet_tau(tau, 1);
  Eigen::Matrix<EffectJet, 3, 1> acc_bias, gyro_bias;
  for (int a = 0; a < 3; ++a) {
    acc_bias[a] = EffectJet(parameters[3][a], 2 + a);
    gyro_bias[a] = EffectJet(parameters[4][a], 5 + a);
  }
  const EffectJet qx(parameters[5][0], 8), qy(parameters[5][1], 9), qz(parameters[5][2], 10),
      qw(parameters[5][3], 11);
  const EffectJet two_over_norm = EffectJet(2.0) / (qx * qx + qy * qy + qz * qz + qw * qw);
  Eigen::Matrix<EffectJet, 3, 3> imu_from_body;
  imu_from_body << EffectJet(1.0) - two_over_norm * (qy * qy + qz * qz), two_over_norm * (qx * qy - qz * qw),
      two_over_norm * (qx * qz + qy * qw),  //
      two_over_norm * (qx * qy + qz * qw), EffectJet(1.0) - two_over_norm * (qx * qx + qz * qz),
      two_over_norm * (qy * qz - qx * qw),  //
      two_over_norm * (qx * qz - qy * qw), two_over_norm * (qy * qz + qx * qw),
      EffectJet(1.0) - two_over_norm * (qx * qx + qy * qy);

  const int rotors = flight_->vehicle.num_rotors();
  Eigen::Matrix<EffectJet, Eigen::Dynamic, 1> omega(rotors);
  for (int s = 0; s < count_; ++s) {
    const int row_sample = first_ + s;
    const int i = flight_->row_samples[row_sample];
    for (int k = 0; k < rotors; ++k) {
      omega[k] = EffectJet(rotor.speed(row_sample, k));
      omega[k] += rotor.d_delay(row_sample, k) * (jet_delay - delay) + rotor.d_tau(row_sample, k) * (jet_tau - tau);
    }
    Eigen::Matrix<EffectJet, 3, 1> w, w_dot, sf;
    CorrectImu<EffectJet>(imu_from_body, acc_bias, gyro_bias, flight_->angular_velocity.row(i).transpose(),
                          flight_->angular_acceleration.row(i).transpose(),
                          flight_->specific_force.row(i).transpose(), &w, &w_dot, &sf);
    const Eigen::Matrix<EffectJet, 6, kNumIdimColumns> rows = IdimRows<EffectJet>(w, w_dot, sf, omega, flight_->vehicle);
    for (int c = 0; c < 6; ++c) {
      const int out = 6 * s + c;
      const double scale = sqrt_weight_[out] / d;
      EffectJet e(0.0);
      for (int k = 0; k < kNumIdimColumns; ++k) e += rows(c, k) * flight_chi[k];
      residuals[out] = scale * e.a;
      if (!jacobians) continue;
      if (jacobians[0]) {
        double* j = jacobians[0] + static_cast<size_t>(out) * p;
        for (int k = 0; k < p; ++k) j[k] = -residuals[out] * n_chi[k] / (context_->total_rows * d_sq);
        j[0] += scale * rows(c, 0).a;
        j[1] += scale * rows(c, 1).a;
        for (int k = 0; k < kNumBodyParameters; ++k) j[c0 + k] += scale * rows(c, 2 + k).a;
        for (int k = 0; k < p; ++k) j[k] *= context_->chi_scale[k];
      }
      static constexpr int kOffsets[5] = {0, 1, 2, 5, 8};
      static constexpr int kSizes[5] = {1, 1, 3, 3, 4};
      for (int b = 0; b < 5; ++b) {
        if (!jacobians[b + 1]) continue;
        for (int k = 0; k < kSizes[b]; ++k) jacobians[b + 1][out * kSizes[b] + k] = scale * e.v[kOffsets[b] + k];
      }
    }
  }
  return true;
}


}  // namespace rotorid::internal
