#pragma once

// The unmodelled effects of INTERFACE.md section 1, with one meaning everywhere (simulator,
// refinement, diagnosis, reports):
//   delay         Omega_true(t) = Omega_log(t - delay_s)
//   motor_lag     tau dOmega/dt = Omega_cmd - Omega   (Omega_cmd: the delayed log signal)
//   acc_bias      acc_log  = Exp(r) s_body + acc_bias + noise
//   gyro_bias     gyro_log = Exp(r) w_body + gyro_bias + noise
//   misalignment  r = misalignment_rad, a rotation vector: v_imu = Exp(r) v_body

#include <array>
#include <string>
#include <vector>

#include <Eigen/Core>

namespace rotorid {

enum class EffectKind { kDelay, kMotorLag, kAccBias, kGyroBias, kMisalignment };
inline constexpr int kNumEffectKinds = 5;
inline constexpr std::array<EffectKind, kNumEffectKinds> kAllEffectKinds = {
    EffectKind::kDelay, EffectKind::kMotorLag, EffectKind::kAccBias, EffectKind::kGyroBias, EffectKind::kMisalignment};

// "delay", "motor_lag", "acc_bias", "gyro_bias", "misalignment".
const char* EffectName(EffectKind kind);
// The parameter's name in reports: "delay_s", "motor_tau_s", "acc_bias", "gyro_bias", "misalignment_rad".
const char* EffectParameterName(EffectKind kind);
// Number of scalar parameters: 1 for delay and motor_lag, 3 for the others.
int EffectDimension(EffectKind kind);
// Parses an effect name (either form above); throws rotorid::Error listing the valid names.
EffectKind ParseEffectKind(const std::string& name);
// Parses "a,b,c" effect lists ("all" for every effect); throws rotorid::Error on unknown names.
std::vector<EffectKind> ParseEffectList(const std::string& list);

struct Effects {
  double delay_s = 0.0;
  double motor_tau_s = 0.0;
  Eigen::Vector3d acc_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d gyro_bias = Eigen::Vector3d::Zero();
  Eigen::Vector3d misalignment_rad = Eigen::Vector3d::Zero();

  // The parameters of one effect as a vector (size EffectDimension(kind)), and setting them.
  Eigen::VectorXd Get(EffectKind kind) const;
  void Set(EffectKind kind, const Eigen::Ref<const Eigen::VectorXd>& value);
  // Applies "name=value" or "name=x,y,z" (name in either form above). Throws rotorid::Error.
  void Assign(const std::string& assignment);
};

}  // namespace rotorid
