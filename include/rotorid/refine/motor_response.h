#pragma once

// The motors' response measured directly, where a log holds both the command and the measured rotor
// speed (a Crazyflie with the RPM deck, a PX4 log with ESC telemetry): the delay and first-order
// time constant from command to speed, in the same model as the `delay` and `motor_lag` effects
// (effect_model.h), plus the static map from the lagged command to speed. It is the reference the
// refinement's estimates from command-driven identification are compared with.

#include <Eigen/Core>
#include <string>

namespace rotorid {

struct MotorResponseOptions {
  double min_delay_s = -0.02, max_delay_s = 0.08;
  double max_tau_s = 0.2;
  // Left out at each end (s), beyond the largest delay searched.
  double edge_s = 0.2;

  std::string Validate() const;
};

struct MotorResponse {
  double delay_s = 0.0;
  double motor_tau_s = 0.0;
  // speed = c0 + c1 y + c2 y^2, y the delayed and lagged command (pooled over the rotors).
  Eigen::Vector3d static_map = Eigen::Vector3d::Zero();
  double residual_rms = 0.0;   // of the speed, in its unit
  double explained_pct = 0.0;  // 100 (1 - residual variance / speed variance)
  int samples = 0;
};

// `command` and `speed` (rows: samples at `t_s`, columns: rotors, same order). Throws rotorid::Error
// on mismatched sizes, non-finite values, a time base that does not increase, or too short a log.
MotorResponse EstimateMotorResponse(const Eigen::VectorXd& t_s, const Eigen::MatrixXd& command,
                                    const Eigen::MatrixXd& speed, const MotorResponseOptions& options = {});

}  // namespace rotorid
